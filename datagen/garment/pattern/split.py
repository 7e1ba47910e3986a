"""Splitting panel edges so that every stitch joins as many edges on both sides, and joining them back.

GarmentCode's format stitches one edge to one edge. A drape stitch may join two edges of a skirt to
one edge of its waistband; to write it, :func:`pair_stitches` splits edges (exactly: a line at a
point, a Bezier by de Casteljau at the parameter of the arc-length fraction, an arc into arcs of the
same circle) at the other side's corners, so the stitch becomes one-edge pairs. Each piece records
``(original edge, t0, t1)`` (curve parameters), which :func:`join_pieces` uses to rebuild the
original edge on reading, so a pattern written and read again is the same pattern.
"""

from __future__ import annotations

import math

import numpy as np

from datagen.garment.pattern.model import Arc, Cubic, Edge, Panel, Pattern, Quadratic, SeamSide, Stitch, arc_geometry

__all__ = ["join_curve", "pair_stitches", "split_curve"]

_CLOSE = 1e-4
"""Corners of two seam sides closer than this share of the seam's length are one corner."""


def _bezier_nodes(panel: Panel, e: Edge) -> np.ndarray:
    p0, p1 = np.asarray(panel.vertices[e.start]), np.asarray(panel.vertices[e.end])
    if isinstance(e.curve, Quadratic):
        return np.stack([p0, np.asarray(e.curve.control), p1])
    return np.stack([p0, np.asarray(e.curve.control1), np.asarray(e.curve.control2), p1])


