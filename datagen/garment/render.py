"""Render a garment on its body (matplotlib, CPU, no display): front and side, Lambert shading,
painter's order over body and garment together; the garment's inside shows darker through its
openings. Drawn by the shared renderer of :mod:`datagen.body.render`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from datagen.body.render import MeshLayer, draw_meshes, pyplot, view_limits

_PANEL_COLOURS = [(0.25, 0.45, 0.75), (0.2, 0.38, 0.65), (0.85, 0.45, 0.3), (0.8, 0.4, 0.28), (0.3, 0.6, 0.45),
                  (0.6, 0.5, 0.75)]
BODY_COLOUR = (0.78, 0.74, 0.70)


def render_garment(garment, body_vertices: np.ndarray, body_faces: np.ndarray, path: str | Path,
                   views=(("front", 0.0), ("side", 90.0)), size: float = 3.2, title: str | None = None) -> Path:
    """Write a PNG of ``garment`` on the body (rest pose) from the given views."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(views), figsize=(size * len(views) * 0.62, size * 1.05), squeeze=False)
    colours = np.array(_PANEL_COLOURS)[garment.face_region % len(_PANEL_COLOURS)]
    layers = [MeshLayer(body_vertices, body_faces, BODY_COLOUR),
              MeshLayer(garment.vertices, garment.faces, colours, two_sided=True)]
    for k, (_name, deg) in enumerate(views):
        limits = view_limits([body_vertices, garment.vertices], deg, pad=1.03)
        draw_meshes(axes[0, k], layers, deg, ambient=0.3, absolute=True, linewidth=0.25, limits=limits)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
