"""The vertex block descent cloth solver: arranges the launches of :mod:`datagen.sim.kernels`.

``SolverVBD(model, config).step(state_in, state_out, control, dt)`` advances every scene of the
model by ``dt`` (one frame) in ``config.steps.substeps_for(dt)`` substeps of ``config.steps.iterations`` colour sweeps,
with the body moving linearly from the previous control to ``control`` within the frame.
"""

from __future__ import annotations

import logging
import numpy as np

from datagen.errors import InputError, SimulationError
from datagen.sim.settings import GLOBAL_FRICTION, REGISTER_CAPS, SolverConfig

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


REFIT_STREAMS = 16
"""CUDA streams that the body meshes' refits are spread over."""


def mesh_edge_length(host) -> float:
    """The smallest of the scenes' median rest edge lengths [m] (0 for a model without edges): what
    the substep length follows (``StepConfig.substep_edge``)."""
    x = np.asarray(host.rest_positions, dtype=np.float64)
    pairs = np.asarray(host.edge_pairs)
    if len(pairs) == 0:
        return 0.0
    length = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    medians = [np.median(length[a:b]) for a, b in np.asarray(host.edge_range) if b > a]
    return float(min(medians)) if medians else 0.0


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
        capped = REGISTER_CAPS[self.config.launch.register_caps]
        # the kernels launched below, each its register-capped copy where the config asks for it
        home = {"detect_vertex_triangle": D, "detect_edge_edge": D, "test_inside_body": PK}
        self._kernel = {name: getattr(home[name], name + ("_capped" if name in capped else "")) for name in home}
        m = model
        n, nf, ne, nb = m.particle_count, m.face_count, m.edge_count, m.body_vertex_count
        with wp.ScopedDevice(m.device):
            z3 = lambda k: wp.zeros(k, dtype=wp.vec3)
            self.x_prev, self.y, self.x_tmp = z3(n), z3(n), z3(n)
            h = m.host
            cols = h.colours if self.config.steps.colour_hinge_wings else triangle_colours(h)  # the sweeps' colours
            if self.config.launch.coherent_order:  # threads of one warp on cloth near each other (launch_order)
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
            self.bound_global = wp.zeros(n, dtype=float)  # the global step's, without the floor (kernels.global_bounds)
            self.min_dist = wp.zeros(n, dtype=float)
            self.friction_used = wp.zeros(n, dtype=float)
            self.slip = wp.zeros(n, dtype=float)
            self.v_old = z3(n)
            self.scene_frozen = wp.zeros(m.scene_count, dtype=wp.int32)  # 1: frozen (:meth:`freeze`)
            # the last substep's correction to its initial guess, where the next global step starts
            self.cg_warm, self.x_init = z3(n), z3(n)
            if self.config.steps.global_iterations:  # the global step's vectors, blocks and per-scene scalars
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
            self._lagged_saved = (wp.zeros((n, P), dtype=float), z3(n), wp.zeros(n, dtype=float), z3(n))
            self.body_has = wp.zeros((n, P), dtype=wp.int32)
            self.body_point, self.body_normal, self.body_disp = (wp.zeros((n, P), dtype=wp.vec3) for _ in range(3))
            self.body_radius = wp.array(m.host.thickness.astype(np.float32) + self.config.body.margin, dtype=float)
            self.body_start = wp.clone(m.body_rest)
            self.body_prev_sub, self.body_sub = z3(nb), wp.clone(m.body_rest)
            self.x_det = wp.clone(m.rest_positions)
            self.bound_end = wp.clone(m.rest_positions)  # x_det carried by the body (kernels.carry_bound)
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
        self._allocate_contacts(self.config.self_contact.capacity)
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
        g = self.verts = G.Vertices()
        g.mass, g.active, g.damping, g.friction, g.area = m.mass, m.active, m.damping, m.friction, m.vertex_area
        g = self.membrane = G.Membrane()
        g.faces, g.dm_inv, g.area, g.stiffness, g.lock = m.faces, m.dm_inv, m.tri_area, m.tri_stiff, m.tri_lock
        g.v2f_offsets, g.v2f = m.v2f_offsets, m.v2f
        g = self.bending = G.Bending()
        g.edges, g.rest_angle, g.stiffness, g.v2e_offsets, g.v2e = m.edges, m.rest_angle, m.bend_k, m.v2e_offsets, m.v2e
        g = self.body_contact = G.BodyContact()
        g.has, g.point, g.normal, g.disp = self.body_has, self.body_point, self.body_normal, self.body_disp
        g.radius, g.lam, g.friction_used = self.body_radius, self.body_lambda, self.friction_used
        g.stiffness, g.friction_pressure = c.body.stiffness, c.body.friction_pressure
        g.friction = int(c.body.friction)
        g.global_friction = GLOBAL_FRICTION[c.body.global_friction] if c.body.friction else 0
        g = self.substep = G.Substep()
        g.x_prev, g.x_det, g.inertia_target, g.bound, g.slip = self.x_prev, self.x_det, self.y, self.bound, self.slip
        g.bound_end = self.bound_end

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
        g.radius, g.stiffness, g.friction = c.self_contact.radius, c.self_contact.stiffness, c.self_contact.friction

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

    def substeps_for(self, dt: float) -> int:
        """Substeps a step of ``dt`` [s] runs (:meth:`StepConfig.substeps_for` at the model's
        :func:`mesh_edge_length`)."""
        edge = getattr(self, "_mesh_edge", None)
        if edge is None:
            edge = self._mesh_edge = mesh_edge_length(self.model.host)
        return self.config.steps.substeps_for(dt, edge)

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
        # the last substep, lagged for the global step's friction; the last substep's correction to
        # its initial guess, where the global step starts): a redo starts from it again,
        # so a step redone after its buffers grew gives what a step with big enough buffers gives,
        # and a scene does not depend on whether another scene of its batch overflowed
        lagged = (self.body_lambda, self.v_old, self.slip, self.cg_warm)
        if self.config.self_contact.enabled:  # only cloth-cloth contact lists can overflow
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
        if not (self.config.launch.cuda_graph and dev.is_cuda) or self.probes:
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
            if self.config.steps.global_iterations:
                from datagen.sim import newton_kernels

                wp.load_module(newton_kernels, device=dev)
            with wp.ScopedDevice(dev), wp.ScopedCapture(device=dev) as capture:
                self._step(state, control, dt)
            graphs[key] = (capture.graph, state, control)  # keep the arrays the graph reads alive
        wp.capture_launch(graphs[key][0])
        return self._needed()

    def _needed(self) -> int:
        return int(self.needed.numpy().max()) if self.config.self_contact.enabled else 0

    def _detect_self(self) -> None:
        """Cloth-cloth pairs and every vertex's move bound at the positions ``x_det``, and the far
        end of the segment it is measured from (``bound_end``: ``kernels.carry_bound``)."""
        import warp as wp

        D, m, c = self.D, self.model, self.config
        n, nf, ne = m.particle_count, m.face_count, m.edge_count
        self.min_dist.fill_(D.BIG)
        self.vt_count.zero_()
        self.tv_count.zero_()
        self.ee_count.zero_()
        if c.self_contact.enabled:
            xd = self.x_det
            wp.launch(D.face_bounds, nf, inputs=[xd, m.faces, self.face_lo, self.face_hi])
            self.face_bvh.refit()
            wp.launch(D.edge_bounds, ne, inputs=[xd, m.edge_pairs, 0.0, self.edge_lo, self.edge_hi])
            self.edge_bvh.refit()
            wp.launch(self._kernel["detect_vertex_triangle"], n,
                      inputs=[self.face_bvh.id, xd, m.rest_positions, m.particle_scene, m.faces,
                              m.nbr_offsets, m.nbr, c.self_contact.query, c.self_contact.radius * 1.5, m.active,
                              self.vt_count, self.vt_tri, self.tv_count, self.tv_vert, self.min_dist,
                              self.vertex_order])
            wp.launch(self._kernel["detect_edge_edge"], ne,
                      inputs=[self.edge_bvh.id, xd, m.rest_positions, m.particle_scene, m.edge_pairs,
                              m.nbr_offsets, m.nbr, c.self_contact.query, c.self_contact.radius * 1.5,
                              self.scene_frozen,
                              self.ee_count, self.ee_edge, self.min_dist, self.edge_order])
            wp.launch(D.sort_lists, n, inputs=[self.vt_count, self.vt_tri])
            wp.launch(D.sort_lists, nf, inputs=[self.tv_count, self.tv_vert])
            wp.launch(D.sort_lists, ne, inputs=[self.ee_count, self.ee_edge])
            wp.launch(D.count_needed, n, inputs=[self.vt_count, self.needed, 0])
            wp.launch(D.count_needed, nf, inputs=[self.tv_count, self.needed, 1])
            wp.launch(D.count_needed, ne, inputs=[self.ee_count, self.needed, 2])
        wp.launch(D.finish_bounds, n, inputs=[self.min_dist, c.self_contact.bound_fraction, c.self_contact.bound_floor,
                                              self.bound])
        wp.launch(self.K.global_bounds, n, inputs=[self.min_dist, c.self_contact.bound_fraction, self.bound_global])
        wp.launch(self.K.carry_bound, n, inputs=[self.x_det, self.x_prev, self.body_has, self.body_point,
                                                 self.body_normal, self.body_disp, c.body.query, m.active,
                                                 self.bound_end])

    def _untangle(self, x) -> None:
        """``untangle_iterations`` steps of intersection contour minimisation at ``x``: every vertex of
        an edge-triangle crossing moves ``untangle_step`` along its contour gradient
        (:mod:`datagen.sim.untangle_kernels`). The first iteration queries every edge and marks those
        that cross; the later ones query only the marked edges (a crossing that the moves make
        elsewhere is found at the next substep). Where the cloth crosses nowhere nothing moves."""
        import warp as wp

        from datagen.sim import untangle_kernels as U

        m = self.model
        for it in range(self.config.self_contact.untangle_iterations):
            self.untangle_push.zero_()
            self.untangle_hits.zero_()
            wp.launch(self.D.face_bounds, m.face_count, inputs=[x, m.faces, self.face_lo, self.face_hi])
            self.face_bvh.refit()
            wp.launch(U.contour_gradients, m.edge_count, inputs=[
                self.face_bvh.id, x, m.particle_scene, m.faces, m.edges, self.scene_frozen, int(it > 0),
                self.untangle_edges, self.untangle_push, self.untangle_hits, self.edge_order])
            wp.launch(U.apply_untangle, m.particle_count, inputs=[self.untangle_push, self.untangle_hits, m.active,
                                                                  self.config.self_contact.untangle_step, x])

    def _global_step(self, x, h: float) -> None:
        """``global_steps`` Newton steps of the substep's incremental potential from the initial
        guess ``x``, each solved by ``global_iterations`` iterations of block-Jacobi preconditioned
        conjugate gradients (per scene), each vertex's move kept within its conservative bound (see
        :mod:`datagen.sim.newton_kernels`). Every step relinearises the elements and the forces at
        the x the last one reached; the preconditioner is the first step's."""
        import warp as wp

        from datagen.sim import newton_kernels as N

        m, c = self.model, self.config
        n, nf, ne = m.particle_count, m.face_count, m.edge_count
        majorise = int(c.steps.compression_hessian == "tension")
        p, q, r, z = self.cg_p, self.cg_q, self.cg_r, self.cg_z
        ranges, scenes = self.particle_range, [m.scene_count]
        probes = self.probes

        def dot(a, b, out):
            wp.launch_tiled(N.scene_dot, dim=scenes, block_dim=N.DOT_LANES, inputs=[a, b, ranges, out])

        for step in range(c.steps.global_steps):
            # x stays put while the iterations run: each element is linearised once a Newton step,
            # and its force shares (into the product buffers, free until the iterations start) with it
            wp.launch(N.membrane_linearise, nf, inputs=[x, self.x_prev, m.faces, m.dm_inv, m.tri_area, m.tri_stiff,
                                                        m.damping, h, majorise, self.cg_face_frame, self.cg_face_law,
                                                        self.cg_face_stress, self.cg_face_scale, self.cg_face_part])
            wp.launch(N.bending_linearise, ne, inputs=[x, self.x_prev, m.edges, m.rest_angle, m.bend_k, m.damping, h,
                                                       self.cg_hinge_grad, self.cg_hinge_scale, self.cg_edge_part])
            wp.launch(N.vertex_force_diagonal, n, inputs=[x, self.verts, self.membrane, self.bending,
                                                          self.body_contact, self.substep, self.cg_face_part,
                                                          self.cg_edge_part, self.cg_force, self.cg_diag_other])
            if step == 0:
                wp.launch(N.element_diagonal, n, inputs=[m.dm_inv, self.cg_face_frame, self.cg_face_law,
                                                         self.cg_face_stress, self.cg_face_scale, m.edges,
                                                         self.cg_hinge_grad, self.cg_hinge_scale, m.v2f_offsets,
                                                         m.v2f, m.v2e_offsets, m.v2e, self.cg_diag_el])
                wp.launch(N.invert_blocks, n, inputs=[self.cg_diag_other, self.cg_diag_el, m.active, self.cg_inverse])
            rz, rz_new = self.cg_rz, self.cg_rz_new
            wp.launch(N.cg_start, n, inputs=[self.cg_force, self.cg_inverse, m.active, r, z, p, self.cg_d])
            if step == 0 and c.steps.warm_start:
                if probes:  # they see the cold start's rᵀP⁻¹r = fᵀP⁻¹f first (iteration -1)
                    dot(r, z, rz)
                    for probe in probes:
                        probe.global_residual(self, -1, rz, False)
                self._product(self.cg_warm, q)
                dot(r, self.cg_warm, self.cg_rz)
                dot(self.cg_warm, q, self.cg_pq)
                wp.launch(N.warm_start, n, inputs=[self.cg_warm, q, self.cg_inverse, m.particle_scene, self.cg_rz,
                                                   self.cg_pq, m.active, self.cg_d, r, z, p])
            dot(r, z, rz)
            for probe in probes:
                probe.global_residual(self, 0, rz, c.steps.global_iterations == 0)
            for it in range(c.steps.global_iterations):
                self._product(p, q)
                dot(p, q, self.cg_pq)
                wp.launch(N.cg_step, n, inputs=[p, q, self.cg_inverse, m.particle_scene, rz, self.cg_pq, self.cg_d, r,
                                                z])
                dot(r, z, rz_new)
                wp.launch(N.cg_direction, n, inputs=[z, m.particle_scene, rz, rz_new, p])
                rz, rz_new = rz_new, rz
                for probe in probes:
                    probe.global_residual(self, it + 1, rz, it + 1 == c.steps.global_iterations)
            wp.launch(N.apply_step, n, inputs=[self.cg_d, self.x_det, self.bound_end, self.bound_global, m.active, x])

    def _product(self, p, q) -> None:
        """q = H p with the global step's Hessian at its linearisation (element by element)."""
        import warp as wp

        from datagen.sim import newton_kernels as N

        m = self.model
        wp.launch(N.membrane_product, m.face_count, inputs=[m.faces, m.dm_inv, self.cg_face_frame, self.cg_face_law,
                                                            self.cg_face_stress, self.cg_face_scale, p,
                                                            self.cg_face_part])
        wp.launch(N.bending_product, m.edge_count, inputs=[m.edges, self.cg_hinge_grad, self.cg_hinge_scale, p,
                                                           self.cg_edge_part])
        wp.launch(N.gather_product, m.particle_count, inputs=[self.cg_diag_other, p, m.v2f_offsets, m.v2f,
                                                              m.v2e_offsets, m.v2e, self.cg_face_part,
                                                              self.cg_edge_part, q])

    def _solve_colour(self, col, x, out) -> None:
        """One sweep of colour ``col`` (its vertices' Newton steps from ``x``, written to ``out``),
        ``sweep_lanes`` threads of a warp per vertex on a GPU, one on a CPU
        (:mod:`datagen.sim.sweep_kernels`)."""
        import warp as wp

        m, c = self.model, self.config
        lanes = int(c.launch.sweep_lanes) if self._on_cuda else 1  # a CPU thread walks a vertex alone
        threads = col.shape[0] * lanes
        if lanes > 1:  # whole warps: every thread of a warp takes part in the lanes' shuffles
            threads = -(-threads // self.S.WARP_SIZE) * self.S.WARP_SIZE
        wp.launch(self.S.solve_colour, threads, device=m.device, inputs=[
            col, x, self.verts, self.membrane, self.bending, self.body_contact, self.self_contact, self.substep, lanes,
            out])

    def _step(self, state, control, dt: float) -> None:
        import warp as wp

        K, m, c = self.K, self.model, self.config
        n, nb = m.particle_count, m.body_vertex_count
        substeps = self.substeps_for(dt)
        h = dt / substeps
        self.substep.h, self.substep.eps_u = h, c.friction_velocity * h
        x, v = state.positions, state.velocities
        self.needed.zero_()
        self.projected.zero_()
        with wp.ScopedDevice(m.device):
            for s in range(substeps):
                if c.self_contact.enabled and c.self_contact.untangle_step > 0.0:
                    # before the substep's solve, which relaxes the membrane around what it moved
                    # (after it, a 4-iteration jump was left in the frame: pants walk 53 % stretch)
                    self._untangle(x)
                a1 = (s + 1) / substeps
                wp.launch(K.interpolate_body, nb, inputs=[self.body_start, control.body_vertices, s / substeps,
                                                          self.body_prev_sub])
                wp.launch(K.interpolate_body, nb, inputs=[self.body_start, control.body_vertices, a1, self.body_sub])
                self._refit_body()
                if c.projection.enabled and c.projection.skip:
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
                                                    m.body_faces, self.body_prev_sub, self.body_sub, c.body.query,
                                                    self.body_radius, m.active, self.y, self.body_has,
                                                    self.body_point, self.body_normal, self.body_disp,
                                                    self.vertex_order])
                if c.body.friction:
                    wp.launch(K.predict_body_friction, n, inputs=[
                        self.x_prev, m.mass, m.active, self.body_has, self.body_normal, self.body_disp,
                        self.body_lambda, m.friction, m.vertex_area, c.body.friction_pressure, h, self.y,
                        self.friction_used])
                wp.copy(self.x_det, self.x_prev)
                self._detect_self()
                wp.launch(K.initial_guess, n, inputs=[self.x_det, self.bound_end, self.y, v, self.v_old,
                                                     wp.vec3(*c.gravity), h, self.body_lambda, self.bound,
                                                     m.active, x])
                if c.steps.global_iterations:
                    if c.steps.warm_start:
                        wp.copy(self.x_init, x)
                    self._global_step(x, h)
                wp.copy(self.x_nm1, x)
                omega, cheb = 1.0, 0
                rho = c.steps.chebyshev_rho
                probes = self.probes
                for it in range(c.steps.iterations):
                    for probe in probes:
                        probe.before_sweep(self, s, it, x)
                    every = c.self_contact.detection_interval
                    if c.self_contact.enabled and every and it and it % every == 0:
                        wp.copy(self.x_det, x)
                        self._detect_self()
                        wp.copy(self.x_nm1, x)
                        omega, cheb = 1.0, 0
                    for col in self.colours:
                        self._solve_colour(col, x, self.x_tmp)
                        wp.launch(K.copy_colour, col.shape[0], inputs=[col, self.x_tmp, x])
                    omega = 1.0 if cheb < 1 else (2.0 / (2.0 - rho * rho) if cheb == 1 else 4.0 / (4.0 - rho * rho * omega))
                    cheb += 1
                    if it == c.steps.iterations - 1:
                        # the substep ends on a plain sweep: an extrapolated last iterate would set the
                        # velocities (a cloth at rest on a plane crept 80 mm in 2 s at 15 iterations)
                        omega = 1.0
                    wp.launch(K.chebyshev, n, inputs=[x, self.x_nm1, self.x_nm2, self.x_det, self.bound_end,
                                                      self.bound, m.active, omega, self.vt_count,
                                                      int(not c.steps.chebyshev_contacts), self.body_has,
                                                      int(not c.steps.chebyshev_body_contacts)])
                    for probe in probes:
                        probe.after_sweep(self, s, it, x, it == c.steps.iterations - 1)
                wp.launch(K.body_contact_force, n, inputs=[x, self.body_has, self.body_point, self.body_normal,
                                                           self.body_radius, c.body.stiffness, self.body_lambda])
                if c.steps.global_iterations and c.body.global_friction == "lagged":
                    wp.launch(K.record_slip, n, inputs=[x, self.x_prev, self.body_has, self.body_normal, self.body_disp,
                                                        self.body_lambda, self.slip])
                wp.launch(K.update_velocity, n, inputs=[x, self.x_prev, h, v, self.v_old])
                if c.steps.global_iterations and c.steps.warm_start:
                    from datagen.sim import newton_kernels as N

                    wp.launch(N.record_correction, n, inputs=[x, self.x_init, m.active, self.cg_warm])
                if c.projection.enabled:
                    for again in range(2):  # a second pass for vertices the first put into another body part
                        wp.launch(self._kernel["test_inside_body"], n, inputs=[
                            self.body_ids, m.particle_scene, self.body_sub, 2.0 * c.body.query, m.active, x, again,
                            self.projection_inside, self.projection_pending, self.projection_face, self.projection_uv,
                            self.body_ref, m.body_part_count, self.body_travel, self.part_lo, self.part_hi,
                            self.check_x, self.check_travel, self.check_bound, self.projection_skipped,
                            int(c.projection.skip), float(c.projection.accuracy), self.vertex_order])
                        wp.launch(self.PK.move_out_of_body, n, inputs=[
                            self.body_ids, m.body_face_base, m.particle_scene, m.body_faces, self.body_prev_sub,
                            self.body_sub, 2.0 * c.body.query, self.body_radius, h, c.projection.reach, x, v,
                            self.projected, self.projection_pending, self.projection_face, self.projection_uv,
                            float(c.projection.accuracy), self.vertex_order])
