"""Per-frame physics measurements of every scene, and the verdict on a scene that failed.

Measured per scene and frame: maximum and mean stretch (largest principal stretch of each
triangle minus one), garment vertices inside the body (count and deepest depth, by warp's
winding-number query on the posed body), self-intersections (cloth edges crossing a cloth
triangle that shares no vertex with them; every pair of intersecting triangles has at least one),
kinetic energy, whether any value is not finite, and slip: how far the top of the garment (the
band within :data:`SLIP_BAND` of its highest rest point: shoulders and neckline of a top, the
waistband of a skirt or pants) has moved away from the body points that carry it (each vertex's
closest body vertex in the rest pose, posed), as a mean over the band's vertices. A garment that
slides off the body (a dress off the shoulders, pants down the legs) keeps every other metric clean;
slip is what shows it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from datagen.geometry.queries import signed_distance
from datagen.sim.detection_kernels import face_bounds, segment_triangle_parameter

METRIC_NAMES = ("stretch_max", "stretch_mean", "penetration_count", "penetration_depth", "self_intersections",
                "kinetic_energy", "nan", "slip")

SLIP_BAND = 0.03
"""Depth of the garment's top band whose slip is measured (m below its highest rest vertex)."""


@dataclass(frozen=True, kw_only=True)
class FailureThresholds:
    """A scene fails when any frame passes one of these (the reason is recorded).

    Attributes:
        penetration_share: share of garment vertices inside the body.
        penetration_depth: depth of the deepest vertex inside the body [m].
        self_intersections: edge-triangle crossings of the cloth with itself.
        stretch: largest principal stretch minus one (strain blow-up), a cap on the materials' own
            limits (:attr:`~datagen.materials.Material.max_strain`): a scene fails beyond the
            smaller of the two.
        slip: mean distance the garment's top band has moved away from its body anchors [m].
    """

    penetration_share: float = 0.01
    penetration_depth: float = 0.02
    self_intersections: int = 50
    stretch: float = 1.0
    slip: float = 0.06


FAILURE_CODES = ("nan", "penetration", "self-intersection", "slip", "stretch", "seam")
"""What a scene can fail on (:attr:`Failure.code`); a store's ``samples/failure`` numbers them by
``schemas.dataset.FAILURE_NAMES``, which holds every one of them."""


@dataclass(frozen=True)
class Failure:
    """Why a scene failed: ``code`` (one of :data:`FAILURE_CODES`) and a sentence with the figures."""

    code: str
    message: str

    def __post_init__(self):
        if self.code not in FAILURE_CODES:
            raise ValueError(f"failure code {self.code!r} is not one of {FAILURE_CODES}")

    def __str__(self) -> str:
        return f"{self.code}: {self.message}"


@wp.kernel
def _inside(body_meshes: wp.array(dtype=wp.uint64), x: wp.array(dtype=wp.vec3), scene: wp.array(dtype=wp.int32),
            depth: wp.array(dtype=float), order: wp.array(dtype=wp.int32)):
    i = order[wp.tid()]  # thread t: vertex order[t] (SolverVBD.vertex_order)
    p = x[i]
    mesh = body_meshes[scene[i]]
    d = signed_distance(mesh, p, 0.5)
    depth[i] = wp.max(-d, 0.0)


@wp.kernel
def crossings(face_bvh: wp.uint64, x: wp.array(dtype=wp.vec3), scene: wp.array(dtype=wp.int32),
              faces: wp.array2d(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32), out: wp.array(dtype=wp.int32),
              pairs: wp.array2d(dtype=wp.int32), order: wp.array(dtype=wp.int32)):
    """How many triangles of its own scene each cloth edge crosses (``out``), and the first
    ``pairs.shape[1]`` of them (``pairs``, left as they were after the last; width 0: none kept,
    as the per-frame metric does; ``benchmarks/crossing_regions.py`` keeps them). Thread t takes
    edge ``order[t]`` (``SolverVBD.edge_order``)."""
    e = order[wp.tid()]
    a = edges[e, 0]
    b = edges[e, 1]
    qry = wp.bvh_query_aabb(face_bvh, wp.min(x[a], x[b]), wp.max(x[a], x[b]), wp.bvh_get_group_root(face_bvh, scene[a]))
    t = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    n = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    while wp.bvh_query_next(qry, t):
        i = faces[t, 0]
        j = faces[t, 1]
        k = faces[t, 2]
        if i == a or i == b or j == a or j == b or k == a or k == b:
            continue
        if segment_triangle_parameter(x[a], x[b], x[i], x[j], x[k]) >= 0.0:
            if n < pairs.shape[1]:
                pairs[e, n] = t
            n += 1
    out[e] = n


