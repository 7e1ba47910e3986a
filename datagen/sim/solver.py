"""The vertex block descent cloth solver: arranges the launches of :mod:`datagen.sim.kernels`.

``SolverVBD(model, config).step(state_in, state_out, control, dt)`` advances every scene of the
model by ``dt`` (one frame) in ``config.substeps`` substeps of ``config.iterations`` colour sweeps,
with the body moving linearly from the previous control to ``control`` within the frame.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from datagen.errors import InputError, SimulationError

log = logging.getLogger(__name__)


TRAVEL_CHUNK = 256
"""Body vertices per thread of ``projection_kernels.body_parts_moved``'s reductions."""

BIG_BOX = 1.0e30
"""The empty bounding box's corners (+-) before ``projection_kernels.body_parts_moved`` shrinks it onto a part."""


def _part_vertices(body_faces: np.ndarray, face_part: np.ndarray, face_range: np.ndarray, body_ranges: np.ndarray,
                   parts: int):
    """Every (scene, body part)'s vertices (those of its faces; a vertex on a border between parts
    is in each), as one int32 list of global body vertex ids and offsets [S * parts + 1] indexed by
    ``scene * parts + part``; made once per distinct body (a batch repeats one body for many
    garments) and shifted to each scene's vertex range."""
    lists, known = [], {}
    for (f0, f1), (b0, _b1) in zip(np.asarray(face_range).reshape(-1, 2), np.asarray(body_ranges).reshape(-1, 2),
                                   strict=True):
        local, part = np.asarray(body_faces[f0:f1]) - b0, np.asarray(face_part[f0:f1])
        key = (local.tobytes(), part.tobytes())
        if key not in known:
            known[key] = [np.unique(local[part == p]) for p in range(parts)]
        lists.extend(x + b0 for x in known[key])
    offsets = np.zeros(len(lists) + 1, dtype=np.int32)
    offsets[1:] = np.cumsum([len(x) for x in lists])
    return (np.concatenate(lists).astype(np.int32) if lists else np.zeros(0, np.int32)), offsets


def _reference_vertices(body_rest: np.ndarray, ranges: np.ndarray, scene_count: int) -> np.ndarray:
    """Per scene the body vertex nearest its rest body's centroid (global index; -1 for a scene
    without a body): the origin whose moves ``projection_kernels.may_have_entered`` subtracts, so a body that
    walks on moves its cloth's bound only by how its parts move about it."""
    ref = np.full(scene_count, -1, dtype=np.int32)
    for s, (b0, b1) in enumerate(np.asarray(ranges).reshape(-1, 2)[:scene_count]):
        if b1 > b0:
            pts = np.asarray(body_rest[b0:b1], dtype=np.float64)
            ref[s] = b0 + int(np.argmin(np.linalg.norm(pts - pts.mean(0), axis=1)))
    return ref


