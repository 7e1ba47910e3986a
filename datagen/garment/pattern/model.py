"""Sewing patterns: panels (closed 2D outlines), their 3D placement, and the stitches between them.

A :class:`Pattern` is what a pattern program builds and what GarmentCode's specification JSON
holds (:mod:`datagen.garment.pattern.spec`): a set of :class:`Panel` s, each a closed loop of
:class:`Edge` s (straight, quadratic or cubic Bezier, circular arc) in 2D panel space, and a set
of :class:`Stitch` es, each joining a run of consecutive edges of one panel to a run of another
(or of the same) panel, with an explicit orientation.

Conventions (docs/patterns.md): metres; panel space is 2D with x to the panel's right seen from
outside the garment and y up; an outline runs counter-clockwise seen from outside (its normal,
after placement, points away from the body). A panel's placement in the body's rest frame (Y up,
the body faces +Z) is ``R @ [x, y, 0] + translation`` with ``R`` from XYZ Euler angles in degrees,
GarmentCode's (Maya's) convention ``R = Rz @ Ry @ Rx``.

Every record is a frozen keyword-only dataclass validated on construction; a mistake raises
:class:`~datagen.errors.InputError` naming the panel and the edge.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from datagen.errors import InputError

__all__ = ["Arc", "Cubic", "Curve", "Edge", "Panel", "Pattern", "Quadratic", "SeamSide", "Stitch",
           "STITCH_TOLERANCE", "euler_xyz_matrix"]

STITCH_TOLERANCE = 0.01
"""Relative length difference allowed between the two sides of a stitch, on top of its ease."""

_CURVE_SAMPLES = 513
"""Points of the dense polyline that measures and resamples a curved edge by arc length (the
length error is below 1e-5 relative for the curves patterns use)."""

_CHECK_SPACING = 0.004
"""Spacing [m] of the outline samples that the self-intersection check walks (at most
:data:`_CHECK_MAX_PER_EDGE` per edge)."""
_CHECK_MAX_PER_EDGE = 96


def _point(p, what: str) -> tuple[float, float]:
    a = np.asarray(p, dtype=float).reshape(-1)
    if a.shape != (2,) or not np.all(np.isfinite(a)):
        raise InputError(f"{what} must be two finite numbers [m], got {p!r}")
    return (float(a[0]), float(a[1]))


@dataclass(frozen=True, kw_only=True)
class Quadratic:
    """Quadratic Bezier edge: one control point in absolute panel coordinates [m]."""

    control: tuple[float, float]

    def __post_init__(self):
        object.__setattr__(self, "control", _point(self.control, "a quadratic edge's control point"))


@dataclass(frozen=True, kw_only=True)
class Cubic:
    """Cubic Bezier edge: two control points in absolute panel coordinates [m]."""

    control1: tuple[float, float]
    control2: tuple[float, float]

    def __post_init__(self):
        object.__setattr__(self, "control1", _point(self.control1, "a cubic edge's first control point"))
        object.__setattr__(self, "control2", _point(self.control2, "a cubic edge's second control point"))


@dataclass(frozen=True, kw_only=True)
class Arc:
    """Circular arc from the edge's start to its end, as SVG's and GarmentCode's ``circle``.

    ``radius`` [m] (at least half the chord); ``large_arc``: the arc spans more than 180 degrees;
    ``right``: the arc bulges to the right of the direction start -> end (in panel space, y up),
    i.e. GarmentCode's relative control point has a negative y."""

    radius: float
    large_arc: bool
    right: bool

    def __post_init__(self):
        r = float(self.radius)
        if not (math.isfinite(r) and r > 0):
            raise InputError(f"an arc's radius must be a positive number of metres, got {self.radius!r}")
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "large_arc", bool(self.large_arc))
        object.__setattr__(self, "right", bool(self.right))


Curve = Quadratic | Cubic | Arc | None
"""An edge's shape between its end points; ``None`` is a straight segment."""