@wp.kernel
def _slip(x: wp.array(dtype=wp.vec3), body: wp.array(dtype=wp.vec3), anchor: wp.array(dtype=wp.int32),
          rest_distance: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = wp.length(x[i] - body[anchor[i]]) - rest_distance[i]


@wp.kernel
def _face_stretch(x: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32), dm_inv: wp.array(dtype=wp.mat22d),
                  out: wp.array(dtype=wp.float64)):
    """Largest principal stretch minus one of every face (float64, +inf where not finite)."""
    f = wp.tid()
    x0 = wp.vec3d(x[faces[f, 0]])
    e1 = wp.vec3d(x[faces[f, 1]]) - x0
    e2 = wp.vec3d(x[faces[f, 2]]) - x0
    d = dm_inv[f]
    f0 = e1 * d[0, 0] + e2 * d[1, 0]
    f1 = e1 * d[0, 1] + e2 * d[1, 1]
    a = wp.dot(f0, f0)
    b = wp.dot(f1, f1)
    c = wp.dot(f0, f1)
    t = wp.float64(0.5) * (a + b) + wp.sqrt(wp.float64(0.25) * (a - b) * (a - b) + c * c)
    s = wp.float64(wp.inf)  # also where t is NaN, which wp.max would drop
    if wp.isfinite(t):
        s = wp.sqrt(wp.max(t, wp.float64(0.0))) - wp.float64(1.0)
    out[f] = s


@wp.kernel
def _vertex_energy(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), mass: wp.array(dtype=wp.float64),
                   energy: wp.array(dtype=wp.float64), bad: wp.array(dtype=wp.int32)):
    """Kinetic energy of every vertex (float64, +inf where not finite) and whether its position
    is not finite."""
    i = wp.tid()
    vi = wp.vec3d(v[i])
    e = wp.float64(0.5) * mass[i] * wp.dot(vi, vi)
    if not wp.isfinite(e):
        e = wp.float64(wp.inf)
    energy[i] = e
    bad[i] = int(not wp.isfinite(x[i]))