@dataclass(frozen=True, kw_only=True)
class SolverConfig:
    """Solver settings (SI units).

    Attributes:
        substeps: substeps per step (frame).
        iterations: colour sweeps per substep.
        gravity: gravitational acceleration [m/s²], Y up.
        air_drag: linear air drag per area [kg/(m² s)].
        body_stiffness: body contact stiffness k_c [N/m].
        body_margin: extra body contact distance beyond the material thickness [m].
        body_query: body contact search distance [m].
        self_collision: vertex-triangle and edge-edge contacts of the cloth with itself.
        self_radius: cloth-cloth contact distance [m].
        self_stiffness: cloth-cloth contact stiffness [N/m].
        self_friction: cloth-cloth Coulomb friction coefficient.
        self_query: cloth-cloth search distance [m]: a vertex with a non-neighbouring cloth
            primitive closer than this moves at most 0.4x that distance per substep.
        self_bound_floor: distance to the nearest cloth primitive below which the move bound stops
            shrinking [m] (primitives that already touch must not freeze a vertex). At most the
            contact registration distance 1.5 x ``self_radius``: pairs farther apart than that are
            not contacts, and each side moves at most 0.4x their distance, so they cannot cross;
            pairs closer than it are contacts and their forces keep them apart. The default is that
            largest safe floor: with a floor of 1 mm, a vertex caught in a fold moved at most 0.4 mm
            per detection, could not follow the body, and its triangles tore (T-shirt walk: stretch
            500 % at the start of the ramp, then a tangle of 1,700 crossings; with 6 mm: none).
        bound_fraction: the share of its distance to the nearest non-neighbouring cloth primitive
            that a vertex may move between two detections (below 0.5: two primitives that both
            move that far towards each other still do not meet).
        friction_velocity: velocity below which friction is smoothed (static) [m/s].
        contact_capacity: initial contacts stored per vertex, triangle and edge (grows on demand).
        chebyshev_rho: spectral radius estimate for Chebyshev acceleration of the sweeps (0: off).
        chebyshev_contacts: whether the acceleration also extrapolates vertices that have cloth-cloth
            (vertex-triangle) contacts; False leaves them at their sweep's result (a walking T-shirt's
            sweeps then converge further; ``docs/simulator.md``, "How many sweeps").
        chebyshev_body_contacts: the same for vertices in contact with the body.
        global_iterations: conjugate-gradient iterations of the global Newton step that starts every
            substep (:mod:`datagen.sim.newton_kernels`; 0: off, the sweeps alone). The sweeps carry
            a load one vertex per sweep; woven cloth needs it carried across the garment at once.
        body_projection: at the end of every substep, move vertices that ended inside the body
            (winding-number test) out to its surface and take their inward velocity (see
            ``projection_kernels.test_inside_body`` and ``move_out_of_body``).
        projection_skip: let the projection's inside test skip a vertex that provably cannot have
            entered the body since its last test (its distance from the body then exceeds how far it
            and the body have moved since; ``projection_kernels.may_have_entered``). The result is the same as
            testing every vertex (tested bitwise); off only to measure what it saves.
        projection_reach: how far the projection's search for a way out (where the closest face's
            normal does not lead outside) may move a vertex [m].
        projection_accuracy: β of the projection's winding-number test (warp's fast winding number: a
            subtree of the body's tree counts as its dipole when the point lies farther than β times
            its radius). 1.25, not warp's 2: on 10.8 million points within 3 or 10 mm of the
            default body posed in nine motions (walk, squat, sit_stand, lunge, box, dance_disco,
            kick, bend_forward, arm_circles) every inside-or-out answer is β = 2's, in 0.47x the time
            on the CPU (``benchmarks/winding_accuracy_probe.py``); at β = 1 one answer differed, at
            0.75 a fifth. On an H100 the projection takes 0.45x its time at β = 2, the frame 0.83-0.86x
            (``docs/simulator.md``). The penetration metric keeps β = 2, so it judges the projection
            independently.
        untangle_step: how far a vertex of a crossing of the cloth with itself moves per untangling
            iteration [m] (0: off; at most ``self_radius``). Before each substep every edge that
            crosses a triangle pushes the two apart along the gradient that shortens their
            intersection contour (:mod:`datagen.sim.untangle_kernels`). The contacts stay on:
            turning them off between the vertices of crossings let a tangle spread (T-shirt dance:
            248 crossings against 22 without untangling).
        untangle_iterations: untangling iterations before each substep (each a refit of the cloth's
            triangle tree and an edge query). A crossing deeper than one step is pushed back by the
            contacts of the next substep, which hold each side where it is: with one 2 mm
            iteration a vertex poked 1.8 mm through the back of a T-shirt stayed there for 250
            frames; with four, the first 84 frames of the T-shirt walk and dance cross nowhere
            (the kernels alone clear that state's 20 crossings in four iterations).
        detection_interval: sweeps between cloth-cloth detections within a substep (0: once per
            substep); each detection renews the move bounds from the current positions, so cloth
            pressed between the body and other cloth can follow a fast body. Every 5 sweeps (four
            detections a substep, the default since the fourth session of 2026-11-28): the six long
            runs pass with the crossings and strain of every 4 (at most 10 / 25 / 3 / 0 / 4 / 0
            crossings against 14 / 25 / 4 / 3 / 4 / 0, strain p99 within 0.6 points) and a frame at
            64 scenes takes 291.9 ms instead of 312.0 (H100, one run). Every 7 (three a substep):
            273.2 ms, all pass but the dress walk crosses 13 times instead of 4; every 10 (two):
            255.4 ms, the pants walk tears (308 % stretch at frame 125). Every 4 had ended the six
            runs as every 2 in 0.76x the time (H200). ``docs/simulator.md``.
        body_friction: Coulomb friction with the body (``kernels.body_stick_slip``); off only to
            diagnose what it does.
        friction_pressure: the largest body contact pressure that friction sees [Pa] (its normal
            force per vertex is at most this x the vertex area). Where the skinned body overlaps
            itself (the armpit), the penalty's normal force on cloth squeezed into the overlap
            grows without bound (50 N per vertex for 5 mm) and would pin it while the arm drags its
            neighbours on. An elastic waistband presses about 1-3 kPa (clothing pressure above
            4 kPa is felt as uncomfortable); the weight of a garment about 100 Pa. At 1 kPa the
            pants on their waistband hold still; at 300 Pa they crept down 1.5 cm/s; at 3 kPa a
            patch sliding down a 35° plane dug in its front edge and lifted 12 mm.
        global_friction: body friction in the global step: ``lagged`` (a Coulomb force smoothed
            below the vertex's slide along the body over the last substep, so a vertex that slid is
            held with μλ at that slide and one that stuck is held stiffly), ``stiff`` (smoothed
            below ``friction_velocity`` x h only: a vertex in contact follows the body in the
            linearised step with whatever force that takes) or ``off``. See
            ``newton_kernels.vertex_force_diagonal``.
        colour_hinge_wings: whether the sweeps' colouring also separates a hinge's two wing vertices
            (the corners opposite its edge, which share only the bending stencil). False (the
            default) colours by the triangles alone: a wing then reads the other wing's position
            from the sweep before (a colour's results are written to a copy, so nothing depends on
            thread order), and the walking T-shirt takes 5 colours instead of 8, so 5 sweep
            launches instead of 8: on an H100 the sweeps take 121 ms a frame instead of 181 at 64
            scenes, and the six long runs, the physics tests and Cusick pass (``docs/simulator.md``).
        register_caps: which kernels run as their register-capped copies
            (``detection_kernels.register_capped``: the same code under CUDA's
            ``__launch_bounds__``, with more threads in flight and a few spills; bitwise the same
            results on the CPU, which ignores the bound; on CUDA not yet compared bitwise):
            ``none``; ``detection`` (the default: the two cloth-cloth queries and the projection's
            inside test, 94 -> 80, 72 -> 64 and 80 -> 64 registers; on an H100 the frame takes
            0.97x at 64 scenes and 0.94x at 256). Capping the old one-thread-per-vertex sweep
            kernel too (116 -> 80 registers with spills) was slower, 1.02x and 1.11x, and is gone
            with that kernel (``sweep_lanes``).
        sweep_lanes: threads per vertex in the sweeps on a GPU (:mod:`datagen.sim.sweep_kernels`:
            this many threads of a warp share a vertex's triangles, hinges, contact lists and body
            planes and add their sums by shuffles in a fixed order). A power of two up to 32; on a
            CPU one thread walks each vertex whatever this says. On an H100 at 64 scenes (with
            ``coherent_order``) a sweep launch takes 100 us at 4 lanes, 119 at 1 (the one-thread
            kernel: 112), 113 at 8 and 168 at 16; the frame 311.3 ms against 329.3 for the
            one-thread kernel without ``coherent_order``, in one run (``docs/simulator.md``).
        coherent_order: launch the tree queries (the cloth-cloth detection, the body contact
            query, the projection, the untangling, and the per-frame penetration and crossing
            metrics) with one thread per vertex or edge in Morton order of the rest shape
            (``model.launch_order``), and sort every sweep colour the same way, so the threads of
            a warp hold cloth near each other; False launches them in index order, in which a
            garment's 32 consecutive vertices span most of it. The results are the same either
            way, bitwise (each thread writes its own element; contact lists are sorted, distances
            are minima and the untangling's pushes integer sums; tested). On an H100 at 64 scenes
            it takes the detection from 105.2 to 98.4 ms a frame and the projection from 40.0 to
            34.2 (``docs/simulator.md``).
        cuda_graph: on a CUDA device, capture a step's launches (thousands per frame) once as a
            CUDA graph and replay it: the same kernels in the same order, without Python's
            per-launch cost. Off, or on a CPU, every launch is made from Python.
    """

    substeps: int = field(default=10, metadata={"min": 1, "max": 200})
    iterations: int = field(default=20, metadata={"min": 1, "max": 200})
    gravity: tuple[float, float, float] = (0.0, -9.81, 0.0)
    air_drag: float = 0.02
    body_stiffness: float = 1.0e4
    body_margin: float = 0.002
    body_query: float = 0.03
    self_collision: bool = True
    self_radius: float = 0.004
    self_stiffness: float = 2.0e3
    self_friction: float = 0.2
    self_query: float = 0.01
    self_bound_floor: float = 0.006
    bound_fraction: float = 0.45
    friction_velocity: float = 1.0e-3
    contact_capacity: int = 16
    chebyshev_rho: float = 0.7
    chebyshev_contacts: bool = True
    chebyshev_body_contacts: bool = True
    detection_interval: int = 5
    body_projection: bool = True
    untangle_step: float = 0.002
    untangle_iterations: int = field(default=4, metadata={"min": 1, "max": 20})
    projection_skip: bool = True
    projection_reach: float = 0.1
    projection_accuracy: float = 1.25
    body_friction: bool = True
    friction_pressure: float = 1000.0
    cuda_graph: bool = True
    global_iterations: int = field(default=20, metadata={"min": 0, "max": 1000})
    global_friction: str = "lagged"
    colour_hinge_wings: bool = False
    register_caps: str = "detection"
    sweep_lanes: int = field(default=4, metadata={"min": 1, "max": 32})
    coherent_order: bool = True

    def __post_init__(self):
        for name in ("substeps", "iterations"):
            if int(getattr(self, name)) < 1:
                raise InputError(f"solver {name} must be >= 1, got {getattr(self, name)}")
        for name in ("body_stiffness", "body_query", "self_radius", "self_stiffness", "self_query",
                     "friction_velocity", "self_bound_floor", "friction_pressure"):
            if not float(getattr(self, name)) > 0:
                raise InputError(f"solver {name} must be > 0, got {getattr(self, name)}")
        if self.self_query <= self.self_radius:
            raise InputError(f"self_query ({self.self_query}) must exceed self_radius ({self.self_radius})")
        if not 0.0 <= float(self.untangle_step) <= self.self_radius:
            raise InputError(f"untangle_step must be in [0, self_radius = {self.self_radius}] m (0: off), got "
                             f"{self.untangle_step}: a longer jump can carry cloth through other cloth")
        if int(self.untangle_iterations) < 1:
            raise InputError(f"untangle_iterations must be >= 1, got {self.untangle_iterations}")
        if self.register_caps not in REGISTER_CAPS:
            raise InputError(f"register_caps must be one of {', '.join(REGISTER_CAPS)}, got {self.register_caps!r}")
        if int(self.sweep_lanes) not in (1, 2, 4, 8, 16, 32):
            raise InputError(f"sweep_lanes must be a power of two from 1 to 32 (a warp), got {self.sweep_lanes}")
        if self.global_friction not in GLOBAL_FRICTION:
            raise InputError(f"global_friction must be one of {', '.join(GLOBAL_FRICTION)}, got {self.global_friction!r}")
        if not 0.0 < self.bound_fraction < 0.5:
            raise InputError(f"bound_fraction must be in (0, 0.5), got {self.bound_fraction}: at 0.5 or more two "
                             "cloth primitives moving towards each other could meet between detections")
        if not float(self.projection_accuracy) >= 1.0:
            raise InputError(f"projection_accuracy must be >= 1, got {self.projection_accuracy}: below 1 warp's "
                             "winding number counts a body part as its dipole from inside its bounding sphere, and "
                             "its inside-or-out answer breaks")
        if self.self_bound_floor > 1.5 * self.self_radius + 1e-12:
            raise InputError(f"self_bound_floor ({self.self_bound_floor}) must be at most 1.5 x self_radius "
                             f"({1.5 * self.self_radius:g}), the distance within which cloth pairs are contacts")