def _bezier(nodes: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Points [len(t), 2] of the Bezier curve with control ``nodes`` [k, 2] at parameters ``t``."""
    pts = np.repeat(nodes[None], len(t), axis=0)
    tt = t[:, None]
    while pts.shape[1] > 1:  # de Casteljau
        pts = pts[:, :-1] * (1 - tt[:, :, None]) + pts[:, 1:] * tt[:, :, None]
    return pts[:, 0]


def arc_geometry(start, end, arc: Arc) -> tuple[np.ndarray, float, float]:
    """Centre [2], start angle and signed sweep angle [rad] of ``arc`` from ``start`` to ``end``.

    Raises :class:`InputError` when the radius is shorter than half the chord (no such circle)."""
    p0, p1 = np.asarray(start, float), np.asarray(end, float)
    chord = p1 - p0
    d = float(np.hypot(*chord))
    if arc.radius < d / 2 * (1 - 1e-9):
        raise InputError(f"an arc of radius {arc.radius:.6g} m cannot join points {d:.6g} m apart "
                         f"(the radius must be at least half the chord, {d / 2:.6g} m)")
    h = math.sqrt(max(arc.radius**2 - d * d / 4, 0.0))
    left = np.array([-chord[1], chord[0]]) / d          # unit normal to the left of start -> end
    bulge = -1.0 if arc.right else 1.0                  # side of the arc's midpoint
    # small arc: the centre lies on the other side of the chord from the arc; large arc: same side
    centre = (p0 + p1) / 2 + left * (bulge * h if arc.large_arc else -bulge * h)
    a0 = math.atan2(p0[1] - centre[1], p0[0] - centre[0])
    half = math.asin(min(d / 2 / arc.radius, 1.0))
    span = 2 * math.pi - 2 * half if arc.large_arc else 2 * half
    # counter-clockwise travel from start to end puts the arc on the right of the chord
    sweep = span if arc.right else -span
    return centre, a0, sweep


@dataclass(frozen=True, kw_only=True)
class Edge:
    """One edge of a panel's outline: from ``vertices[start]`` to ``vertices[end]``."""

    start: int
    end: int
    curve: Curve = None

    def __post_init__(self):
        for name in ("start", "end"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise InputError(f"an edge's {name} must be a vertex index, got {v!r}")
            object.__setattr__(self, name, int(v))
        if self.curve is not None and not isinstance(self.curve, (Quadratic, Cubic, Arc)):
            raise InputError(f"an edge's curve must be Quadratic, Cubic, Arc or None, got {self.curve!r}")

    def _dense(self, panel: Panel) -> np.ndarray:
        p0 = np.asarray(panel.vertices[self.start])
        p1 = np.asarray(panel.vertices[self.end])
        c = self.curve
        t = np.linspace(0.0, 1.0, _CURVE_SAMPLES)
        if c is None:
            return np.stack([p0, p1])
        if isinstance(c, Quadratic):
            return _bezier(np.stack([p0, np.asarray(c.control), p1]), t)
        if isinstance(c, Cubic):
            return _bezier(np.stack([p0, np.asarray(c.control1), np.asarray(c.control2), p1]), t)
        centre, a0, sweep = arc_geometry(p0, p1, c)
        a = a0 + sweep * t
        pts = centre + c.radius * np.stack([np.cos(a), np.sin(a)], axis=1)
        pts[0], pts[-1] = p0, p1
        return pts

    def length(self, panel: Panel) -> float:
        """Arc length of the edge [m] in ``panel``'s space."""
        if isinstance(self.curve, Arc):
            _, _, sweep = arc_geometry(panel.vertices[self.start], panel.vertices[self.end], self.curve)
            return abs(sweep) * self.curve.radius
        pts = self._dense(panel)
        return float(np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1)))

    def sample(self, panel: Panel, n: int) -> np.ndarray:
        """``n`` >= 2 points [n, 2] equally spaced by arc length from start to end (both included)."""
        if n < 2:
            raise InputError(f"an edge is sampled with at least 2 points, got {n}")
        return self.points_at(panel, np.linspace(0.0, 1.0, n))

    def points_at(self, panel: Panel, fractions) -> np.ndarray:
        """Points [len(fractions), 2] at the given fractions (0 = start, 1 = end) of the arc length."""
        f = np.clip(np.asarray(fractions, dtype=float), 0.0, 1.0)
        p0, p1 = np.asarray(panel.vertices[self.start]), np.asarray(panel.vertices[self.end])
        if isinstance(self.curve, Arc):  # equal angles are equal lengths: exact points on the circle
            centre, a0, sweep = arc_geometry(p0, p1, self.curve)
            a = a0 + sweep * f
            out = centre + self.curve.radius * np.stack([np.cos(a), np.sin(a)], axis=1)
        else:
            pts = self._dense(panel)
            seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
            s = np.concatenate([[0.0], np.cumsum(seg)])
            target = f * s[-1]
            out = np.stack([np.interp(target, s, pts[:, 0]), np.interp(target, s, pts[:, 1])], axis=1)
        out[f == 0.0] = p0
        out[f == 1.0] = p1
        return out