def principal_strain(rest_vertices: np.ndarray, faces: np.ndarray, positions: np.ndarray,
                     rest_corners: np.ndarray | None = None) -> np.ndarray:
    """The largest principal strain of every triangle against its rest shape: the largest singular
    value of the deformation gradient F = Ds Dm⁻¹ minus one, [T, F] for ``positions`` [T, V, 3]
    (or [F] for [V, 3]); rest vertices [V, 3] (m), faces [F, 3]. The measure of the physics issue's
    strain figures (``benchmarks/garment_strain.py``).

    ``rest_corners`` [F, 3, 2] (m): a pattern garment's cut, each face's corners in its panel's plane
    (``GarmentMesh.face_uv``, the store's ``rest_uv``), the simulator's own rest shape. Given, Dm is
    taken from it and ``rest_vertices`` is not read: measured against a sewn garment's settled 3D
    template instead, a seam corner that rests squeezed to 0.63 of its cut width reads 58 % when it
    is back at its cut."""
    f = np.asarray(faces)
    if rest_corners is not None:
        c = np.asarray(rest_corners, dtype=np.float64)
        Dm = np.stack([c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]], -1)  # [F, 2, 2]: columns are the two edges
    else:
        X = np.asarray(rest_vertices, dtype=np.float64)
        e1, e2 = X[f[:, 1]] - X[f[:, 0]], X[f[:, 2]] - X[f[:, 0]]
        u = e1 / np.linalg.norm(e1, axis=1, keepdims=True)
        n = np.cross(e1, e2)
        w = np.cross(n / np.linalg.norm(n, axis=1, keepdims=True), u)
        Dm = np.stack([np.stack([(e1 * u).sum(1), (e2 * u).sum(1)], 1),
                       np.stack([(e1 * w).sum(1), (e2 * w).sum(1)], 1)], 1)
    Dinv = np.linalg.inv(Dm)  # [F, 2, 2]
    x = np.asarray(positions, dtype=np.float64)
    one = x.ndim == 2
    x = x[None] if one else x
    d1, d2 = x[:, f[:, 1]] - x[:, f[:, 0]], x[:, f[:, 2]] - x[:, f[:, 0]]
    Fg = np.stack([d1, d2], -1) @ Dinv[None]  # [T, F, 3, 2]
    C = np.swapaxes(Fg, -1, -2) @ Fg  # [T, F, 2, 2]
    a, b, c = C[..., 0, 0], C[..., 1, 1], C[..., 0, 1]
    out = np.sqrt(0.5 * (a + b) + np.sqrt(0.25 * (a - b) ** 2 + c**2)) - 1.0
    return out[0] if one else out


def elastic_energy(host, x: np.ndarray) -> float:
    """The cloth's stored elastic energy [J] at positions ``x`` [N, 3] (m): the membrane's
    orthotropic StVK (with its buckling branch) and lock energies and the hinges' bending energy, as the solver's kernels
    define them, from a model's host arrays (:class:`~datagen.sim.model.ClothHostArrays`).

    With the kinetic energy and the work of gravity it makes the mechanical energy balance that a
    dissipative solver can only lower with a static support (``benchmarks/convergence.py``,
    ``tests/sim/test_physics.py``)."""
    x = np.asarray(x, dtype=np.float64)
    F, D = host.faces, host.dm_inv
    e1, e2 = x[F[:, 1]] - x[F[:, 0]], x[F[:, 2]] - x[F[:, 0]]
    f0 = e1 * D[:, 0, 0, None] + e2 * D[:, 1, 0, None]
    f1 = e1 * D[:, 0, 1, None] + e2 * D[:, 1, 1, None]
    a, b, c = (f0 * f0).sum(1), (f1 * f1).sum(1), (f0 * f1).sum(1)
    g00, g11, g01 = 0.5 * (a - 1), 0.5 * (b - 1), 0.5 * c
    k = host.tri_stiff
    # a compressed direction is on the buckling branch: its stiffness and the coupling x r
    ru = np.where(g00 < 0, k[:, 4], 1.0)
    rv = np.where(g11 < 0, k[:, 4], 1.0)
    psi = (0.5 * ru * k[:, 0] * g00**2 + 0.5 * rv * k[:, 1] * g11**2 + ru * rv * k[:, 2] * g00 * g11
           + 2 * k[:, 3] * g01**2)
    # the lock: kA/2 Σ (λ - λ_lock)² over the principal stretches above λ_lock
    mean, rad = 0.5 * (a + b), np.sqrt(0.25 * (a - b) ** 2 + c**2)
    lam = np.sqrt(np.maximum(np.stack([mean + rad, mean - rad], 1), 0.0))
    over = np.maximum(lam - host.tri_lock[:, :1], 0.0)
    psi = psi + 0.5 * host.tri_lock[:, 1] * (over**2).sum(1)
    energy = float((psi * host.tri_area).sum())
    E = host.edges
    inner = (E[:, 2] >= 0) & (E[:, 3] >= 0)
    if inner.any():
        x0, x1, x2, x3 = (x[E[inner, j]] for j in range(4))
        ed = x1 - x0
        n1, n2 = np.cross(ed, x2 - x0), np.cross(x3 - x0, ed)
        n1 /= np.linalg.norm(n1, axis=1, keepdims=True)
        n2 /= np.linalg.norm(n2, axis=1, keepdims=True)
        eh = ed / np.linalg.norm(ed, axis=1, keepdims=True)
        theta = np.arctan2((np.cross(n1, n2) * eh).sum(1), (n1 * n2).sum(1))
        energy += float((0.5 * host.bend_k[inner] * (theta - host.rest_angle[inner]) ** 2).sum())
    return energy


