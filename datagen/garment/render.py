"""Render a garment on its body (matplotlib, CPU, no display): front and side, Lambert shading,
painter's order over body and garment together; the garment's inside shows darker through its
openings."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from datagen.errors import require

_PANEL_COLOURS = [(0.25, 0.45, 0.75), (0.2, 0.38, 0.65), (0.85, 0.45, 0.3), (0.8, 0.4, 0.28), (0.3, 0.6, 0.45),
                  (0.6, 0.5, 0.75)]


def render_garment(garment, body_vertices: np.ndarray, body_faces: np.ndarray, path: str | Path,
                   views=(("front", 0.0), ("side", 90.0)), size: float = 3.2, title: str | None = None) -> Path:
    """Write a PNG of ``garment`` on the body (rest pose) from the given views."""
    require("matplotlib", "rendering pictures", extra="dev")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    light = np.array([0.3, 0.5, 1.0])
    light /= np.linalg.norm(light)
    fig, axes = plt.subplots(1, len(views), figsize=(size * len(views) * 0.62, size * 1.05), squeeze=False)
    colours = np.array(_PANEL_COLOURS)[garment.face_region % len(_PANEL_COLOURS)]
    body_colour = np.array([0.78, 0.74, 0.70])
    for k, (name, deg) in enumerate(views):
        ax = axes[0, k]
        a = np.radians(deg)
        rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        polys, depth, rgb = [], [], []
        for verts, faces, cols, two_sided in ((body_vertices, body_faces, None, False),
                                               (garment.vertices, garment.faces, colours, True)):
            p = verts @ rot.T
            tri = p[faces]
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
            front = n[:, 2] > 0
            show = front | two_sided
            shade = np.clip(np.abs(n @ light), 0, 1)
            base = np.repeat(body_colour[None], len(faces), 0) if cols is None else cols
            c = base * (0.3 + 0.7 * shade[:, None])
            c = np.where(front[:, None], c, c * 0.45)  # the inside of the garment
            polys.append(tri[show][:, :, :2])
            depth.append(tri[show, :, 2].mean(1))
            rgb.append(np.clip(c[show], 0, 1))
        polys, depth, rgb = np.concatenate(polys), np.concatenate(depth), np.concatenate(rgb)
        order = np.argsort(depth)
        ax.add_collection(PolyCollection(polys[order], facecolors=rgb[order], edgecolors=rgb[order], linewidths=0.25))
        allp = np.concatenate([body_vertices @ rot.T, garment.vertices @ rot.T])
        lo, hi = allp.min(0), allp.max(0)
        c0, r = (lo + hi) / 2, (hi - lo)[:2].max() / 2 * 1.03
        ax.set_xlim(c0[0] - r, c0[0] + r)
        ax.set_ylim(c0[1] - r, c0[1] + r)
        ax.set_aspect("equal")
        ax.axis("off")
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
