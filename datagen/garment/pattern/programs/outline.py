"""Building panel outlines by name: chains of named edges, mirrored halves, and stitches by name.

A program draws a panel as a chain of :class:`Seg` s (a start point, the curve to the next
segment's start, the edge's name and its edge group), usually half of it: the half right of the
centre line (panel x >= 0), from the bottom centre counter-clockwise to the top centre.
:func:`mirror` gives the other half (x -> -x, order reversed, names ``...+`` -> ``...-``), and
:func:`piece` closes the loop into a :class:`~datagen.garment.pattern.model.Panel` that remembers
which edge index has which name, so stitches are written by name (:func:`seam`).

Names end in ``+`` (panel x > 0) or ``-`` (panel x < 0) for the two sides of a symmetric panel.
Seen from outside, the body's left (+X) is panel ``+`` on a front panel and panel ``-`` on a back
panel (a back panel is turned 180 degrees about Y).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from datagen.garment.pattern.model import Arc, Cubic, Edge, Panel, Quadratic, SeamSide, Stitch

__all__ = ["Piece", "Seg", "curve_length", "mirror", "mirrored_name", "piece", "seam", "shift", "straight", "turn"]

P = tuple[float, float]


@dataclass(frozen=True)
class Seg:
    """One edge of an outline under construction: from ``start`` to the next segment's start."""

    start: P
    curve: Quadratic | Cubic | Arc | None = None
    name: str = ""
    group: str | None = None


def straight(points: Sequence[P], names: Sequence[str], group: str | None = None) -> list[Seg]:
    """Straight segments from each of ``points`` to the next (the last point starts no segment)."""
    return [Seg(tuple(map(float, p)), None, n, group) for p, n in zip(points[:-1], names)]


def mirrored_name(name: str) -> str:
    if name.endswith("+"):
        return name[:-1] + "-"
    if name.endswith("-"):
        return name[:-1] + "+"
    return name


def _mx(p: P) -> P:
    return (-float(p[0]), float(p[1]))


def _reverse_mirror_curve(c):
    if c is None or isinstance(c, Arc):  # mirroring and reversing both flip an arc's side
        return c
    if isinstance(c, Quadratic):
        return Quadratic(control=_mx(c.control))
    return Cubic(control1=_mx(c.control2), control2=_mx(c.control1))


def mirror(segs: Sequence[Seg], end: P) -> tuple[list[Seg], P]:
    """The chain ``segs`` (ending at ``end``) mirrored in x and reversed: (segments, its end point).

    The chain from A to B becomes the chain from mirror(B) to mirror(A), so that a counter-clockwise
    half outline right of x = 0 followed by its mirror is a counter-clockwise whole."""
    pts = [s.start for s in segs] + [end]
    out = []
    for k in range(len(segs) - 1, -1, -1):
        s = segs[k]
        out.append(Seg(_mx(pts[k + 1]), _reverse_mirror_curve(s.curve), mirrored_name(s.name), s.group))
    return out, _mx(pts[0])


def _map_points(segs: Sequence[Seg], f) -> list[Seg]:
    """``segs`` with every point (starts and Bézier controls) mapped by ``f`` [m] -> [m]."""
    out = []
    for s in segs:
        c = s.curve
        if isinstance(c, Quadratic):
            c = Quadratic(control=f(c.control))
        elif isinstance(c, Cubic):
            c = Cubic(control1=f(c.control1), control2=f(c.control2))
        out.append(Seg(f(s.start), c, s.name, s.group))
    return out


def shift(segs: Sequence[Seg], dx: float = 0.0, dy: float = 0.0) -> list[Seg]:
    """``segs`` translated by (dx, dy) [m] in panel space."""
    return _map_points(segs, lambda p: (p[0] + dx, p[1] + dy))


def turn(segs: Sequence[Seg]) -> list[Seg]:
    """``segs`` turned a quarter counter-clockwise in panel space ((x, y) -> (-y, x)); a panel so
    turned is placed as before with ``Rz(-90 degrees)`` applied first."""
    return _map_points(segs, lambda p: (-float(p[1]), float(p[0])))


def curve_length(start: P, end: P, curve=None) -> float:
    """Length [m] of one edge from ``start`` to ``end`` (the model's measure)."""
    panel_like = _Two(vertices=(tuple(start), tuple(end)))
    return Edge(start=0, end=1, curve=curve).length(panel_like)


@dataclass(frozen=True)
class _Two:
    vertices: tuple


@dataclass(frozen=True)
class Piece:
    """A built panel and the index of each named edge."""

    panel: Panel
    index: dict[str, int] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.panel.name

    def side(self, *names: str) -> SeamSide:
        """The seam side made of the named edges (consecutive in the loop, in loop order)."""
        return SeamSide(panel=self.panel.name, edges=tuple(self.index[n] for n in names))

    def length(self, *names: str) -> float:
        return float(sum(self.panel.edge_length(self.index[n]) for n in names))

    def point(self, name: str) -> np.ndarray:
        """Start point [2] of the named edge, in panel space."""
        return np.asarray(self.panel.vertices[self.panel.edges[self.index[name]].start])


def piece(name: str, segs: Iterable[Seg], *, translation=(0.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.0),
          grain=(0.0, 1.0), limb: bool = False) -> Piece:
    """The closed panel of ``segs`` (the last segment ends at the first's start), with edge groups
    from the segments' groups and an index of their names (names must be unique, or empty); ``limb``:
    the panel covers one limb (:class:`~datagen.garment.pattern.model.Panel`)."""
    segs = list(segs)
    verts = [s.start for s in segs]
    edges = tuple(Edge(start=i, end=(i + 1) % len(segs), curve=s.curve) for i, s in enumerate(segs))
    groups: dict[str, list[int]] = {}
    index: dict[str, int] = {}
    for i, s in enumerate(segs):
        if s.group:
            groups.setdefault(s.group, []).append(i)
        if s.name:
            if s.name in index:
                raise ValueError(f"panel {name!r}: two edges named {s.name!r}")
            index[s.name] = i
    panel = Panel(name=name, vertices=tuple(verts), edges=edges, translation=tuple(translation),
                  rotation=tuple(rotation), grain=tuple(grain), edge_groups={k: tuple(v) for k, v in groups.items()},
                  limb=limb)
    return Piece(panel, index)


def seam(a: Piece, a_names: Sequence[str], b: Piece, b_names: Sequence[str], *, reversed: bool = True,
         ease: float = 0.0) -> Stitch:
    """The stitch joining the named edges of ``a`` to those of ``b`` (two counter-clockwise outlines
    sewn right sides out meet reversed: a's first point at b's last)."""
    return Stitch(a=a.side(*a_names), b=b.side(*b_names), reversed=reversed, ease=ease)
