"""Placing a flat pattern mesh around the body in its rest pose: the simulator's start positions.

Two modes (:func:`place`):

- ``"flat"``: every panel where its pattern puts it, ``R @ [x, y, 0] + translation`` (GarmentCode's
  and the programs' placement), then pushed out of the body.
- ``"wrap"`` (default): each flat panel is first bent, without stretching, around an axis along its
  own y direction through the middle of the body behind it (a cylinder of the panel's distance to
  that axis; wider, with the axis moved back, for a panel that would turn more than 99 degrees either
  side), so a front and a back panel meet at the sides; then pushed out of the body. Bending
  is isometric, so the rest state (the flat panel) is unstrained; the stitched pairs start closer.

In both modes a panel marked ``limb`` (a trouser leg's front or back) is bent instead into a half
tube round the limb behind it (:func:`_limb`): its axis runs along the panel's y direction through the
middle of the body behind the panel's lower half and central half (the leg), its radius is the
largest of the panel's half width over 90 degrees and the limb's own radius there plus the
clearance, so a front and a back panel meet at the limb's sides and their crotch extensions curl
between the legs; a tube that would cross the body's midplane (a back panel, wider by its crotch
extension) has its axis moved out until it keeps half of ``SEPARATION`` from it. Laid flat in front of both legs (trousers seed 0, regular body) the left
front panel's crotch extension lies on the right one: 75 crossings once sewn; wrapped round each
leg, 4.

Pushing out: a vertex inside the body or closer than ``clearance`` to it moves to the closest body
point plus ``clearance`` along the outward direction (warp mesh queries, as the garment checks).
:func:`placement_report` gives the figures that compare the modes (stitch gap, vertices inside).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Literal

import numpy as np

from datagen.errors import InputError
from datagen.garment.pattern.mesh import FlatPatternMesh
from datagen.geometry.queries import push_out

__all__ = ["CLEARANCE", "SEPARATION", "PlacementReport", "place", "placement_report", "push_out", "separate"]

log = logging.getLogger(__name__)

CLEARANCE = 0.008
"""Smallest distance [m] between a placed vertex and the body (the procedural garments' MIN_CLEARANCE)."""

Mode = Literal["flat", "wrap"]

_MAX_TURN = 0.5 * np.pi
"""Largest angle [rad] a wrapped panel turns either side of its middle."""


def _flat(mesh: FlatPatternMesh) -> np.ndarray:
    out = np.zeros((mesh.vertex_count, 3))
    for pi, panel in enumerate(mesh.pattern.panels):
        sel = mesh.panel_id == pi
        out[sel] = panel.to_3d(mesh.rest_uv[sel])
    return out


def _limb(mesh: FlatPatternMesh, body_vertices: np.ndarray, out: np.ndarray, clearance: float) -> np.ndarray:
    """``out`` [V, 3] with every ``limb`` panel bent into a half tube round the limb behind it
    (module docstring); the others as given."""
    out = out.copy()
    flat = _flat(mesh)
    mid = body_vertices.mean(axis=0)
    for pi, panel in enumerate(mesh.pattern.panels):
        if not panel.limb:
            continue
        sel = mesh.panel_id == pi
        r = panel.matrix()
        ex, ey, n = r[:, 0], r[:, 1], r[:, 2]
        origin = np.asarray(panel.translation)
        pts = flat[sel]
        px, py = (pts - origin) @ ex, (pts - origin) @ ey
        rel = body_vertices - origin
        bx, by, bn = rel @ ex, rel @ ey, rel @ n
        x0, x1 = np.percentile(px, [25, 75])
        y0 = py.min()
        behind = (bx > x0) & (bx < x1) & (by > y0) & (by < y0 + 0.5 * (py.max() - y0)) & (bn < 0)
        if behind.sum() < 10:
            continue  # no limb behind it: left where the program put it
        axis = body_vertices[behind].mean(axis=0)
        limb = body_vertices[behind] - axis
        limb_radius = float(np.percentile(np.hypot(limb @ ex, limb @ n), 90))
        rel = pts - axis
        x, y = rel @ ex, rel @ ey
        radius = max(float(np.abs(x).max()) / _MAX_TURN, limb_radius + clearance)
        # the tube keeps to its side of the body's midplane (the other leg's tube is its mirror)
        side = float((axis - mid) @ ex)
        short = radius + SEPARATION / 2 - abs(side)
        if short > 0:
            axis = axis + np.sign(side) * short * ex
            x = (pts - axis) @ ex
        theta = x / radius
        out[sel] = axis + y[:, None] * ey + radius * (np.cos(theta)[:, None] * n + np.sin(theta)[:, None] * ex)
    return out


def _wrap(mesh: FlatPatternMesh, body_vertices: np.ndarray) -> np.ndarray:
    out = _flat(mesh)
    for pi, panel in enumerate(mesh.pattern.panels):
        if panel.limb:
            continue  # bent round its limb (_limb)
        sel = mesh.panel_id == pi
        r = panel.matrix()
        ex, ey, n = r[:, 0], r[:, 1], r[:, 2]
        origin = np.asarray(panel.translation)
        pts = out[sel]
        # the body behind the panel: vertices whose projection along the normal falls on the panel's box
        rel = body_vertices - origin
        bx, by, bn = rel @ ex, rel @ ey, rel @ n
        px, py = (pts - origin) @ ex, (pts - origin) @ ey
        behind = ((bx > px.min()) & (bx < px.max()) & (by > py.min()) & (by < py.max()) & (bn < 0))
        if behind.sum() < 10:
            continue  # nothing behind this panel (a collar above the neck, a far-away piece): leave it flat
        axis = body_vertices[behind].mean(axis=0)
        d = float((origin - axis) @ n)
        if d <= 0.02:
            continue  # the panel cuts through the body's middle: bending would fold it; the push handles it
        # a panel wider than half the way around (a circle skirt's) gets a larger radius, the axis
        # moved back: it turns at most _MAX_TURN either side, so it does not wrap over itself
        half = float(np.abs((pts - axis) @ ex).max())
        if half / d > _MAX_TURN:
            axis = axis - n * (half / _MAX_TURN - d)
            d = half / _MAX_TURN
        rel = pts - axis
        x, y = rel @ ex, rel @ ey
        theta = x / d
        out[sel] = axis + y[:, None] * ey + d * (np.cos(theta)[:, None] * n + np.sin(theta)[:, None] * ex)
    return out


SEPARATION = 0.012
"""Smallest distance [m] between vertices of two panels that are not sewn to each other, once placed
(:func:`separate`): above the simulator's cloth-cloth contact distance (4 mm) and its query (10 mm),
so no two panels start inside each other's contact."""


def separate(points: np.ndarray, mesh: FlatPatternMesh, gap: float = SEPARATION, rounds: int = 6) -> np.ndarray:
    """``points`` [V, 3] with panels that come closer than ``gap`` [m] to another panel moved apart:
    of every two such panels the later one (panel order) moves ``gap`` along its normal (the
    program's placement normal, away from the body), round after round until none is that close
    (stitched vertices and the vertices within ``gap`` of them along their own panel's seam aside:
    they are meant to meet). Two panels laid on the same spot (a cuff on a trouser leg's hem in the
    flat placement) would start inside the simulator's cloth-cloth contact and burst apart."""
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=np.float64).copy()
    pid = mesh.panel_id
    sewn = np.zeros(len(pts), dtype=bool)
    if len(mesh.stitch_pairs):
        sewn[mesh.stitch_pairs.ravel()] = True
    normals = np.array([p.matrix()[:, 2] for p in mesh.pattern.panels])
    for _ in range(rounds):
        free = np.flatnonzero(~sewn)
        tree = cKDTree(pts[free])
        pairs = tree.query_pairs(gap, output_type="ndarray")
        if not len(pairs):
            break
        a, b = pid[free[pairs[:, 0]]], pid[free[pairs[:, 1]]]
        cross = a != b
        if not cross.any():
            break
        later = np.unique(np.maximum(a[cross], b[cross]))
        for k in later:
            pts[pid == k] += gap * normals[k]
    return pts