def _de_casteljau(nodes: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Control points of the two halves of a Bezier split at parameter t."""
    left, right, pts = [nodes[0]], [nodes[-1]], nodes
    while len(pts) > 1:
        pts = pts[:-1] * (1 - t) + pts[1:] * t
        left.append(pts[0])
        right.append(pts[-1])
    return np.array(left), np.array(right[::-1])


def _param_at_fractions(panel: Panel, e: Edge, fractions: np.ndarray) -> np.ndarray:
    """Curve parameters t at arc-length fractions of edge e."""
    if e.curve is None or isinstance(e.curve, Arc):
        return np.asarray(fractions, float)  # lines and arcs: the parameter is the arc-length fraction
    dense = e._dense(panel)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))])
    return np.interp(np.asarray(fractions) * s[-1], s, np.linspace(0, 1, len(dense)))


def split_curve(panel: Panel, e: Edge, ts: list[float]) -> list[tuple[np.ndarray, object]]:
    """Pieces of edge e split at parameters ``ts`` (increasing, inside (0, 1)): [(end point, curve)]."""
    out = []
    p0, p1 = np.asarray(panel.vertices[e.start]), np.asarray(panel.vertices[e.end])
    bounds = [0.0, *ts, 1.0]
    if e.curve is None:
        for t0, t1 in zip(bounds[:-1], bounds[1:]):
            out.append((p0 + (p1 - p0) * t1, None))
    elif isinstance(e.curve, Arc):
        centre, a0, sweep = arc_geometry(p0, p1, e.curve)
        for t0, t1 in zip(bounds[:-1], bounds[1:]):
            a = a0 + sweep * t1
            end = centre + e.curve.radius * np.array([math.cos(a), math.sin(a)])
            out.append((end, Arc(radius=e.curve.radius, large_arc=abs(sweep) * (t1 - t0) > math.pi,
                                 right=e.curve.right)))
    else:
        rest, done = _bezier_nodes(panel, e), 0.0
        for t in bounds[1:]:
            if t < 1.0:
                left, rest = _de_casteljau(rest, (t - done) / (1 - done))
            else:
                left = rest
            done = t
            curve = (Quadratic(control=tuple(left[1])) if len(left) == 3
                     else Cubic(control1=tuple(left[1]), control2=tuple(left[2])))
            out.append((left[-1], curve))
    out[-1] = (p1, out[-1][1])
    return out


def join_curve(start, end, pieces: list[tuple[object, float, float]], first_start, first_curve_end):
    """The curve of an edge from ``start`` to ``end`` rebuilt from its pieces.

    ``pieces``: [(curve, t0, t1)] in order, the first piece running from ``first_start`` to
    ``first_curve_end``. A line stays a line; arcs keep their circle; a Bezier's control points are
    those of the polynomial the first piece lies on, extended to [0, 1]."""
    curve, t0, t1 = pieces[0]
    if curve is None:
        return None
    if isinstance(curve, Arc):
        total = 0.0
        for c, a, b in pieces:
            total += b - a
        # a full sweep's share: large if the pieces together sweep more than half the circle
        p0, p1 = np.asarray(first_start), np.asarray(first_curve_end)
        _, _, sweep = arc_geometry(p0, p1, curve)
        whole = abs(sweep) / (t1 - t0)
        return Arc(radius=curve.radius, large_arc=whole > math.pi, right=curve.right)
    nodes = (np.stack([first_start, curve.control, first_curve_end]) if isinstance(curve, Quadratic)
             else np.stack([first_start, curve.control1, curve.control2, first_curve_end]))
    deg = len(nodes) - 1
    # the piece is the original on [t0, t1]: evaluate it at s in [0, 1], refit on t in [0, 1]
    s = np.linspace(0, 1, 2 * deg + 3)
    from math import comb
    bern = lambda x: np.stack([comb(deg, k) * x**k * (1 - x) ** (deg - k) for k in range(deg + 1)], axis=1)  # noqa: E731
    pts = bern(s) @ nodes
    t = t0 + s * (t1 - t0)
    full = np.linalg.lstsq(bern(t), pts, rcond=None)[0]
    if deg == 2:
        return Quadratic(control=tuple(full[1]))
    return Cubic(control1=tuple(full[1]), control2=tuple(full[2]))


def pair_stitches(pattern: Pattern) -> tuple[Pattern, dict[tuple[str, int], tuple[int, float, float]]]:
    """``pattern`` with edges split so that both sides of every stitch have as many edges, matching.

    Returns the split pattern and, for every new edge that is a piece of an old one, ``(panel name,
    new edge) -> (old edge, t0, t1)``. A pattern whose stitches already pair up is returned as is."""
    cuts: dict[tuple[str, int], set[float]] = {}
    for st in pattern.stitches:
        if len(st.a.edges) == len(st.b.edges):
            continue
        sides = []
        for side in (st.a, st.b):
            p = pattern.panel(side.panel)
            ln = np.array([p.edge_length(i) for i in side.edges])
            sides.append((p, ln, np.concatenate([[0.0], np.cumsum(ln) / ln.sum()])))
        ca, cb = sides[0][2], sides[1][2]
        cb_sewn = 1 - cb[::-1] if st.reversed else cb
        for (side, (p, ln, corners), other) in ((st.a, sides[0], cb_sewn), (st.b, sides[1], None)):
            if other is None:
                other = 1 - ca[::-1] if st.reversed else ca
            for f in other[1:-1]:
                if np.min(np.abs(corners - f)) < _CLOSE:
                    continue
                k = int(np.searchsorted(corners, f) - 1)
                local = (f - corners[k]) / (corners[k + 1] - corners[k])
                cuts.setdefault((side.panel, side.edges[k]), set()).add(float(local))
    if not cuts:
        return pattern, {}
    panels, pieces, new_index = [], {}, {}
    for p in pattern.panels:
        verts = [np.asarray(v) for v in p.vertices]
        edges: list[Edge] = []
        index: dict[int, list[int]] = {}
        # vertices keep their indices; inserted points are appended
        for i, e in enumerate(p.edges):
            fr = sorted(cuts.get((p.name, i), ()))
            if not fr:
                index[i] = [len(edges)]
                edges.append(e)
                continue
            ts = list(_param_at_fractions(p, e, np.array(fr)))
            parts = split_curve(p, e, ts)
            bounds = [0.0, *ts, 1.0]
            start = e.start
            ids = []
            for k, (end_pt, curve) in enumerate(parts):
                if k == len(parts) - 1:
                    end = e.end
                else:
                    verts.append(end_pt)
                    end = len(verts) - 1
                ids.append(len(edges))
                pieces[(p.name, len(edges))] = (i, bounds[k], bounds[k + 1])
                edges.append(Edge(start=start, end=end, curve=curve))
                start = end
            index[i] = ids
        new_index[p.name] = index
        groups = {g: tuple(j for i in ids for j in index[i]) for g, ids in p.edge_groups.items()}
        panels.append(Panel(name=p.name, vertices=[tuple(v) for v in verts], edges=edges,
                            translation=p.translation, rotation=p.rotation, grain=p.grain, edge_groups=groups,
                            limb=p.limb))
    stitches = []
    for st in pattern.stitches:
        sides = [SeamSide(panel=s.panel, edges=tuple(j for i in s.edges for j in new_index[s.panel][i]))
                 for s in (st.a, st.b)]
        stitches.append(Stitch(a=sides[0], b=sides[1], reversed=st.reversed, ease=st.ease))
    return Pattern(name=pattern.name, panels=tuple(panels), stitches=tuple(stitches), design=pattern.design), pieces
