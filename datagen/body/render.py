"""A small offscreen renderer for meshes (matplotlib, CPU, no display): orthographic views with
Lambert shading, drawn back to front (painter's algorithm). Good for README figures, quick checks
and the previews of ``drape preview``.

:func:`shade_polygons` turns :class:`MeshLayer` s (one-sided meshes such as a body, two-sided ones
such as a garment whose inside shows, darker, through its openings) into sorted 2-D polygons and
colours for one view; :func:`draw_meshes` puts them on a matplotlib axes. :func:`render_views`
(bodies side by side) and :func:`datagen.garment.render.render_garment` are built on them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from datagen.errors import require

VIEWS = {"front": 0.0, "three-quarter": 45.0, "side": 90.0, "back": 180.0}
"""Named views: the azimuth (degrees) of the camera around the vertical (Y) axis; 0 looks at the
body's front (from +Z), 90 at its right side (from -X), 45 from between the two."""

LIGHT = np.array([0.3, 0.5, 1.0]) / np.linalg.norm([0.3, 0.5, 1.0])
"""Direction to the light, in view coordinates (x right, y up, z towards the camera)."""


@dataclass
class MeshLayer:
    """One mesh to draw.

    Attributes:
        vertices: [V, 3] (Y up).
        faces: [F, 3] triangles, counter-clockwise seen from outside.
        colors: one RGB [3] or an RGB per face [F, 3], before shading.
        two_sided: draw faces seen from behind too (an open garment's inside), times ``inside``;
            else they are culled.
        inside: brightness factor of faces seen from behind.
        depth_bias: added to the sort depth of this layer's faces that face the camera [m]: a
            garment lying on the body is drawn over it even where its (larger, tilted) triangles'
            centres are farther from the camera than the body's (painter's order by centres).
    """

    vertices: np.ndarray
    faces: np.ndarray
    colors: np.ndarray | tuple[float, float, float]
    two_sided: bool = False
    inside: float = 0.45
    depth_bias: float = 0.0


def view_rotation(azimuth: float) -> np.ndarray:
    """The 3x3 rotation taking world points to view coordinates for a camera at ``azimuth`` degrees."""
    a = np.radians(azimuth)
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def shade_polygons(layers: list[MeshLayer], azimuth: float, *, ambient: float = 0.25, absolute: bool = False,
                   light: np.ndarray = LIGHT) -> tuple[np.ndarray, np.ndarray]:
    """2-D triangles [N, 3, 2] (view x, y) and their shaded colours [N, 3], back to front.

    Shading is ``colour * (ambient + (1 - ambient) * s)`` with ``s = max(n . light, 0)``, or
    ``|n . light|`` if ``absolute``.
    """
    rot = view_rotation(azimuth)
    polys, depth, rgb = [], [], []
    for layer in layers:
        p = np.asarray(layer.vertices, dtype=np.float64) @ rot.T
        tri = p[np.asarray(layer.faces)]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
        front = n[:, 2] > 0
        show = front | layer.two_sided
        d = n[show] @ light
        shade = np.clip(np.abs(d) if absolute else d, 0, 1)
        base = np.asarray(layer.colors, dtype=np.float64)
        base = np.broadcast_to(base, (len(tri), 3))[show]
        c = base * (ambient + (1 - ambient) * shade[:, None])
        if layer.two_sided:
            c = np.where(front[show][:, None], c, c * layer.inside)
        polys.append(tri[show][:, :, :2])
        depth.append(tri[show, :, 2].mean(1) + layer.depth_bias * front[show])
        rgb.append(np.clip(c, 0, 1))
    polys, depth, rgb = np.concatenate(polys), np.concatenate(depth), np.concatenate(rgb)
    order = np.argsort(depth, kind="stable")
    return polys[order], rgb[order]


def view_limits(points: list[np.ndarray], azimuth: float, pad: float = 1.05) -> tuple[tuple, tuple]:
    """Square (xlim, ylim) around every point of ``points`` (arrays [..., 3]) seen from ``azimuth``."""
    rot = view_rotation(azimuth)
    p = np.concatenate([np.asarray(x, dtype=np.float64).reshape(-1, 3) for x in points]) @ rot.T
    lo, hi = p.min(0), p.max(0)
    c, r = (lo + hi) / 2, (hi - lo)[:2].max() / 2 * pad
    return (c[0] - r, c[0] + r), (c[1] - r, c[1] + r)


def draw_meshes(ax, layers: list[MeshLayer], azimuth: float, *, ambient: float = 0.25, absolute: bool = False,
                linewidth: float = 0.3, limits: tuple[tuple, tuple] | None = None, pad: float = 1.05):
    """Draw ``layers`` on the matplotlib axes ``ax`` from ``azimuth``; returns the ``PolyCollection``.

    ``limits``: (xlim, ylim); default :func:`view_limits` of every layer's vertices.
    """
    from matplotlib.collections import PolyCollection

    polys, rgb = shade_polygons(layers, azimuth, ambient=ambient, absolute=absolute)
    collection = PolyCollection(polys, facecolors=rgb, edgecolors=rgb, linewidths=linewidth)
    ax.add_collection(collection)
    xlim, ylim = limits if limits is not None else view_limits([la.vertices for la in layers], azimuth, pad)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal")
    ax.axis("off")
    return collection


def pyplot():
    """matplotlib's pyplot on the non-interactive Agg backend (no display needed)."""
    require("matplotlib", "rendering pictures", extra="render")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def render_views(meshes: list[tuple[np.ndarray, np.ndarray]], path: str | Path, views=("front", "side"),
                 titles: list[str] | None = None, color=(0.80, 0.66, 0.56), size: float = 3.0) -> Path:
    """Render each (vertices [V, 3], faces [F, 3]) mesh (Y up) from each named view, side by side."""
    plt = pyplot()
    cols = len(meshes) * len(views)
    fig, axes = plt.subplots(1, cols, figsize=(size * cols * 0.62, size * 1.05), squeeze=False)
    for m, (verts, faces) in enumerate(meshes):
        for v, view in enumerate(views):
            ax = axes[0, m * len(views) + v]
            draw_meshes(ax, [MeshLayer(verts, faces, color)], VIEWS[view], ambient=0.25, linewidth=0.3, pad=1.05)
            if titles:
                ax.set_title(f"{titles[m]} ({view})", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