def _segments_cross(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray) -> np.ndarray:
    """Whether segments a_i and b_j properly intersect or touch: [len(a), len(b)] booleans."""
    def orient(p, q, r):
        return ((q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
                - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0]))

    A0, A1 = a0[:, None], a1[:, None]
    B0, B1 = b0[None], b1[None]
    d1, d2 = orient(A0, A1, B0), orient(A0, A1, B1)
    d3, d4 = orient(B0, B1, A0), orient(B0, B1, A1)
    pts = np.concatenate([a0, a1, b0, b1])
    scale = max(float(np.ptp(pts, axis=0).max()), 1e-9)
    eps = 1e-12 * scale * scale
    crosses = (d1 * d2 <= eps) & (d3 * d4 <= eps)
    # collinear segments pass the orientation test wherever they lie: their boxes must overlap too
    lo_a, hi_a = np.minimum(A0, A1), np.maximum(A0, A1)
    lo_b, hi_b = np.minimum(B0, B1), np.maximum(B0, B1)
    tol = 1e-9 * scale
    boxes = np.all((lo_a <= hi_b + tol) & (lo_b <= hi_a + tol), axis=-1)
    return crosses & boxes


@dataclass(frozen=True, kw_only=True)
class Panel:
    """A piece of cloth: a closed, counter-clockwise (seen from outside) loop of edges.

    ``vertices`` [m] in panel space; ``edges[i].end == edges[i+1].start`` and the last edge ends
    where the first starts; ``translation`` [m] and ``rotation`` (XYZ Euler, degrees) place it in
    the body's rest frame; ``grain`` is the warp direction in panel space (unit); ``edge_groups``
    names runs of edges (``"hem": (2,)``) for openings and for the programs; ``limb``: the panel
    covers one limb (a trouser leg's front or back), so the placement bends it into a half tube
    round that limb (:mod:`datagen.garment.pattern.placement`) instead of laying it round the body."""

    name: str
    vertices: tuple[tuple[float, float], ...]
    edges: tuple[Edge, ...]
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    grain: tuple[float, float] = (0.0, 1.0)
    edge_groups: Mapping[str, tuple[int, ...]] = field(default_factory=dict)
    limb: bool = False

    def __post_init__(self):
        if not isinstance(self.limb, (bool, np.bool_)):
            raise InputError(f"panel '{self.name}': limb must be True or False, got {self.limb!r}")
        object.__setattr__(self, "limb", bool(self.limb))
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"a panel needs a non-empty name, got {self.name!r}")
        who = f"panel '{self.name}'"
        verts = tuple(_point(v, f"{who}: vertex {i}") for i, v in enumerate(self.vertices))
        if len(verts) < 2:
            raise InputError(f"{who} has {len(verts)} vertices; an outline needs at least 2 (with curved edges) or 3")
        object.__setattr__(self, "vertices", verts)
        edges = tuple(self.edges)
        if len(edges) < 2:
            raise InputError(f"{who} has {len(edges)} edges; a closed outline needs at least 2")
        for i, e in enumerate(edges):
            if not isinstance(e, Edge):
                raise InputError(f"{who}: edge {i} is not an Edge ({e!r})")
            for end in (e.start, e.end):
                if not 0 <= end < len(verts):
                    raise InputError(f"{who}: edge {i} refers to vertex {end}, but the panel has {len(verts)} vertices")
            nxt = edges[(i + 1) % len(edges)]
            if e.end != nxt.start:
                raise InputError(f"{who}: the outline is not closed: edge {i} ends at vertex {e.end} but edge "
                                 f"{(i + 1) % len(edges)} starts at vertex {nxt.start}")
            if np.allclose(verts[e.start], verts[e.end], atol=1e-9):
                raise InputError(f"{who}: edge {i} starts and ends at the same point {verts[e.start]}")
        object.__setattr__(self, "edges", edges)
        used = sorted({e.start for e in edges})
        if len(used) != len(edges):
            raise InputError(f"{who}: the outline visits a vertex twice (edges start at {[e.start for e in edges]})")
        for name, n in (("translation", 3), ("rotation", 3)):
            a = np.asarray(getattr(self, name), dtype=float).reshape(-1)
            if a.shape != (n,) or not np.all(np.isfinite(a)):
                raise InputError(f"{who}: {name} must be {n} finite numbers, got {getattr(self, name)!r}")
            object.__setattr__(self, name, tuple(float(x) for x in a))
        g = _point(self.grain, f"{who}: grain")
        if abs(math.hypot(*g) - 1.0) > 1e-6:
            raise InputError(f"{who}: the grain {g} must be a unit vector (its length is {math.hypot(*g):.6g})")
        object.__setattr__(self, "grain", g)
        groups = {}
        for gname, ids in dict(self.edge_groups).items():
            ids = tuple(int(i) for i in ((ids,) if isinstance(ids, (int, np.integer)) else ids))
            for i in ids:
                if not 0 <= i < len(edges):
                    raise InputError(f"{who}: edge group '{gname}' names edge {i}, but the panel has {len(edges)} edges")
            groups[str(gname)] = ids
        object.__setattr__(self, "edge_groups", groups)
        # curves that cannot exist (an arc shorter than its chord) fail here, naming the edge
        lengths = []
        for i, e in enumerate(edges):
            try:
                lengths.append(e.length(self))
            except InputError as exc:
                raise InputError(f"{who}: edge {i}: {exc}") from None
        self._check_outline(lengths)

    def _check_outline(self, lengths: list[float]) -> None:
        """Raise if the outline crosses itself or runs clockwise."""
        who = f"panel '{self.name}'"
        pieces, owner = [], []
        for i, e in enumerate(self.edges):
            n = 2 if e.curve is None else int(min(max(math.ceil(lengths[i] / _CHECK_SPACING), 8), _CHECK_MAX_PER_EDGE)) + 1
            pts = e.sample(self, n)
            pieces.append(pts[:-1])
            owner.append(np.full(n - 1, i))
        poly = np.concatenate(pieces)
        seg_edge = np.concatenate(owner)
        m = len(poly)
        a0, a1 = poly, np.roll(poly, -1, axis=0)
        hit = _segments_cross(a0, a1, a0, a1)
        idx = np.arange(m)
        adjacent = (np.abs(idx[:, None] - idx[None]) <= 1) | (np.abs(idx[:, None] - idx[None]) == m - 1)
        hit &= ~adjacent
        if hit.any():
            i, j = np.argwhere(hit)[0]
            ei, ej = int(seg_edge[i]), int(seg_edge[j])
            where = f"edge {ei}" if ei == ej else f"edges {min(ei, ej)} and {max(ei, ej)}"
            raise InputError(f"{who}: the outline crosses itself ({where}, near "
                             f"({poly[i, 0]:.3f}, {poly[i, 1]:.3f}) m); fix the vertices or curves of {where}")
        area = 0.5 * float(np.sum(a0[:, 0] * a1[:, 1] - a1[:, 0] * a0[:, 1]))
        if area <= 0:
            raise InputError(f"{who}: the outline runs clockwise (signed area {area:.4g} m^2); list its edges "
                             f"counter-clockwise as seen from outside the garment")

    def edge_length(self, i: int) -> float:
        """Length [m] of edge ``i``."""
        return self.edges[i].length(self)

    def outline(self, spacing: float = 0.01) -> np.ndarray:
        """The closed outline as points [N, 2] about ``spacing`` apart (first point not repeated)."""
        parts = []
        for e in self.edges:
            n = max(2, int(math.ceil(e.length(self) / spacing)) + 1)
            parts.append(e.sample(self, n)[:-1])
        return np.concatenate(parts)

    def area(self) -> float:
        """Area [m^2] enclosed by the outline (sampled 2 mm apart)."""
        p = self.outline(0.002)
        q = np.roll(p, -1, axis=0)
        return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))

    def matrix(self) -> np.ndarray:
        """Rotation [3, 3] that takes panel space (x, y, 0) into the body's rest frame."""
        return euler_xyz_matrix(self.rotation)

    def to_3d(self, points: np.ndarray) -> np.ndarray:
        """Panel points [N, 2] placed flat at this panel's rotation and translation: [N, 3] [m]."""
        p = np.asarray(points, float)
        p3 = np.concatenate([p, np.zeros((len(p), 1))], axis=1)
        return p3 @ self.matrix().T + np.asarray(self.translation)


