"""Drawing a pattern: every panel flat, side by side, its stitches numbered on both sides.

:func:`draw_svg` writes plain SVG (no dependency); a path ending ``.png`` is drawn with matplotlib
instead (``pip install matplotlib``). Each stitch gets a number and a colour; its number sits at the
middle of both of its sides, with a tick at each side's first point (where a reversed stitch meets
the other side's last point). Free edges are grey, the grain is an arrow in each panel.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from datagen.errors import InputError, require
from datagen.garment.pattern.model import Pattern

__all__ = ["draw_svg", "layout"]

_GAP = 0.08
"""Space between panels in the drawing [m]."""

_COLOURS = ["#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#42d4f4", "#f032e6", "#9a6324",
            "#469990", "#800000", "#808000", "#000075", "#bfef45", "#dcbeff", "#fabed4", "#aaffc3"]


def layout(pattern: Pattern, row_width: float = 2.4) -> dict[str, np.ndarray]:
    """Offset [2] of every panel so that they sit in rows left to right, ``row_width`` [m] wide."""
    out, x, y, row_h = {}, 0.0, 0.0, 0.0
    for p in pattern.panels:
        pts = p.outline(0.01)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        w, h = hi - lo
        if x > 0 and x + w > row_width:
            x, y, row_h = 0.0, y - row_h - _GAP, 0.0
        out[p.name] = np.array([x, y - h]) - lo
        x += w + _GAP
        row_h = max(row_h, h)
    return out


def _seams(pattern: Pattern):
    """(stitch number, colour, panel, points of the side [n, 2], sewn in reverse) for both sides of every stitch."""
    for k, st in enumerate(pattern.stitches):
        colour = _COLOURS[k % len(_COLOURS)]
        for side, rev in ((st.a, False), (st.b, st.reversed)):
            p = pattern.panel(side.panel)
            pts = np.concatenate([p.edges[i].sample(p, max(2, int(p.edge_length(i) / 0.01) + 1)) for i in side.edges])
            yield k, colour, p.name, pts, rev


def draw_svg(pattern: Pattern, path, scale: float = 250.0) -> Path:
    """Draw ``pattern``'s panels and numbered stitches to ``path`` (.svg, or .png via matplotlib).

    ``scale``: pixels per metre of the SVG."""
    path = Path(path)
    if path.suffix.lower() == ".png":
        return _draw_png(pattern, path)
    if path.suffix.lower() != ".svg":
        raise InputError(f"{path}: a pattern is drawn as .svg or .png")
    off = layout(pattern)
    everything = np.concatenate([p.outline(0.02) + off[p.name] for p in pattern.panels])
    lo, hi = everything.min(axis=0) - 0.05, everything.max(axis=0) + 0.05
    width, height = (hi - lo) * scale

    def xy(pts):
        pts = np.atleast_2d(pts)
        return [((x - lo[0]) * scale, (hi[1] - y) * scale) for x, y in pts]

    def poly(pts):
        return " ".join(f"{x:.1f},{y:.1f}" for x, y in xy(pts))

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0f}" height="{height:.0f}" '
           f'viewBox="0 0 {width:.1f} {height:.1f}" font-family="sans-serif">',
           f'<title>{pattern.name}: {len(pattern.panels)} panels, {len(pattern.stitches)} stitches</title>',
           '<rect width="100%" height="100%" fill="white"/>']
    for p in pattern.panels:
        o = off[p.name]
        out.append(f'<polygon points="{poly(p.outline(0.005) + o)}" fill="#f4f1ea" stroke="#999" stroke-width="1"/>')
        c = p.outline(0.01).mean(axis=0) + o
        g = np.asarray(p.grain) * 0.08
        (x0, y0), (x1, y1) = xy(np.stack([c - g, c + g]))
        out.append(f'<line x1="{x0:.1f}" y1="{y0:.1f}" x2="{x1:.1f}" y2="{y1:.1f}" stroke="#666" stroke-width="1" '
                   f'marker-end="url(#arrow)"/>')
        (tx, ty), = xy(c)
        out.append(f'<text x="{tx:.1f}" y="{ty + 14:.1f}" font-size="11" text-anchor="middle" fill="#333">{p.name}</text>')
    out.insert(2, '<defs><marker id="arrow" markerWidth="6" markerHeight="6" refX="5" refY="3" orient="auto">'
                  '<path d="M0,0 L6,3 L0,6 z" fill="#666"/></marker></defs>')
    for k, colour, name, pts, rev in _seams(pattern):
        pts = pts + off[name]
        out.append(f'<polyline points="{poly(pts)}" fill="none" stroke="{colour}" stroke-width="3"/>')
        first = pts[-1] if rev else pts[0]
        (fx, fy), = xy(first)
        out.append(f'<circle cx="{fx:.1f}" cy="{fy:.1f}" r="3" fill="{colour}"/>')
        (mx, my), = xy(pts[len(pts) // 2])
        out.append(f'<text x="{mx:.1f}" y="{my - 4:.1f}" font-size="12" font-weight="bold" text-anchor="middle" '
                   f'fill="{colour}">{k}</text>')
    out.append("</svg>")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(out))
    return path


def draw_pattern_axes(ax, pattern: Pattern) -> None:
    """Draw ``pattern`` on a matplotlib axes (equal aspect, metres)."""
    off = layout(pattern)
    for p in pattern.panels:
        o = off[p.name]
        pts = p.outline(0.005) + o
        ax.fill(pts[:, 0], pts[:, 1], facecolor="#f4f1ea", edgecolor="#999", linewidth=0.6)
        c = p.outline(0.01).mean(axis=0) + o
        g = np.asarray(p.grain) * 0.08
        ax.annotate("", xy=c + g, xytext=c - g, arrowprops={"arrowstyle": "->", "color": "#666", "lw": 0.6})
        ax.text(c[0], c[1] - 0.05, p.name, fontsize=5, ha="center", color="#333")
    for k, colour, name, pts, rev in _seams(pattern):
        pts = pts + off[name]
        ax.plot(pts[:, 0], pts[:, 1], color=colour, linewidth=1.4)
        first = pts[-1] if rev else pts[0]
        ax.plot(*first, "o", color=colour, markersize=2)
        m = pts[len(pts) // 2]
        ax.text(m[0], m[1], str(k), fontsize=6, fontweight="bold", color=colour, ha="center", va="bottom")
    ax.set_aspect("equal")
    ax.axis("off")


def _draw_png(pattern: Pattern, path: Path) -> Path:
    require("matplotlib", "drawing a pattern as PNG", "render")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    off = layout(pattern)
    everything = np.concatenate([p.outline(0.02) + off[p.name] for p in pattern.panels])
    w, h = np.ptp(everything, axis=0) + 0.1
    fig, ax = plt.subplots(figsize=(min(3 + 3 * w, 16), min(3 + 3 * h, 16)))
    draw_pattern_axes(ax, pattern)
    ax.set_title(f"{pattern.name}: {len(pattern.panels)} panels, {len(pattern.stitches)} stitches", fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(fig)
    return path