GLOBAL_FRICTION = {"off": 0, "stiff": 1, "lagged": 2}
"""``SolverConfig.global_friction`` values and the code the global step's kernel takes."""

_CAPPED_DETECTION = ("detect_vertex_triangle", "detect_edge_edge", "test_inside_body")
REGISTER_CAPS = {"none": (), "detection": _CAPPED_DETECTION}
"""``SolverConfig.register_caps`` values and the kernels each runs as their register-capped copies."""

REFIT_STREAMS = 16
"""CUDA streams that the body meshes' refits are spread over."""


def refit_on_streams(meshes, streams, device) -> None:
    """Refit warp meshes (or BVHs), spread round ``streams`` that first wait for ``device``'s current
    stream and that it then waits for in turn (the refits are independent, so a captured CUDA
    graph runs them side by side); with no streams, one after another on the current stream."""
    import warp as wp

    if not streams:
        for mesh in meshes:
            mesh.refit()
        return
    main = wp.get_stream(device)
    for stream in streams:
        stream.wait_stream(main)
    for k, mesh in enumerate(meshes):
        with wp.ScopedStream(streams[k % len(streams)], sync_enter=False):
            mesh.refit()
    for stream in streams:
        main.wait_stream(stream)


class SolverVBD:
    """Vertex block descent (Chen et al. 2024) for cloth against moving bodies and itself."""

    def __init__(self, model, config: SolverConfig | None = None, *, probes: tuple = ()):
        """``probes``: :class:`~datagen.sim.probes.SolverProbe` objects the solver calls at the points
        that protocol lists (none in production; with any, a step is launched directly, never
        from a captured CUDA graph); the attribute ``probes`` may be set later too."""
        import warp as wp

        from datagen.sim import detection_kernels as D
        from datagen.sim import kernels as K
        from datagen.sim import projection_kernels as PK
        from datagen.sim import sweep_kernels as S
        from datagen.sim.model import launch_order, triangle_colours

        self.model = model
        self.config = config or SolverConfig()
        self.probes = tuple(probes)
        self.K, self.D, self.PK, self.S = K, D, PK, S
        capped = REGISTER_CAPS[self.config.register_caps]
        # the kernels launched below, each its register-capped copy where the config asks for it
        home = {"detect_vertex_triangle": D, "detect_edge_edge": D, "test_inside_body": PK}
        self._kernel = {name: getattr(home[name], name + ("_capped" if name in capped else "")) for name in home}
        m = model
        n, nf, ne, nb = m.particle_count, m.face_count, m.edge_count, m.body_vertex_count
        with wp.ScopedDevice(m.device):
            z3 = lambda k: wp.zeros(k, dtype=wp.vec3)
            self.x_prev, self.y, self.x_tmp = z3(n), z3(n), z3(n)
            h = m.host
            cols = h.colours if self.config.colour_hinge_wings else triangle_colours(h)  # the sweeps' colours
            if self.config.coherent_order:  # threads of one warp on cloth near each other (launch_order)
                vertex_order = launch_order(h.rest_positions, h.particle_range)
                edge_order = launch_order(np.asarray(h.rest_positions)[np.asarray(h.edge_pairs)].mean(1), h.edge_range)
                rank = np.empty(n, dtype=np.int64)
                rank[vertex_order] = np.arange(n)
                cols = [np.asarray(c)[np.argsort(rank[np.asarray(c)], kind="stable")] for c in cols]
            else:
                vertex_order, edge_order = np.arange(n, dtype=np.int32), np.arange(ne, dtype=np.int32)
            self.vertex_order = wp.array(vertex_order, dtype=wp.int32)
            self.edge_order = wp.array(edge_order, dtype=wp.int32)
            self.colours = [wp.array(np.asarray(c, dtype=np.int32), dtype=wp.int32) for c in cols]
            self.x_nm1, self.x_nm2 = z3(n), z3(n)
            self.bound = wp.zeros(n, dtype=float)
            self.min_dist = wp.zeros(n, dtype=float)
            self.friction_used = wp.zeros(n, dtype=float)
            self.slip = wp.zeros(n, dtype=float)
            self.v_old = z3(n)
            self.scene_frozen = wp.zeros(m.scene_count, dtype=wp.int32)  # 1: frozen (:meth:`freeze`)
            if self.config.global_iterations:  # the global step's vectors, blocks and per-scene scalars
                self.cg_force, self.cg_r, self.cg_z, self.cg_p, self.cg_q, self.cg_d = (z3(n) for _ in range(6))
                self.cg_diag_other, self.cg_diag_el, self.cg_inverse = (wp.zeros(n, dtype=wp.mat33) for _ in range(3))
                self.cg_rz, self.cg_rz_new, self.cg_pq = (wp.zeros(m.scene_count, dtype=wp.float64) for _ in range(3))
                # each element's share of a product at its corners, gathered per vertex
                self.cg_face_part = wp.zeros((nf, 3), dtype=wp.vec3)
                self.cg_edge_part = wp.zeros((ne, 4), dtype=wp.vec3)
                # each element's linearisation at the global step's x (newton_kernels.*_linearise)
                self.cg_face_frame = wp.zeros((nf, 2), dtype=wp.vec3)
                self.cg_face_law = wp.zeros(nf, dtype=wp.vec4)
                self.cg_face_stress = wp.zeros(nf, dtype=wp.mat22)
                self.cg_face_scale = wp.zeros(nf, dtype=float)
                self.cg_hinge_grad = wp.zeros((ne, 4), dtype=wp.vec3)
                self.cg_hinge_scale = wp.zeros(ne, dtype=float)
                self.particle_range = wp.array(np.asarray(m.host.particle_range, dtype=np.int32).reshape(-1, 2),
                                               dtype=wp.int32)  # each scene's vertices, for its dot products
            P = m.body_part_count
            self.body_lambda = wp.zeros((n, P), dtype=float)
            # copies of what a step carries over from the last besides the state, for a redo
            self._lagged_saved = (wp.zeros((n, P), dtype=float), z3(n), wp.zeros(n, dtype=float))
            self.body_has = wp.zeros((n, P), dtype=wp.int32)
            self.body_point, self.body_normal, self.body_disp = (wp.zeros((n, P), dtype=wp.vec3) for _ in range(3))
            self.body_radius = wp.array(m.host.thickness.astype(np.float32) + self.config.body_margin, dtype=float)
            self.body_start = wp.clone(m.body_rest)
            self.body_prev_sub, self.body_sub = z3(nb), wp.clone(m.body_rest)
            self.x_det = wp.clone(m.rest_positions)
            self.edge_lo, self.edge_hi = z3(ne), z3(ne)
            wp.launch(D.edge_bounds, ne, inputs=[m.rest_positions, m.edge_pairs, 0.0, self.edge_lo, self.edge_hi])
            self.face_lo, self.face_hi = z3(nf), z3(nf)
            wp.launch(D.face_bounds, nf, inputs=[m.rest_positions, m.faces, self.face_lo, self.face_hi])
            # one body mesh per scene over views of the flat arrays (its closest-point, box and
            # winding queries have no group root in warp 1.19; the contact search takes every
            # part's closest point from one box query of it, so no part needs a tree of its own);
            # the cloth's faces and edges are each one BVH with a group per scene: one refit per
            # detection for the whole batch, queries start at their scene's group root, and the
            # pair lists are sorted, so nothing depends on the batch
            h = m.host
            self.body_meshes = []
            for s in range(m.scene_count):
                b0, b1 = h.body_ranges[s]
                bf0, bf1 = h.body_face_range[s]
                self.body_meshes.append(wp.Mesh(points=self.body_sub[int(b0):int(b1)], indices=wp.array(
                    (h.body_faces[bf0:bf1] - b0).astype(np.int32).ravel()), support_winding_number=True))
            self.body_ids = wp.array([x.id for x in self.body_meshes], dtype=wp.uint64)
            # on CUDA the meshes' refits (a few short launches each, every substep) go round several
            # streams, so a captured graph runs them side by side instead of one after another
            dev = wp.get_device(m.device)
            self._on_cuda = dev.is_cuda
            meshes = len(self.body_meshes)
            self._refit_streams = [wp.Stream(dev) for _ in range(min(REFIT_STREAMS, meshes))] if dev.is_cuda else []
            scene_of = h.particle_scene
            self.face_bvh = wp.Bvh(self.face_lo, self.face_hi,
                                   groups=wp.array(scene_of[h.faces[:, 0]].astype(np.int32), dtype=wp.int32))
            self.edge_bvh = wp.Bvh(self.edge_lo, self.edge_hi,
                                   groups=wp.array(scene_of[h.edges[:, 0]].astype(np.int32), dtype=wp.int32))
            self.vt_count = wp.zeros(n, dtype=wp.int32)
            self.tv_count = wp.zeros(nf, dtype=wp.int32)
            self.ee_count = wp.zeros(ne, dtype=wp.int32)
            self.needed = wp.zeros(3, dtype=wp.int32)
            self.projected = wp.zeros(m.scene_count, dtype=wp.int32)
            self.projection_inside = wp.zeros(n, dtype=wp.int32)  # the projection's first pass found it inside
            # the inside test's finds, for the move out (projection_kernels.test_inside_body, move_out_of_body)
            self.projection_pending = wp.zeros(n, dtype=wp.int32)
            self.projection_face = wp.zeros(n, dtype=wp.int32)
            self.projection_uv = wp.zeros(n, dtype=wp.vec2)
            # what lets the projection's first pass skip a vertex that cannot have entered the body
            # since its last test (projection_kernels.may_have_entered): per scene a reference body vertex (the
            # one nearest the rest body's centroid; -1 without a body), and per body part its
            # vertices, its bounding box and its accumulated largest move relative to the reference;
            # per cloth vertex where its last test found it outside (relative to the reference) and
            # how far from each part
            P = m.body_part_count
            self.body_ref = wp.array(_reference_vertices(h.body_rest, h.body_ranges, m.scene_count), dtype=wp.int32)
            part_vertices, part_offsets = _part_vertices(h.body_faces, h.body_face_part, h.body_face_range,
                                                        h.body_ranges, P)
            self.part_vertices = wp.array(part_vertices, dtype=wp.int32)
            self.part_offsets = wp.array(part_offsets, dtype=wp.int32)
            self._travel_chunks = max(1, -(-int(np.diff(part_offsets).max(initial=0)) // TRAVEL_CHUNK))
            self.body_travel = wp.zeros((m.scene_count, P), dtype=float)
            self.body_step_max = wp.zeros((m.scene_count, P), dtype=float)
            self.part_lo, self.part_hi = (wp.zeros((m.scene_count, P), dtype=wp.vec3) for _ in range(2))
            self.check_x = z3(n)
            self.check_travel = wp.zeros((n, P), dtype=float)
            self.check_bound = wp.zeros((n, P), dtype=float)  # [:, 0] 0: test at the next pass
            self.projection_skipped = wp.zeros(n, dtype=wp.int32)  # skipped by the last first pass
            self.untangle_push = wp.zeros((n, 3), dtype=wp.int32)  # untangle_kernels.PUSH_SCALE units
            self.untangle_hits = wp.zeros(n, dtype=wp.int32)  # crossings each vertex is part of
            self.untangle_edges = wp.zeros(ne, dtype=wp.int32)  # edges that crossed at the first iteration
        self._build_groups()
        self._allocate_contacts(self.config.contact_capacity)
        self.contact_growths = 0
        self._graphs: dict[tuple, tuple] = {}
        """Captured CUDA graphs of a step, by (id(state), id(control), dt, capacity): (graph, state,
        control), the two kept alive because the graph reads their arrays (at most 9 kept)."""

    def _build_groups(self) -> None:
        """The per-vertex kernels' argument groups (:mod:`datagen.sim.kernel_groups`) over the model's
        and the solver's arrays, made once: the cloth-cloth lists' group is remade when they grow
        (:meth:`_allocate_contacts`), the substep's values are set once a step (:meth:`_step`)."""
        from datagen.sim import kernel_groups as G

        m, c = self.model, self.config
        self.verts = G.Vertices()
        self.verts.mass, self.verts.active, self.verts.damping = m.mass, m.active, m.damping
        self.verts.friction, self.verts.area = m.friction, m.vertex_area
        self.membrane = G.Membrane()
        self.membrane.faces, self.membrane.dm_inv, self.membrane.area = m.faces, m.dm_inv, m.tri_area
        self.membrane.stiffness, self.membrane.lock = m.tri_stiff, m.tri_lock
        self.membrane.v2f_offsets, self.membrane.v2f = m.v2f_offsets, m.v2f
        self.bending = G.Bending()
        self.bending.edges, self.bending.rest_angle, self.bending.stiffness = m.edges, m.rest_angle, m.bend_k
        self.bending.v2e_offsets, self.bending.v2e = m.v2e_offsets, m.v2e
        self.body = G.BodyContact()
        self.body.has, self.body.point, self.body.normal = self.body_has, self.body_point, self.body_normal
        self.body.disp, self.body.radius, self.body.lam = self.body_disp, self.body_radius, self.body_lambda
        self.body.stiffness = c.body_stiffness
        self.body.friction = int(c.body_friction)
        self.body.global_friction = GLOBAL_FRICTION[c.global_friction] if c.body_friction else 0
        self.body.friction_pressure = c.friction_pressure
        self.body.friction_used = self.friction_used
        self.substep = G.Substep()
        self.substep.x_prev, self.substep.x_det, self.substep.inertia_target = self.x_prev, self.x_det, self.y
        self.substep.bound, self.substep.slip = self.bound, self.slip

    def _allocate_contacts(self, cap: int) -> None:
        import warp as wp

        from datagen.sim.kernel_groups import SelfContact

        m, c = self.model, self.config
        with wp.ScopedDevice(m.device):
            self.capacity = int(cap)
            self.vt_tri = wp.zeros((m.particle_count, cap), dtype=wp.int32)
            self.tv_vert = wp.zeros((m.face_count, cap), dtype=wp.int32)
            self.ee_edge = wp.zeros((m.edge_count, cap), dtype=wp.int32)
        g = self.self_contact = SelfContact()
        g.vt_count, g.vt_tri, g.tv_count, g.tv_vert = self.vt_count, self.vt_tri, self.tv_count, self.tv_vert
        g.ee_count, g.ee_edge = self.ee_count, self.ee_edge
        g.radius, g.stiffness, g.friction = c.self_radius, c.self_stiffness, c.self_friction

    def freeze(self, state, scene: int) -> None:
        """Stop simulating scene ``scene`` (one that failed): from the next step its vertices are
        inactive like pinned vertices, held where ``state`` has them, at rest, and its cloth-cloth
        contacts are no longer looked for. The sweeps, the global step, the body contact and
        projection and the detection skip it; the other scenes of the batch are unchanged (a scene
        never reads another's vertices)."""
        idx = np.flatnonzero(self.model.host.particle_scene == scene)
        if not len(idx):
            return
        frozen = self.scene_frozen.numpy().copy()
        frozen[scene] = 1
        self.scene_frozen.assign(frozen)
        active = self.model.active.numpy().copy()
        active[idx] = 0
        self.model.active.assign(active)
        x = state.positions.numpy()
        target = state.pinned_target.numpy().copy()
        target[idx] = x[idx]
        state.pinned_target.assign(target)
        v = state.velocities.numpy().copy()
        v[idx] = 0.0
        state.velocities.assign(v)

    def reset_body(self, control) -> None:
        """Take ``control`` as the body's pose at the start of the next step (no motion in between)."""
        self.body_start.assign(control.body_vertices)
        self._forget_checks()

    def _forget_checks(self) -> None:
        """The body jumped (or a step is redone from an earlier body): no vertex may skip the
        projection's next inside test on what an earlier one found."""
        self.check_bound.zero_()

    def place_body(self, control) -> None:
        """Put the body at ``control``'s pose now: the start of the next step and the collider that
        contacts and metrics read (its meshes refitted), as if a step had just ended there."""
        self.reset_body(control)
        self.body_sub.assign(control.body_vertices)
        self._refit_body()

    def _refit_body(self) -> None:
        """Refit every body mesh to ``body_sub`` (on CUDA spread over streams that wait for the
        current stream's work and that it waits for in turn: the refits are independent)."""
        refit_on_streams(self.body_meshes, self._refit_streams, self.model.device)

    def step(self, state_in, state_out, control, dt: float) -> None:
        """Advance by ``dt`` [s]; ``state_in`` is read, ``state_out`` written (they may be the same).

        Contact buffers that overflow are grown and the step is redone, so no contact is dropped.
        """
        import warp as wp

        if not dt > 0:
            raise InputError(f"time step must be > 0, got {dt}")
        # what a step carries over from the last one besides the state (the body's normal forces,
        # lagged for friction; the velocity before the last substep; the slide along the body over
        # the last substep, lagged for the global step's friction): a redo starts from it again,
        # so a step redone after its buffers grew gives what a step with big enough buffers gives,
        # and a scene does not depend on whether another scene of its batch overflowed
        lagged = (self.body_lambda, self.v_old, self.slip)
        if self.config.self_collision:  # only cloth-cloth contact lists can overflow
            for a, b in zip(lagged, self._lagged_saved):
                wp.copy(b, a)
        for _attempt in range(6):
            if state_out is not state_in:
                state_out.assign(state_in)
            need = self._run_step(state_out, control, float(dt))
            if need <= self.capacity:
                self.body_start.assign(control.body_vertices)
                return
            self.contact_growths += 1
            self._allocate_contacts(int(need * 1.5) + 1)
            log.info("cloth-cloth contact lists grown to %d per element (a step needed %d; %d scenes, %d vertices); "
                     "the step is redone", self.capacity, need, self.model.scene_count, self.model.particle_count)
            for a, b in zip(lagged, self._lagged_saved):
                wp.copy(a, b)
            self._forget_checks()
            if state_out is state_in:
                raise SimulationError("contact buffers overflowed in an in-place step; they have been grown: "
                                      "step with separate input and output states")
        raise SimulationError(f"contact buffers kept overflowing (last need {need} per element)")

    def _run_step(self, state, control, dt: float) -> int:
        """One step's launches (on CUDA replayed from a captured graph), then the contact capacity
        the step needed."""
        import warp as wp

        dev = wp.get_device(self.model.device)
        # the probes read arrays back inside the step, which a captured graph cannot do
        if not (self.config.cuda_graph and dev.is_cuda) or self.probes:
            self._step(state, control, dt)
            return self._needed()
        # a graph bakes in its arrays and constants: one per (state, control, dt, capacity)
        key = (id(state), id(control), dt, self.capacity)
        graphs = self._graphs
        if key not in graphs:
            if len(graphs) > 8:
                graphs.clear()
            wp.load_module(self.K, device=dev)  # compile before capturing
            wp.load_module(self.D, device=dev)
            wp.load_module(self.S, device=dev)
            if self.config.global_iterations:
                from datagen.sim import newton_kernels

                wp.load_module(newton_kernels, device=dev)
            with wp.ScopedDevice(dev), wp.ScopedCapture(device=dev) as capture:
                self._step(state, control, dt)
            graphs[key] = (capture.graph, state, control)  # keep the arrays the graph reads alive
        wp.capture_launch(graphs[key][0])
        return self._needed()

    def _needed(self) -> int:
        return int(self.needed.numpy().max()) if self.config.self_collision else 0

    def _detect_self(self) -> None:
        """Cloth-cloth pairs and every vertex's move bound at the positions ``x_det``."""
        import warp as wp

        D, m, c = self.D, self.model, self.config
        n, nf, ne = m.particle_count, m.face_count, m.edge_count
        self.min_dist.fill_(D.BIG)
        self.vt_count.zero_()
        self.tv_count.zero_()
        self.ee_count.zero_()
        if c.self_collision:
            xd = self.x_det
            wp.launch(D.face_bounds, nf, inputs=[xd, m.faces, self.face_lo, self.face_hi])
            self.face_bvh.refit()
            wp.launch(D.edge_bounds, ne, inputs=[xd, m.edge_pairs, 0.0, self.edge_lo, self.edge_hi])
            self.edge_bvh.refit()
            wp.launch(self._kernel["detect_vertex_triangle"], n,
                      inputs=[self.face_bvh.id, xd, m.rest_positions, m.particle_scene, m.faces,
                              m.nbr_offsets, m.nbr, c.self_query, c.self_radius * 1.5, m.active,
                              self.vt_count, self.vt_tri, self.tv_count, self.tv_vert, self.min_dist,
                              self.vertex_order])
            wp.launch(self._kernel["detect_edge_edge"], ne,
                      inputs=[self.edge_bvh.id, xd, m.rest_positions, m.particle_scene, m.edge_pairs,
                              m.nbr_offsets, m.nbr, c.self_query, c.self_radius * 1.5, self.scene_frozen,
                              self.ee_count, self.ee_edge, self.min_dist, self.edge_order])
            wp.launch(D.sort_lists, n, inputs=[self.vt_count, self.vt_tri])
            wp.launch(D.sort_lists, nf, inputs=[self.tv_count, self.tv_vert])
            wp.launch(D.sort_lists, ne, inputs=[self.ee_count, self.ee_edge])
            wp.launch(D.count_needed, n, inputs=[self.vt_count, self.needed, 0])
            wp.launch(D.count_needed, nf, inputs=[self.tv_count, self.needed, 1])
            wp.launch(D.count_needed, ne, inputs=[self.ee_count, self.needed, 2])
        wp.launch(D.finish_bounds, n, inputs=[self.min_dist, c.bound_fraction, c.self_bound_floor, self.bound])

    def _untangle(self, x) -> None:
        """``untangle_iterations`` steps of intersection contour minimisation at ``x``: every vertex of
        an edge-triangle crossing moves ``untangle_step`` along its contour gradient
        (:mod:`datagen.sim.untangle_kernels`). The first iteration queries every edge and marks those
        that cross; the later ones query only the marked edges (a crossing that the moves make
        elsewhere is found at the next substep). Where the cloth crosses nowhere nothing moves."""
        import warp as wp

        from datagen.sim import untangle_kernels as U

        m = self.model
        for it in range(self.config.untangle_iterations):
            self.untangle_push.zero_()
            self.untangle_hits.zero_()
            wp.launch(self.D.face_bounds, m.face_count, inputs=[x, m.faces, self.face_lo, self.face_hi])
            self.face_bvh.refit()
            wp.launch(U.contour_gradients, m.edge_count, inputs=[
                self.face_bvh.id, x, m.particle_scene, m.faces, m.edges, self.scene_frozen, int(it > 0),
                self.untangle_edges, self.untangle_push, self.untangle_hits, self.edge_order])
            wp.launch(U.apply_untangle, m.particle_count, inputs=[self.untangle_push, self.untangle_hits, m.active,
                                                                  self.config.untangle_step, x])

    def _global_step(self, x, h: float) -> None:
        """One Newton step of the substep's incremental potential from the initial guess ``x``,
        solved by block-Jacobi preconditioned conjugate gradients (per scene), each vertex's move
        kept within its conservative bound (see :mod:`datagen.sim.newton_kernels`)."""
        import warp as wp

        from datagen.sim import newton_kernels as N

        m, c = self.model, self.config
        n, nf, ne = m.particle_count, m.face_count, m.edge_count
        wp.launch(N.vertex_force_diagonal, n, inputs=[x, self.verts, self.membrane, self.bending, self.body,
                                                      self.substep, self.cg_force, self.cg_diag_other])
        # x stays put while the iterations run: each element is linearised once, not once an iteration
        wp.launch(N.membrane_linearise, nf, inputs=[x, m.faces, m.dm_inv, m.tri_area, m.tri_stiff, m.damping, h,
                                                    self.cg_face_frame, self.cg_face_law, self.cg_face_stress,
                                                    self.cg_face_scale])
        wp.launch(N.bending_linearise, ne, inputs=[x, m.edges, m.bend_k, m.damping, h, self.cg_hinge_grad,
                                                   self.cg_hinge_scale])
        wp.launch(N.element_diagonal, n, inputs=[m.dm_inv, self.cg_face_frame, self.cg_face_law, self.cg_face_stress,
                                                 self.cg_face_scale, m.edges, self.cg_hinge_grad, self.cg_hinge_scale,
                                                 m.v2f_offsets, m.v2f, m.v2e_offsets, m.v2e, self.cg_diag_el])
        wp.launch(N.invert_blocks, n, inputs=[self.cg_diag_other, self.cg_diag_el, m.active, self.cg_inverse])
        p, q, r, z = self.cg_p, self.cg_q, self.cg_r, self.cg_z
        rz, rz_new = self.cg_rz, self.cg_rz_new
        ranges, scenes = self.particle_range, [m.scene_count]

        def dot(a, b, out):
            wp.launch_tiled(N.scene_dot, dim=scenes, block_dim=N.DOT_LANES, inputs=[a, b, ranges, out])

        wp.launch(N.cg_start, n, inputs=[self.cg_force, self.cg_inverse, m.active, r, z, p, self.cg_d])
        dot(r, z, rz)
        probes = self.probes
        for probe in probes:
            probe.global_residual(self, 0, rz, c.global_iterations == 0)
        for it in range(c.global_iterations):
            wp.launch(N.membrane_product, nf, inputs=[m.faces, m.dm_inv, self.cg_face_frame, self.cg_face_law,
                                                      self.cg_face_stress, self.cg_face_scale, p, self.cg_face_part])
            wp.launch(N.bending_product, ne, inputs=[m.edges, self.cg_hinge_grad, self.cg_hinge_scale, p,
                                                     self.cg_edge_part])
            wp.launch(N.gather_product, n, inputs=[self.cg_diag_other, p, m.v2f_offsets, m.v2f, m.v2e_offsets,
                                                   m.v2e, self.cg_face_part, self.cg_edge_part, q])
            dot(p, q, self.cg_pq)
            wp.launch(N.cg_step, n, inputs=[p, q, self.cg_inverse, m.particle_scene, rz, self.cg_pq, self.cg_d, r, z])
            dot(r, z, rz_new)
            wp.launch(N.cg_direction, n, inputs=[z, m.particle_scene, rz, rz_new, p])
            rz, rz_new = rz_new, rz
            for probe in probes:
                probe.global_residual(self, it + 1, rz, it + 1 == c.global_iterations)
        wp.launch(N.apply_step, n, inputs=[self.cg_d, self.x_det, self.bound, m.active, x])

    def _solve_colour(self, col, x, out) -> None:
        """One sweep of colour ``col`` (its vertices' Newton steps from ``x``, written to ``out``),
        ``sweep_lanes`` threads of a warp per vertex on a GPU, one on a CPU
        (:mod:`datagen.sim.sweep_kernels`)."""
        import warp as wp

        m, c = self.model, self.config
        lanes = int(c.sweep_lanes) if self._on_cuda else 1  # a CPU thread walks a vertex alone
        threads = col.shape[0] * lanes
        if lanes > 1:  # whole warps: every thread of a warp takes part in the lanes' shuffles
            threads = -(-threads // self.S.WARP_SIZE) * self.S.WARP_SIZE
        wp.launch(self.S.solve_colour, threads, device=m.device, inputs=[
            col, x, self.verts, self.membrane, self.bending, self.body, self.self_contact, self.substep, lanes, out])

    def _step(self, state, control, dt: float) -> None:
        import warp as wp

        K, m, c = self.K, self.model, self.config
        n, nb = m.particle_count, m.body_vertex_count
        h = dt / c.substeps
        self.substep.h, self.substep.eps_u = h, c.friction_velocity * h
        x, v = state.positions, state.velocities
        self.needed.zero_()
        self.projected.zero_()
        with wp.ScopedDevice(m.device):
            for s in range(c.substeps):
                if c.self_collision and c.untangle_step > 0.0:
                    # before the substep's solve, which relaxes the membrane around what it moved
                    # (after it, a 4-iteration jump was left in the frame: pants walk 53 % stretch)
                    self._untangle(x)
                a1 = (s + 1) / c.substeps
                wp.launch(K.interpolate_body, nb, inputs=[self.body_start, control.body_vertices, s / c.substeps,
                                                          self.body_prev_sub])
                wp.launch(K.interpolate_body, nb, inputs=[self.body_start, control.body_vertices, a1, self.body_sub])
                self._refit_body()
                if c.body_projection and c.projection_skip:
                    P = m.body_part_count
                    self.part_lo.fill_(wp.vec3(BIG_BOX))
                    self.part_hi.fill_(wp.vec3(-BIG_BOX))
                    wp.launch(self.PK.body_parts_moved, (m.scene_count * P, self._travel_chunks), inputs=[
                        self.body_prev_sub, self.body_sub, self.part_vertices, self.part_offsets, self.body_ref, P,
                        TRAVEL_CHUNK, self.body_step_max, self.part_lo, self.part_hi])
                    wp.launch(self.PK.add_travel, (m.scene_count, P), inputs=[self.body_step_max, self.body_travel])
                wp.launch(K.forward_step, n, inputs=[x, v, m.mass, m.vertex_area, m.active, wp.vec3(*c.gravity),
                                                     c.air_drag, h, self.x_prev, self.y, state.pinned_target])
                wp.launch(K.detect_body, n, inputs=[self.body_ids, m.body_face_base, m.body_face_part,
                                                    m.body_face_border, self.x_prev, m.particle_scene,
                                                    m.body_faces, self.body_prev_sub, self.body_sub, c.body_query,
                                                    self.body_radius, m.active, self.y, self.body_has,
                                                    self.body_point, self.body_normal, self.body_disp,
                                                    self.vertex_order])
                if c.body_friction:
                    wp.launch(K.predict_body_friction, n, inputs=[
                        self.x_prev, m.mass, m.active, self.body_has, self.body_normal, self.body_disp,
                        self.body_lambda, m.friction, m.vertex_area, c.friction_pressure, h, self.y,
                        self.friction_used])
                wp.copy(self.x_det, self.x_prev)
                self._detect_self()
                wp.launch(K.initial_guess, n, inputs=[self.x_det, self.y, v, self.v_old, wp.vec3(*c.gravity), h,
                                                     self.body_lambda, self.bound, m.active, x])
                if c.global_iterations:
                    self._global_step(x, h)
                wp.copy(self.x_nm1, x)
                omega, cheb = 1.0, 0
                rho = c.chebyshev_rho
                probes = self.probes
                for it in range(c.iterations):
                    for probe in probes:
                        probe.before_sweep(self, s, it, x)
                    if c.self_collision and c.detection_interval and it and it % c.detection_interval == 0:
                        wp.copy(self.x_det, x)
                        self._detect_self()
                        wp.copy(self.x_nm1, x)
                        omega, cheb = 1.0, 0
                    for col in self.colours:
                        self._solve_colour(col, x, self.x_tmp)
                        wp.launch(K.copy_colour, col.shape[0], inputs=[col, self.x_tmp, x])
                    omega = 1.0 if cheb < 1 else (2.0 / (2.0 - rho * rho) if cheb == 1 else 4.0 / (4.0 - rho * rho * omega))
                    cheb += 1
                    if it == c.iterations - 1:
                        # the substep ends on a plain sweep: an extrapolated last iterate would set the
                        # velocities (a cloth at rest on a plane crept 80 mm in 2 s at 15 iterations)
                        omega = 1.0
                    wp.launch(K.chebyshev, n, inputs=[x, self.x_nm1, self.x_nm2, self.x_det, self.bound, m.active,
                                                      omega, self.vt_count, int(not c.chebyshev_contacts),
                                                      self.body_has, int(not c.chebyshev_body_contacts)])
                    for probe in probes:
                        probe.after_sweep(self, s, it, x, it == c.iterations - 1)
                wp.launch(K.body_contact_force, n, inputs=[x, self.body_has, self.body_point, self.body_normal,
                                                           self.body_radius, c.body_stiffness, self.body_lambda])
                if c.global_iterations and c.global_friction == "lagged":
                    wp.launch(K.record_slip, n, inputs=[x, self.x_prev, self.body_has, self.body_normal, self.body_disp,
                                                        self.body_lambda, self.slip])
                wp.launch(K.update_velocity, n, inputs=[x, self.x_prev, h, v, self.v_old])
                if c.body_projection:
                    for again in range(2):  # a second pass for vertices the first put into another body part
                        wp.launch(self._kernel["test_inside_body"], n, inputs=[
                            self.body_ids, m.particle_scene, self.body_sub, 2.0 * c.body_query, m.active, x, again,
                            self.projection_inside, self.projection_pending, self.projection_face, self.projection_uv,
                            self.body_ref, m.body_part_count, self.body_travel, self.part_lo, self.part_hi,
                            self.check_x, self.check_travel, self.check_bound, self.projection_skipped,
                            int(c.projection_skip), float(c.projection_accuracy), self.vertex_order])
                        wp.launch(self.PK.move_out_of_body, n, inputs=[
                            self.body_ids, m.body_face_base, m.particle_scene, m.body_faces, self.body_prev_sub,
                            self.body_sub, 2.0 * c.body_query, self.body_radius, h, c.projection_reach, x, v,
                            self.projected, self.projection_pending, self.projection_face, self.projection_uv,
                            float(c.projection_accuracy), self.vertex_order])
