"""Bands: straight strips sewn along a run of edges (waistbands, cuffs, stand collars).

A band's bottom edge is cut into pieces as long as the edges it is sewn to, so each piece is one
stitch; its ends are ``end-`` (left, seen from outside) and ``end+`` (right) and its top edge is the
band's free edge. Two bands make a ring when each one's ``end+`` is sewn to the other's ``end-``.
The grain runs along a band.
"""

from __future__ import annotations

import numpy as np

from datagen.garment.pattern.model import Stitch
from datagen.garment.pattern.programs.outline import Piece, Seg, piece, seam

__all__ = ["Target", "band"]

Target = tuple[Piece, list[str]]
"""A run of edges to sew to: a piece and the names of its edges, consecutive in its loop's order."""


def band(name: str, targets: list[Target], height: float, *, top_group: str, translation=None,
         rotation=None, stitch_ease: float = 0.0) -> tuple[Piece, list[Stitch]]:
    """A straight band (waistband, cuff or stand collar) whose bottom edge is sewn, piece by piece,
    to ``targets`` in the band's order (left to right seen from outside); its ends are ``end-``
    (left) and ``end+`` (right), its top edge is in group ``top_group``. Placed as given, or else
    flat over the first target's panel 1 cm outside it, its left end on that target's last point."""
    lengths = [p.length(*names) for p, names in targets]
    if translation is None:
        translation, rotation = _along(*targets[0])
    xs = np.concatenate([[0.0], np.cumsum(lengths)])
    segs = [Seg((float(xs[k]), 0.0), None, f"bottom{k}", "seam") for k in range(len(targets))]
    segs += [Seg((float(xs[-1]), 0.0), None, "end+"), Seg((float(xs[-1]), height), None, "top", top_group),
             Seg((0.0, height), None, "end-")]
    b = piece(name, segs, translation=translation, rotation=rotation, grain=(1.0, 0.0))
    return b, [seam(b, [f"bottom{k}"], p, names, ease=stitch_ease) for k, (p, names) in enumerate(targets)]


def _along(target: Piece, names: list[str]) -> tuple[tuple, tuple]:
    """Placement (translation, XYZ Euler degrees) of a band sewn to ``names`` of ``target``: in the
    target panel's plane 1 cm outside it, its x axis running from the target run's last point back
    to its first (a band sewn right sides out runs opposite to what it is sewn to)."""
    from scipy.spatial.transform import Rotation

    p = target.panel
    first = p.vertices[p.edges[target.index[names[0]]].start]
    last = p.vertices[p.edges[target.index[names[-1]]].end]
    a, b = p.to_3d(np.asarray([first, last]))
    normal = p.matrix()[:, 2]
    x = a - b
    x = x - normal * float(x @ normal)
    x /= np.linalg.norm(x)
    r = np.stack([x, np.cross(normal, x), normal], axis=1)
    angles = Rotation.from_matrix(r).as_euler("xyz", degrees=True)
    return tuple(float(v) for v in b + 0.01 * normal), tuple(float(v) for v in angles)