def euler_xyz_matrix(angles_deg) -> np.ndarray:
    """Rotation matrix [3, 3] of XYZ Euler angles in degrees, as GarmentCode/Maya: ``Rz @ Ry @ Rx``."""
    x, y, z = np.deg2rad(np.asarray(angles_deg, float))
    cx, sx, cy, sy, cz, sz = np.cos(x), np.sin(x), np.cos(y), np.sin(y), np.cos(z), np.sin(z)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


@dataclass(frozen=True, kw_only=True)
class SeamSide:
    """One side of a stitch: consecutive edges of panel ``panel``, in the loop's order."""

    panel: str
    edges: tuple[int, ...]

    def __post_init__(self):
        ids = (self.edges,) if isinstance(self.edges, (int, np.integer)) else self.edges
        ids = tuple(int(i) for i in ids)
        if not ids:
            raise InputError(f"a stitch side on panel '{self.panel}' names no edge")
        object.__setattr__(self, "edges", ids)

    def length(self, pattern: Pattern) -> float:
        """Total length [m] of this side's edges."""
        p = pattern.panel(self.panel)
        return float(sum(p.edge_length(i) for i in self.edges))

    def sample(self, pattern: Pattern, counts: tuple[int, ...]) -> np.ndarray:
        """Points along this side, edge ``edges[k]`` with ``counts[k]`` segments: [sum(counts) + 1, 2]."""
        p = pattern.panel(self.panel)
        parts = [p.edges[i].sample(p, c + 1)[:-1] for i, c in zip(self.edges, counts)]
        last = p.edges[self.edges[-1]]
        return np.concatenate(parts + [np.asarray(p.vertices[last.end])[None]])


