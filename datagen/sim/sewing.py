"""Sewing a pattern garment on the body at rest: its placed panels closed along their stitches into one
welded garment, then settled under gravity until static.

:func:`sew` takes a garment of the pattern kind (:mod:`datagen.garment.pattern`: flat panels placed
around the body, not welded, ``stitch_pairs`` to be sewn) and the body in its rest pose, and runs:

1. **sewing**, without gravity, body contact and self-contact on, the rest state the panels' flat
   2D shape. How the seams close is :attr:`SewConfig.method`:

   - ``"stitch"`` (default): every stitched vertex is led (held like a pinned vertex, at a target
     moved every frame) towards the centroid of its stitched group by at most
     :attr:`SewConfig.speed` x dt a frame, each target pushed out of the body (to
     :attr:`SewConfig.clearance`), so a seam is led around a limb, not through it; the rest of the cloth follows in
     the solver's step, with body and self contact. Once the largest
     gap is under :attr:`SewConfig.tolerance` the pairs are welded into one vertex at their centroid.
   - ``"weld"``: the pairs are welded into one vertex at their centroid from the first frame
     (GarmentCodeData's way), and the membrane pulls the panels after them.

   A seam that has not closed after :attr:`SewConfig.sew_frames`, or a sewn garment with vertices
   inside the body or crossing itself beyond the gates, fails with :class:`~datagen.sim.metrics.Failure`
   code ``seam``.
2. **settling** of the welded garment under gravity until it is static: 99 % of its vertices moving
   slower than :attr:`SewConfig.static_speed` over a frame, :attr:`SewConfig.static_frames` frames in
   a row (at most :attr:`SewConfig.settle_frames`).

The result (:class:`SewResult`) holds the welded garment (one manifold mesh whose vertices are the
settled positions, its per-corner 2D rest coordinates in ``face_uv``), the weld map from the
placed garment's vertices to the welded ones, and per-frame figures of the two stages.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from datagen.errors import InputError
from datagen.sim.metrics import Failure, FailureThresholds, Metrics
from datagen.sim.model import ClothModelBuilder
from datagen.sim.settings import SolverConfig

log = logging.getLogger(__name__)

__all__ = ["PLACEMENT", "SewConfig", "SewResult", "face_stretch", "folded_faces", "rest_corners", "seam_corner_faces",
           "seam_targets", "sew", "stitch_groups", "weld_garment"]


PLACEMENT = "flat"
"""The placement mode (:func:`datagen.garment.pattern.placement.place`) a garment to be sewn is made
with: panels where the pattern puts them start without crossing each other (A-line skirt seed
1367864806 on the regular body: 0 crossings flat, 304 wrapped; top seed 1: 12 flat, 82 wrapped, the
hood halves), and :func:`sew` closes the larger gaps in a few more frames."""


@dataclass(frozen=True, kw_only=True)
class SewConfig:
    """How a pattern garment is sewn and settled (see the module doc).

    Attributes:
        method: ``"stitch"`` (pull the stitched vertices together, weld once closed) or ``"weld"``
            (weld from the first frame).
        fps: frames per second of both stages [1/s].
        speed: the fastest a stitched vertex is pulled towards its partner [m/s] (``"stitch"``).
        tolerance: the largest stitch gap [m] at which the seams count as closed.
        sew_frames: the most frames sewing may take before the garment fails.
        relax_frames: frames without gravity after welding (the seams' neighbourhood relaxes).
        settle_frames: the most frames of settling under gravity.
        static_speed: the speed [m/s] under which 99 % of a static garment's vertices move over a
            frame (displacement / dt; the largest is no criterion: the solver's velocity of a vertex
            held where body parts meet carries a substep's contact jump, 2.4 m/s on a skirt at rest).
        static_frames: frames in a row the garment must be static to end the settling.
        gravity_scale: gravity while sewing, as a share of the solver's [-] (0: none).
        clearance: how far outside the body a led seam vertex is kept [m] (the placement's, 8 mm).
        lead: ``"together"``: every led vertex goes the same share of its way to its group's target
            each frame (the farthest at ``speed``), the targets the groups' centroids held to the
            seams' rest lengths (:func:`seam_targets`), so all seams close at once; ``"each"``: every
            vertex at ``speed`` to its group's centroid (the rule before; trousers seed 0 tore
            corner triangles by 606 % and crossed 75 times with it, 142 % and 0 led together).

    The solver's settings and the gates are the run's (:func:`sew`'s ``solver`` and ``thresholds``;
    :class:`~datagen.sim.scene.RunConfig` holds this as ``sewing`` beside them).
    """

    method: Literal["stitch", "weld"] = "stitch"
    fps: float = field(default=30.0, metadata={"min": 1.0})
    speed: float = field(default=0.5, metadata={"min": 1e-3})
    tolerance: float = field(default=1e-3, metadata={"min": 1e-6})
    sew_frames: int = field(default=60, metadata={"min": 1})
    relax_frames: int = field(default=5, metadata={"min": 0})
    settle_frames: int = field(default=90, metadata={"min": 0})
    static_speed: float = field(default=0.02, metadata={"min": 0.0})
    static_frames: int = field(default=5, metadata={"min": 1})
    gravity_scale: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0})
    clearance: float = field(default=0.008, metadata={"min": 0.0, "max": 0.05})
    lead: Literal["together", "each"] = "together"

    def __post_init__(self):
        if self.method not in ("stitch", "weld"):
            raise InputError(f"SewConfig.method must be 'stitch' or 'weld', got {self.method!r}")
        if self.lead not in ("together", "each"):
            raise InputError(f"SewConfig.lead must be 'together' or 'each', got {self.lead!r}")
        for f in dataclasses.fields(self):
            lo = f.metadata.get("min")
            hi = f.metadata.get("max")
            v = getattr(self, f.name)
            if (lo is not None and v < lo) or (hi is not None and v > hi):
                raise InputError(f"SewConfig.{f.name} must be in [{lo}, {hi}], got {v}")

    def most_frames(self) -> int:
        """The most frames :func:`sew` runs (sewing, relaxing, settling)."""
        return self.sew_frames + self.relax_frames + self.settle_frames


@dataclass
class SewResult:
    """What :func:`sew` produced.

    Attributes:
        garment: the sewn, settled garment: one welded manifold mesh (``vertices`` the settled
            positions [m], ``face_uv`` [F, 3, 2] each corner's 2D rest coordinate in its panel's
            (weft, warp) frame, ``rest_uv``/``uv``/``vertex_region`` of each welded vertex's first
            panel vertex, ``seam_vertex`` set on the seams), or None when sewing failed before welding.
        weld: the welded vertex of every vertex of the placed garment [V_placed] (int64): stitch
            pair (a, b) of the placed garment is welded vertex ``weld[a] == weld[b]``.
        stitch_pairs: the placed garment's stitch pairs [P, 2] (its vertex ids).
        placed: the placed garment's start positions [V_placed, 3] [m].
        sewn: the welded garment's positions at the end of sewing (before settling) [V, 3] [m].
        gap: the largest stitch gap of every sewing frame [m] [sew frames] (0 after welding).
        seam_stretch: the largest principal strain of the faces at a seam, every frame of both stages.
        corner_stretch: the largest principal strain of the faces at a seam corner (a vertex where
            three or more panel vertices are welded, :func:`seam_corner_faces`), every frame.
        folded: how many faces are folded over their neighbours (:func:`folded_faces`), every frame.
        stretch: the largest principal strain of all faces, every frame of both stages.
        self_intersections: cloth edge-triangle crossings, every frame of both stages.
        penetration: vertices inside the body, every frame of both stages.
        speed: the 99th percentile of the vertices' speeds over the frame (displacement / dt) [m/s],
            every frame of both stages.
        sew_frames: frames sewing took (to the weld), or -1 when the seams did not close.
        settle_frames: frames settling took to be static, or -1 when it did not get there.
        failure: why the garment could not be sewn, or None.
        seconds: wall time [s].
    """

    garment: object
    weld: np.ndarray
    stitch_pairs: np.ndarray
    placed: np.ndarray
    sewn: np.ndarray | None
    gap: np.ndarray
    seam_stretch: np.ndarray
    corner_stretch: np.ndarray
    folded: np.ndarray
    stretch: np.ndarray
    self_intersections: np.ndarray
    penetration: np.ndarray
    speed: np.ndarray
    sew_frames: int
    settle_frames: int
    failure: Failure | None
    seconds: float

    @property
    def ok(self) -> bool:
        return self.failure is None


def stitch_groups(vertex_count: int, pairs: np.ndarray) -> np.ndarray:
    """The welded vertex of every vertex once the stitched ``pairs`` [P, 2] are merged [V] (int64):
    stitched vertices share one id; ids number the groups in order of their smallest vertex."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    graph = coo_matrix((np.ones(len(p)), (p[:, 0], p[:, 1])), shape=(vertex_count, vertex_count))
    _, label = connected_components(graph, directed=False)
    # renumber in order of each group's smallest vertex (stable, independent of scipy's labelling)
    first = np.full(label.max() + 1, vertex_count)
    np.minimum.at(first, label, np.arange(vertex_count))
    rank = np.empty_like(first)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[label].astype(np.int64)


def rest_corners(garment) -> np.ndarray:
    """The 2D rest coordinate of every face corner of a pattern garment [F, 3, 2] [m], in its panel's
    (weft, warp) frame (the warp is (0, 1)): ``face_uv``, which a pattern garment keeps per corner."""
    if garment.rest_uv is None:
        raise InputError("rest_corners needs a garment of the pattern kind (rest_uv set)")
    return np.asarray(garment.uv[garment.faces] if garment.face_uv is None else garment.face_uv, dtype=np.float64)


def face_stretch(host, x: np.ndarray) -> np.ndarray:
    """The largest principal strain of every face of a model's host arrays at positions ``x`` [N, 3]
    against the model's reference shape (Dm⁻¹: the 2D cut of a pattern garment) [F]."""
    F, D = host.faces, host.dm_inv
    x = np.asarray(x, dtype=np.float64)
    e1, e2 = x[F[:, 1]] - x[F[:, 0]], x[F[:, 2]] - x[F[:, 0]]
    f0 = e1 * D[:, 0, 0, None] + e2 * D[:, 1, 0, None]
    f1 = e1 * D[:, 0, 1, None] + e2 * D[:, 1, 1, None]
    a, b, c = (f0 * f0).sum(1), (f1 * f1).sum(1), (f0 * f1).sum(1)
    return np.sqrt(0.5 * (a + b) + np.sqrt(0.25 * (a - b) ** 2 + c**2)) - 1.0


def folded_faces(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Which faces [F] (bool) are folded over their neighbours: the face's normal points against the
    area-weighted normal of the faces sharing an edge with it (a triangle flipped onto its
    neighbour, which the membrane cannot tell from a flat one: it reads FᵀF). ``positions`` [V, 3]
    [m], ``faces`` [F, 3] (consistently oriented)."""
    x = np.asarray(positions, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    n = np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])  # 2 x area along the normal
    a, b = _face_neighbours(f)
    around = np.zeros_like(n)
    np.add.at(around, a, n[b])
    np.add.at(around, b, n[a])
    return np.einsum("ij,ij->i", n, around) < 0.0


def _face_neighbours(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The face pairs (a [H], b [H]) that share an edge (each interior edge once)."""
    f = np.asarray(faces, dtype=np.int64)
    he = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    face = np.tile(np.arange(len(f)), 3)
    key = he[:, 0] * (int(f.max()) + 1) + he[:, 1]
    order = np.argsort(key, kind="stable")
    k = key[order]
    same = np.flatnonzero(k[1:] == k[:-1])
    return face[order[same]], face[order[same + 1]]


def seam_targets(centres: np.ndarray, a: np.ndarray, b: np.ndarray, rest: np.ndarray, iterations: int = 60
                 ) -> np.ndarray:
    """Where the stitched groups are led [G, 3] [m]: their ``centres`` [G, 3], moved so that no
    seam edge between two groups (``a``, ``b`` [H] group ids, ``rest`` [H] its 2D rest length [m])
    is longer than at rest (Jacobi projections of the stretched edges, ``iterations`` rounds).

    A group's centroid alone is a poor target where seams of different gaps meet: a waistband's end
    on a side seam is a group of four whose centroid lies at the side of the body, while the band's
    next vertex, 1 cm from its partner, has its centroid in front; led there, the triangle between
    them stretched 180 % (trousers seed 0, regular body). Projected, the short seam's vertices are
    led round with the corner. Compression is left alone (cloth buckles)."""
    t = np.asarray(centres, dtype=np.float64).copy()
    if not len(a):
        return t
    n = np.bincount(np.concatenate([a, b]), minlength=len(t)).astype(np.float64)[:, None]
    for _ in range(iterations):
        d = t[b] - t[a]
        length = np.linalg.norm(d, axis=1)
        over = np.maximum(length - rest, 0.0) / np.maximum(length, 1e-12)
        if not (over > 1e-3).any():
            break
        move = 0.5 * over[:, None] * d
        acc = np.zeros_like(t)
        np.add.at(acc, a, move)
        np.add.at(acc, b, -move)
        t += acc / np.maximum(n, 1.0)
    return t


def seam_corner_faces(faces: np.ndarray, members: np.ndarray) -> np.ndarray:
    """Which faces [F] (bool) touch a seam corner: a vertex where three or more panel vertices are
    (or will be) welded together (``members`` [V], how many placed vertices each vertex's stitch group
    holds), e.g. a crotch point, an underarm, a waistband's end on a side seam."""
    return (np.asarray(members)[np.asarray(faces)] >= 3).any(1)


def weld_garment(garment, positions: np.ndarray | None = None):
    """The pattern garment welded along its stitches: (welded garment, weld map [V_placed]).

    Every stitched group becomes one vertex at the centroid of its members' ``positions`` [V, 3]
    (default: the garment's vertices); faces are renumbered, their corners keep their own panel's
    2D coordinate (``face_uv``); a welded vertex takes ``uv``, ``rest_uv`` and panel of its first
    member. Openings are those of the welded mesh (the pattern's ``sewn_openings`` names them)."""
    if garment.rest_uv is None:
        raise InputError("weld_garment welds a garment of the pattern kind (rest_uv set)")
    x = np.asarray(garment.vertices if positions is None else positions, dtype=np.float64)
    pairs = np.zeros((0, 2), np.int64) if garment.stitch_pairs is None else np.asarray(garment.stitch_pairs)
    weld = stitch_groups(len(x), pairs)
    n = int(weld.max()) + 1
    count = np.bincount(weld, minlength=n).astype(np.float64)
    welded = np.stack([np.bincount(weld, weights=x[:, k], minlength=n) for k in range(3)], 1) / count[:, None]
    first = np.full(n, len(x))
    np.minimum.at(first, weld, np.arange(len(x)))
    faces = weld[garment.faces]
    bad = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    if bad.any():
        raise InputError(f"welding the stitches collapses {int(bad.sum())} triangles (a stitch joins two vertices of "
                         "one triangle): remesh the pattern finer")
    seam = np.zeros(n, dtype=bool)
    seam[weld[pairs.ravel()]] = True
    loops = {k: _dedup(weld[np.asarray(v)]) for k, v in garment.loops.items()}
    out = type(garment).create(welded, faces, uv=garment.uv[first], vertex_region=garment.vertex_region[first],
                             region_names=garment.region_names, material=garment.material,
                             metadata=dataclasses.replace(garment.metadata), face_uv=rest_corners(garment),
                             extra_seam=seam, loops=loops, rest_uv=garment.rest_uv[first],
                             stitch_pairs=np.zeros((0, 2), np.int64), face_grain=garment.face_grain,
                             pattern=garment.pattern)
    return out, weld


def _dedup(ids: np.ndarray) -> np.ndarray:
    """``ids`` without repeats, first occurrence kept, in order (a loop through a welded seam)."""
    _, first = np.unique(ids, return_index=True)
    return ids[np.sort(first)]


def _build(garment, body_vertices, body_faces, face_part, positions, corners, device):
    b = ClothModelBuilder()
    b.add_cloth(positions, garment.faces, material_name=garment.material, rest_corners=corners)
    b.add_body(body_vertices, body_faces, face_part=face_part)
    return b.finalize(device)


class _Run:
    """One garment on a static body: a model, a solver, states and the per-frame figures."""

    def __init__(self, model, config: SolverConfig, body_vertices, seam_faces, corner_faces, probes=()):
        from datagen.sim.interface import make_solver
        from datagen.sim.state import BodyControl, ClothState

        self.model = model
        self.solver = make_solver("vbd", model, config, probes=probes)
        self.metrics = Metrics(model)
        self.a, self.b = ClothState.from_model(model), ClothState.from_model(model)
        self.control = BodyControl.from_numpy(model, body_vertices)
        self.solver.reset_body(self.control)
        self.seam_faces = seam_faces
        self.corner_faces = corner_faces
        self.x_prev = model.host.rest_positions

    def step(self, dt: float, series: dict) -> np.ndarray:
        self.solver.step(self.a, self.b, self.control, dt)
        self.a, self.b = self.b, self.a
        frame = self.metrics.measure(self.a, self.solver)
        x = self.a.positions.numpy().copy()
        s = face_stretch(self.model.host, x)
        series["stretch"].append(float(s.max()))
        series["seam_stretch"].append(float(s[self.seam_faces].max()) if self.seam_faces.any() else 0.0)
        series["corner_stretch"].append(float(s[self.corner_faces].max()) if self.corner_faces.any() else 0.0)
        series["folded"].append(int(folded_faces(x, self.model.host.faces).sum()))
        series["self_intersections"].append(int(frame["self_intersections"][0]))
        series["penetration"].append(int(frame["penetration_count"][0]))
        moved = np.linalg.norm(x - self.x_prev, axis=1) / dt  # over the frame: a substep's contact jump aside
        series["speed"].append(float(np.percentile(moved, 99)))
        self.x_prev = x
        return x

    def set_positions(self, x: np.ndarray) -> None:
        self.a.positions.assign(np.asarray(x, dtype=np.float32))
        self.x_prev = np.asarray(x, dtype=np.float64)

    def set_targets(self, x: np.ndarray) -> None:
        """Where the held (inactive) vertices are at the end of the next step [N, 3]."""
        for s in (self.a, self.b):
            s.pinned_target.assign(np.asarray(x, dtype=np.float32))


def sew(garment, body_vertices: np.ndarray, body_faces: np.ndarray, *, body_face_part: np.ndarray | None = None,
        config: SewConfig = SewConfig(), solver: SolverConfig | None = None,
        thresholds: FailureThresholds | None = None, device: str | None = None) -> SewResult:
    """Sew the pattern ``garment`` (placed around the body, not welded) on the body at rest
    (``body_vertices`` [B, 3] [m], ``body_faces`` [Fb, 3], its parts ``body_face_part`` [Fb]), then
    settle it under gravity until static; see the module doc. ``solver``: the solver's settings
    (default: the production ones; gravity is that of the settling, scaled by
    ``config.gravity_scale`` while sewing); ``thresholds``: the gates of the sewn garment
    (penetration share, self-intersections, stretch; default: the scenes'). A garment that cannot be sewn comes
    back with ``failure`` set (code ``seam``), never an exception."""
    if getattr(garment, "kind", None) != "pattern":
        raise InputError("sew() sews a garment of the pattern kind (`drape garment make --pattern NAME`)")
    pairs = np.zeros((0, 2), np.int64) if garment.stitch_pairs is None else np.asarray(garment.stitch_pairs)
    if not len(pairs):
        raise InputError("the garment has no stitches to sew (already welded?)")
    t0 = time.perf_counter()
    solver = SolverConfig() if solver is None else solver
    thresholds = FailureThresholds() if thresholds is None else thresholds
    dt = 1.0 / config.fps
    sew_cfg = dataclasses.replace(solver, gravity=tuple(config.gravity_scale * g for g in solver.gravity))
    weld = stitch_groups(garment.vertex_count, pairs)
    n_groups = int(weld.max()) + 1
    member_count = np.bincount(weld, minlength=n_groups)
    corners = rest_corners(garment)
    series = {k: [] for k in ("stretch", "seam_stretch", "corner_stretch", "folded", "self_intersections",
                              "penetration", "speed")}
    gaps: list[float] = []
    failure = None
    x = np.asarray(garment.vertices, dtype=np.float64)
    sewn_frames = -1

    def gap_of(x):
        return float(np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1).max())

    if config.method == "stitch":
        from datagen.geometry.queries import push_out

        seam_v = member_count[weld] > 1
        seam_faces = seam_v[garment.faces].any(1)
        model = _build(garment, body_vertices, body_faces, body_face_part, x, corners, device)
        run = _Run(model, sew_cfg, body_vertices, seam_faces, seam_corner_faces(garment.faces, member_count[weld]))
        # the stitched vertices are led (held like pinned ones, at targets moved each frame); the cloth follows
        active = model.active.numpy().copy()
        active[seam_v] = 0
        model.active.assign(active)
        ids = np.flatnonzero(seam_v)
        # seam edges between stitched groups, with their 2D rest length (the shortest of the group pair's)
        from datagen.geometry.topology import unique_edges

        e = unique_edges(garment.faces)
        e = e[seam_v[e[:, 0]] & seam_v[e[:, 1]]]
        ga, gb = weld[e[:, 0]], weld[e[:, 1]]
        glen = np.linalg.norm(garment.rest_uv[e[:, 0]] - garment.rest_uv[e[:, 1]], axis=1)
        keep = ga != gb
        key = np.minimum(ga, gb)[keep] * n_groups + np.maximum(ga, gb)[keep]
        order = np.lexsort((glen[keep], key))
        first = np.unique(key[order], return_index=True)[1]
        pick = order[first]
        ga, gb, glen = np.minimum(ga, gb)[keep][pick], np.maximum(ga, gb)[keep][pick], glen[keep][pick]
        gaps.append(gap_of(x))
        reach = config.speed * dt
        for f in range(config.sew_frames):
            if gaps[-1] < config.tolerance:
                sewn_frames = f
                break
            centre = np.stack([np.bincount(weld, weights=x[:, k], minlength=n_groups) for k in range(3)], 1)
            centre /= member_count[:, None]
            if config.lead == "together":
                centre = seam_targets(centre, ga, gb, glen)
            centre = push_out(centre, body_vertices, body_faces, config.clearance)  # the seam closes outside the body
            d = centre[weld[ids]] - x[ids]
            dist = np.linalg.norm(d, axis=1, keepdims=True)
            far = float(dist.max())
            if config.lead == "together":  # every seam vertex the same share of its way: all seams close at once
                step = np.full_like(dist, min(1.0, reach / max(far, 1e-12)))
                step[dist < config.tolerance / 4] = 1.0
            else:
                step = np.where(dist < config.tolerance / 4, 1.0, np.minimum(1.0, reach / np.maximum(dist, 1e-12)))
            target = x.copy()
            # each step kept outside the body: a seam led around a limb, not through it
            target[ids] = push_out(x[ids] + d * step, body_vertices, body_faces, config.clearance)
            run.set_targets(target)
            x = run.step(dt, series)
            x[ids] = target[ids]
            gaps.append(gap_of(x))
        else:
            if gaps[-1] < config.tolerance:
                sewn_frames = config.sew_frames
        if sewn_frames < 0:
            failure = Failure("seam", f"a seam is still {1000 * gaps[-1]:.1f} mm open after {config.sew_frames} "
                                      f"frames of sewing (tolerance {1000 * config.tolerance:g} mm)")
        welded, weld_map = weld_garment(garment, x)
        model = _build(welded, body_vertices, body_faces, body_face_part, welded.vertices, rest_corners(welded), device)
        wseam = welded.seam_vertex[welded.faces].any(1)
        wcorner = seam_corner_faces(welded.faces, np.bincount(weld_map, minlength=welded.vertex_count))
        run = _Run(model, sew_cfg, body_vertices, wseam, wcorner)
        relax = config.relax_frames
    else:
        welded, weld_map = weld_garment(garment, x)
        model = _build(welded, body_vertices, body_faces, body_face_part, welded.vertices, rest_corners(welded), device)
        wseam = welded.seam_vertex[welded.faces].any(1)
        wcorner = seam_corner_faces(welded.faces, np.bincount(weld_map, minlength=welded.vertex_count))
        run = _Run(model, sew_cfg, body_vertices, wseam, wcorner)
        gaps.append(gap_of(x))
        sewn_frames = 0
        relax = config.sew_frames  # the membrane closes the welded seams' stretch: until it is under the gate
    xw = welded.vertices
    limit = min(thresholds.stretch, float(garment.material.max_strain))
    for f in range(relax):
        xw = run.step(dt, series)
        gaps.append(0.0)
        if config.method == "weld" and series["seam_stretch"][-1] < limit and series["speed"][-1] < 10 * config.static_speed:
            sewn_frames = f + 1
            break
    else:
        if config.method == "weld" and relax:
            sewn_frames = -1
            failure = failure or Failure("seam", f"the welded seams are not relaxed after {relax} frames (seam "
                                                 f"stretch {series['seam_stretch'][-1]:.0%}, 99th percentile speed "
                                                 f"{series['speed'][-1]:.2f} m/s)")
    sewn = xw.copy()
    failure = failure or _gate(series, welded.vertex_count, thresholds, limit, "after sewing")
    settle_frames = -1
    if failure is None and config.settle_frames:
        run2 = _Run(model, solver, body_vertices, wseam, wcorner)
        run2.set_positions(xw)
        calm = 0
        for f in range(config.settle_frames):
            xw = run2.step(dt, series)
            calm = calm + 1 if series["speed"][-1] < config.static_speed else 0
            if calm >= config.static_frames:
                settle_frames = f + 1
                break
        failure = _gate(series, welded.vertex_count, thresholds, limit, "after settling")
    out = dataclasses.replace(welded, vertices=np.asarray(xw, dtype=np.float64))
    res = SewResult(garment=out, weld=weld_map, stitch_pairs=pairs, placed=np.asarray(garment.vertices), sewn=sewn,
                    gap=np.asarray(gaps), **{k: np.asarray(v) for k, v in series.items()}, sew_frames=sewn_frames,
                    settle_frames=settle_frames, failure=failure, seconds=time.perf_counter() - t0)
    log.info("sewn in %d frames (largest gap %.2f mm), static after %d frames, %.1f s%s", sewn_frames,
             1000 * gaps[-1] if gaps else 0.0, settle_frames, res.seconds, f"; {failure}" if failure else "")
    return res


def _gate(series: dict, vertex_count: int, th: FailureThresholds, stretch_limit: float, when: str) -> Failure | None:
    """The sewn garment's gates at the last frame: no more than the share of vertices inside the
    body, crossings and stretch the scene gates allow."""
    inside = series["penetration"][-1] if series["penetration"] else 0
    if inside > th.penetration_share * vertex_count:
        return Failure("seam", f"{inside} vertices inside the body {when} (a panel on the wrong side of a limb?)")
    cross = series["self_intersections"][-1] if series["self_intersections"] else 0
    if cross > th.self_intersections:
        return Failure("seam", f"{cross} self-crossings {when}")
    s = series["stretch"][-1] if series["stretch"] else 0.0
    if s > stretch_limit:
        return Failure("seam", f"a triangle stretched by {s:.0%} {when}")
    return None