def place(mesh: FlatPatternMesh, body_vertices: np.ndarray, body_faces: np.ndarray, *, mode: Mode = "wrap",
          clearance: float = CLEARANCE, push: bool = True) -> np.ndarray:
    """3D start positions [V, 3] [m] of ``mesh``'s vertices around the body (module docstring).

    ``body_vertices`` [Vb, 3] and ``body_faces`` [Fb, 3]: the body in its rest pose, the frame the
    pattern's translations and rotations are given in. ``push=False`` skips pushing vertices out
    of the body (to look at the placement itself)."""
    bv = np.asarray(body_vertices, dtype=np.float64)
    bf = np.asarray(body_faces, dtype=np.int64)
    if bv.ndim != 2 or bv.shape[1] != 3 or bf.ndim != 2 or bf.shape[1] != 3:
        raise InputError(f"the body must be vertices [V, 3] and faces [F, 3], got {bv.shape} and {bf.shape}")
    if mode == "flat":
        pts = _flat(mesh)
    elif mode == "wrap":
        pts = _wrap(mesh, bv)
    else:
        raise InputError(f"placement mode must be 'flat' or 'wrap', got {mode!r}")
    pts = _limb(mesh, bv, pts, clearance)
    # two passes: a vertex pushed onto another part of the body (an arm) is pushed again
    for _ in range(2 if push else 0):
        pts = push_out(pts, bv, bf, clearance)
    if push:  # panels pushed onto one another (or placed so) are moved apart, outwards
        pts = separate(pts, mesh)
        pts = push_out(pts, bv, bf, clearance)
    return pts