class Metrics:
    """Measures every scene of a model each frame (arrays on the model's device)."""

    def __init__(self, model):
        self.model = model
        m = model
        with wp.ScopedDevice(m.device):
            self._depth = wp.zeros(m.particle_count, dtype=float)
            self._cross = wp.zeros(m.edge_count, dtype=wp.int32)
            self._no_pairs = wp.zeros((m.edge_count, 0), dtype=wp.int32)
            h = m.host
            # every scene's faces in one BVH, a group per scene (one refit per frame for the batch)
            self._lo, self._hi = wp.zeros(m.face_count, dtype=wp.vec3), wp.zeros(m.face_count, dtype=wp.vec3)
            wp.launch(face_bounds, m.face_count, inputs=[m.rest_positions, m.faces, self._lo, self._hi])
            self._bvh = wp.Bvh(self._lo, self._hi, groups=wp.array(
                h.particle_scene[h.faces[:, 0]].astype(np.int32), dtype=wp.int32))
            # each frame's stretch and kinetic energy are computed here, in float64 like the host
            # arrays they come from: only per-face and per-vertex scalars come back (on a GPU the
            # host's numpy pass over a 252-scene batch took a few hundred ms a frame with the
            # device idle)
            self._dm_inv = wp.array(m.host.dm_inv.astype(np.float64), dtype=wp.mat22d)
            self._mass = wp.array(m.host.mass.astype(np.float64), dtype=wp.float64)
            self._stretch = wp.zeros(m.face_count, dtype=wp.float64)
            self._energy = wp.zeros(m.particle_count, dtype=wp.float64)
            self._bad = wp.zeros(m.particle_count, dtype=wp.int32)
        h = m.host
        self._face_start, self._vertex_start = h.face_range[:, 0], h.particle_range[:, 0]
        self._scene = h.particle_scene
        self._face_scene = self._scene[h.faces[:, 0]]
        self._edge_scene = self._scene[h.edges[:, 0]]
        self._counts = np.bincount(self._scene, minlength=m.scene_count)
        # every scene's stretch gate: the smallest strain limit of its materials
        self._max_strain = np.full(m.scene_count, np.inf)
        np.minimum.at(self._max_strain, self._scene, m.host.max_strain)
        # slip: each vertex's closest body vertex at rest (its scene's body), and the top band
        from scipy.spatial import cKDTree

        X = h.rest_positions
        anchor, rest_d = np.zeros(len(X), dtype=np.int32), np.zeros(len(X))
        self._band = np.zeros(len(X), dtype=bool)
        known = {}  # a batch repeats a few (garment, body) pairs: one tree and query per distinct pair
        for s, (p0, p1) in enumerate(h.particle_range):
            if s in m.scenes_without_body:
                continue  # no body to slip off (its slip is 0)
            b0, b1 = h.body_ranges[s]
            key = (X[p0:p1].tobytes(), h.body_rest[b0:b1].tobytes())
            if key not in known:
                known[key] = cKDTree(h.body_rest[b0:b1]).query(X[p0:p1])
            rest_d[p0:p1], a = known[key]
            anchor[p0:p1] = a + b0
            self._band[p0:p1] = X[p0:p1, 1] > X[p0:p1, 1].max() - SLIP_BAND
        self._band_count = np.bincount(self._scene, weights=self._band, minlength=m.scene_count)
        with wp.ScopedDevice(m.device):
            self._anchor = wp.array(anchor, dtype=wp.int32)
            self._rest_d = wp.array(rest_d.astype(np.float32), dtype=float)
            self._slip = wp.zeros(m.particle_count, dtype=float)

    def measure(self, state, solver) -> dict[str, np.ndarray]:
        """Metrics of every scene [scene_count] for the current state (the solver's body pose)."""
        m, h, S = self.model, self.model.host, self.model.scene_count
        x_wp = state.positions
        with wp.ScopedDevice(m.device):
            wp.launch(_inside, m.particle_count, inputs=[solver.body_ids, x_wp, m.particle_scene, self._depth,
                                                         solver.vertex_order])
            wp.launch(face_bounds, m.face_count, inputs=[x_wp, m.faces, self._lo, self._hi])
            self._bvh.refit()
            wp.launch(crossings, m.edge_count, inputs=[self._bvh.id, x_wp, m.particle_scene, m.faces,
                                                       m.edge_pairs, self._cross, self._no_pairs, solver.edge_order])
            wp.launch(_slip, m.particle_count, inputs=[x_wp, solver.body_sub, self._anchor, self._rest_d, self._slip])
            wp.launch(_face_stretch, m.face_count, inputs=[x_wp, m.faces, self._dm_inv, self._stretch])
            wp.launch(_vertex_energy, m.particle_count, inputs=[x_wp, state.velocities, self._mass, self._energy,
                                                                self._bad])
        depth = self._depth.numpy()
        stretch = self._stretch.numpy()
        area = h.tri_area
        out = {
            # every scene has faces, contiguous in scene order
            "stretch_max": np.maximum.reduceat(stretch, self._face_start),
            "stretch_mean": (np.bincount(self._face_scene, weights=stretch * area, minlength=S)
                             / np.bincount(self._face_scene, weights=area, minlength=S)),
            "penetration_count": np.bincount(self._scene, weights=depth > 0, minlength=S).astype(np.int64),
            "penetration_depth": np.maximum.reduceat(depth, self._vertex_start).astype(np.float64),
            "self_intersections": np.bincount(self._edge_scene, weights=self._cross.numpy(), minlength=S).astype(
                np.int64),
            "kinetic_energy": np.bincount(self._scene, weights=self._energy.numpy(), minlength=S),
            "nan": np.bincount(self._scene, weights=self._bad.numpy(), minlength=S) > 0,
            "slip": np.bincount(self._scene, weights=np.nan_to_num(self._slip.numpy(), nan=np.inf) * self._band,
                                minlength=S) / np.maximum(self._band_count, 1),
        }
        return out

    def failure(self, frame: dict[str, np.ndarray], scene: int, thresholds: FailureThresholds) -> Failure | None:
        """Why scene ``scene`` fails on this frame's metrics, or None."""
        if frame["nan"][scene] or not np.isfinite(frame["kinetic_energy"][scene]):
            return Failure("nan", "positions or velocities are not finite")
        share = frame["penetration_count"][scene] / self._counts[scene]
        if share > thresholds.penetration_share:
            return Failure("penetration", f"{share:.1%} of vertices inside the body "
                           f"(limit {thresholds.penetration_share:.1%})")
        if frame["penetration_depth"][scene] > thresholds.penetration_depth:
            return Failure("penetration", f"a vertex {frame['penetration_depth'][scene] * 1000:.1f} mm inside the "
                           f"body (limit {thresholds.penetration_depth * 1000:.0f} mm)")
        if frame["self_intersections"][scene] > thresholds.self_intersections:
            return Failure("self-intersection", f"{frame['self_intersections'][scene]} edge-triangle "
                           f"crossings (limit {thresholds.self_intersections})")
        if frame["slip"][scene] > thresholds.slip:
            return Failure("slip", f"the garment's top moved {frame['slip'][scene] * 100:.1f} cm off the body "
                           f"points that carry it (limit {thresholds.slip * 100:.0f} cm): it is sliding off the body")
        limit = min(thresholds.stretch, float(self._max_strain[scene]))
        if frame["stretch_max"][scene] > limit:
            return Failure("stretch", f"a triangle stretched by {frame['stretch_max'][scene]:.0%} "
                           f"(limit {limit:.0%})")
        return None
