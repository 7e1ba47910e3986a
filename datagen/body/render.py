"""A small offscreen renderer for body meshes (matplotlib, CPU, no display): orthographic views
with Lambert shading, drawn back to front. Good for README figures and quick checks."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from datagen.errors import require

VIEWS = {"front": 0.0, "side": 90.0, "back": 180.0}


def render_views(meshes: list[tuple[np.ndarray, np.ndarray]], path: str | Path, views=("front", "side"),
                 titles: list[str] | None = None, color=(0.80, 0.66, 0.56), size: float = 3.0) -> Path:
    """Render each (vertices [V, 3], faces [F, 3]) mesh (Y up) from each named view, side by side."""
    require("matplotlib", "rendering pictures", extra="dev")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    cols = len(meshes) * len(views)
    fig, axes = plt.subplots(1, cols, figsize=(size * cols * 0.62, size * 1.05), squeeze=False)
    light = np.array([0.3, 0.5, 1.0])
    light /= np.linalg.norm(light)
    for m, (verts, faces) in enumerate(meshes):
        for v, view in enumerate(views):
            ax = axes[0, m * len(views) + v]
            a = np.radians(VIEWS[view])
            rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
            p = verts @ rot.T
            tri = p[faces]
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
            visible = n[:, 2] > 0
            order = np.argsort(tri[visible, :, 2].mean(axis=1))
            shade = np.clip(n[visible] @ light, 0, 1)[order]
            rgb = np.clip(np.outer(0.25 + 0.75 * shade, color), 0, 1)
            ax.add_collection(PolyCollection(tri[visible][order][:, :, :2], facecolors=rgb, edgecolors=rgb, linewidths=0.3))
            lo, hi = p.min(0), p.max(0)
            c, r = (lo + hi) / 2, (hi - lo)[:2].max() / 2 * 1.05
            ax.set_xlim(c[0] - r, c[0] + r)
            ax.set_ylim(c[1] - r, c[1] + r)
            ax.set_aspect("equal")
            ax.axis("off")
            if titles:
                ax.set_title(f"{titles[m]} ({view})", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