@dataclass(frozen=True, kw_only=True)
class PlacementReport:
    """How well a placement is set up to be sewn."""

    vertices_inside: int        # vertices inside the body
    min_clearance: float        # [m], negative inside
    stitch_gap_mean: float      # mean 3D distance between sewn vertices [m]
    stitch_gap_max: float       # [m]
    stretch_max: float          # largest relative change of an edge's length from the flat rest state


def placement_report(mesh: FlatPatternMesh, positions: np.ndarray, body_vertices: np.ndarray,
                     body_faces: np.ndarray) -> PlacementReport:
    """:class:`PlacementReport` of ``positions`` [V, 3]."""
    from datagen.geometry.queries import mesh_signed_distance, warp_mesh

    sd = mesh_signed_distance(warp_mesh(np.asarray(body_vertices, float), np.asarray(body_faces)), positions, 10.0)
    gaps = (np.linalg.norm(positions[mesh.stitch_pairs[:, 0]] - positions[mesh.stitch_pairs[:, 1]], axis=1)
            if len(mesh.stitch_pairs) else np.zeros(1))
    e = np.unique(np.sort(np.concatenate([mesh.faces[:, [0, 1]], mesh.faces[:, [1, 2]], mesh.faces[:, [2, 0]]]),
                          axis=1), axis=0)
    rest = np.linalg.norm(mesh.rest_uv[e[:, 0]] - mesh.rest_uv[e[:, 1]], axis=1)
    now = np.linalg.norm(positions[e[:, 0]] - positions[e[:, 1]], axis=1)
    return PlacementReport(vertices_inside=int((sd < 0).sum()), min_clearance=float(sd.min()),
                           stitch_gap_mean=float(gaps.mean()), stitch_gap_max=float(gaps.max()),
                           stretch_max=float(np.abs(now / rest - 1).max()))