@dataclass(frozen=True, kw_only=True)
class Stitch:
    """Two seam sides sewn together.

    ``reversed=True``: a's first point meets b's LAST point (two counter-clockwise outlines sewn
    right sides out meet this way); ``False``: a's first point meets b's first point. ``ease`` is
    the relative length difference allowed on top of :data:`STITCH_TOLERANCE` (gathering)."""

    a: SeamSide
    b: SeamSide
    reversed: bool = True
    ease: float = 0.0

    def __post_init__(self):
        if not isinstance(self.a, SeamSide) or not isinstance(self.b, SeamSide):
            raise InputError(f"a stitch joins two SeamSides, got {self.a!r} and {self.b!r}")
        e = float(self.ease)
        if not (math.isfinite(e) and 0 <= e < 1):
            raise InputError(f"a stitch's ease is a relative length difference in [0, 1), got {self.ease!r}")
        object.__setattr__(self, "ease", e)
        object.__setattr__(self, "reversed", bool(self.reversed))

    def describe(self) -> str:
        return f"stitch {self.a.panel}{list(self.a.edges)} - {self.b.panel}{list(self.b.edges)}"


@dataclass(frozen=True, kw_only=True)
class Pattern:
    """A garment's panels and the stitches between them, with the design that made it."""

    name: str
    panels: tuple[Panel, ...]
    stitches: tuple[Stitch, ...]
    design: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"a pattern needs a non-empty name, got {self.name!r}")
        panels = tuple(self.panels)
        stitches = tuple(self.stitches)
        if not panels:
            raise InputError(f"pattern '{self.name}' has no panel")
        seen = set()
        for p in panels:
            if not isinstance(p, Panel):
                raise InputError(f"pattern '{self.name}': {p!r} is not a Panel")
            if p.name in seen:
                raise InputError(f"pattern '{self.name}': two panels are named '{p.name}'; panel names must be unique")
            seen.add(p.name)
        object.__setattr__(self, "panels", panels)
        object.__setattr__(self, "stitches", stitches)
        object.__setattr__(self, "design", dict(self.design))
        by_name = {p.name: p for p in panels}
        sewn: dict[tuple[str, int], int] = {}
        for k, s in enumerate(stitches):
            if not isinstance(s, Stitch):
                raise InputError(f"pattern '{self.name}': stitch {k} is not a Stitch ({s!r})")
            lengths = []
            for side in (s.a, s.b):
                p = by_name.get(side.panel)
                if p is None:
                    raise InputError(f"pattern '{self.name}': stitch {k} names panel '{side.panel}', which the "
                                     f"pattern does not have (panels: {sorted(by_name)})")
                n = len(p.edges)
                for j, i in enumerate(side.edges):
                    if not 0 <= i < n:
                        raise InputError(f"pattern '{self.name}': stitch {k} names edge {i} of panel '{p.name}', "
                                         f"which has {n} edges")
                    if j and i != (side.edges[j - 1] + 1) % n:
                        raise InputError(f"pattern '{self.name}': stitch {k}: edges {list(side.edges)} of panel "
                                         f"'{p.name}' are not consecutive in its loop")
                    if (p.name, i) in sewn:
                        raise InputError(f"pattern '{self.name}': edge {i} of panel '{p.name}' is stitched twice "
                                         f"(stitches {sewn[(p.name, i)]} and {k}); an edge joins one seam only")
                    sewn[(p.name, i)] = k
                lengths.append(sum(p.edge_length(i) for i in side.edges))
            la, lb = lengths
            tol = STITCH_TOLERANCE + s.ease
            if abs(la - lb) > tol * max(la, lb):
                raise InputError(
                    f"pattern '{self.name}': stitch {k} joins panel '{s.a.panel}' edges {list(s.a.edges)} "
                    f"({la * 100:.2f} cm) to panel '{s.b.panel}' edges {list(s.b.edges)} ({lb * 100:.2f} cm): "
                    f"they differ by {abs(la - lb) / max(la, lb):.1%}, more than the {tol:.1%} allowed "
                    f"(1 % + ease {s.ease:.1%}); make the two sides the same length or give the stitch ease")

    def panel(self, name: str) -> Panel:
        """The panel called ``name``."""
        for p in self.panels:
            if p.name == name:
                return p
        raise InputError(f"pattern '{self.name}' has no panel '{name}' (panels: {[p.name for p in self.panels]})")

    def panel_index(self, name: str) -> int:
        """Position of panel ``name`` in :attr:`panels`."""
        for i, p in enumerate(self.panels):
            if p.name == name:
                return i
        raise InputError(f"pattern '{self.name}' has no panel '{name}' (panels: {[p.name for p in self.panels]})")

    def free_edges(self) -> list[tuple[str, int]]:
        """(panel, edge) pairs that no stitch sews: the garment's openings and hems."""
        sewn = {(side.panel, i) for s in self.stitches for side in (s.a, s.b) for i in side.edges}
        return [(p.name, i) for p in self.panels for i in range(len(p.edges)) if (p.name, i) not in sewn]
