"""drape's cloth solver and Newton's VBD cloth solver side by side, in one run, on the same scene.

The scene is one of ``sim prepare-runs``' (default: the T-shirt on the regular body
walking, 30 fps), run as ``drape``'s pipeline runs it: settle at rest, lead-in from the rest pose,
settle in the first pose, the 1 s ramp into the motion, then the motion (``frame_schedule`` in
datagen/sim/scene.py). Both solvers get the same garment mesh, the same posed body mesh per frame
(interpolated linearly within the frame, substep by substep), the same substeps and iterations (drape's
solver settings, 10 x 10 by default), the same
contact distances and stiffnesses, and the same material; batches of N copies of the scene run in
one model (drape: scenes; Newton: worlds).

    python -m benchmarks sim prepare-runs --out runs.pkl --frames 300
    python -m benchmarks newton --inputs runs.pkl --scene tshirt/walk --device cuda --batches 1,16

Printed per solver, batch size and self-collision on/off: ms per frame, garment-frames per second,
and over every frame of scene 0 (measured by drape's metrics, the same code for both): frames with
a vertex inside the body (of the recorded frames: after the ramp), the most such vertices and the deepest, the most self-intersections
(edge-triangle crossings), the largest single-triangle stretch, and NaN.

How Newton's side is set up (newton 1.8):
- the garment is ``ModelBuilder.add_cloth_mesh`` with StVK Lamé parameters from the material's
  2D Young's modulus E and Poisson ratio nu (plane stress: mu = E / 2(1 + nu), lambda = E nu /
  (1 - nu^2)), its bending stiffness as ``edge_ke`` and its density; ``builder.color()``;
- the body is a mesh shape per world whose ``wp.Mesh`` points (and velocities) are overwritten
  before every substep and refitted, so ``CollisionPipeline.collide`` makes particle-body contacts
  against the posed body with its velocity (friction), at distance particle radius (material
  thickness + drape's body margin) plus the soft-contact margin;
- self-contact (``particle_enable_self_contact``) with margin = drape's ``self_radius`` and gap =
  drape's ``self_query`` - ``self_radius``; its topological contact filters (two rings) are built by
  Newton's own code for world 0 and copied to the other worlds, which are the same mesh
  (:class:`_WorldFilters`; set-up only, not timed: built for all 256 worlds they took minutes;
  ``--check-filters`` compares both ways at 3 worlds first).
- how it is launched (``--newton-launch``): ``python``, every substep from Python and the body
  meshes refitted one after another (the earlier sessions' figures), or ``graph``, as drape's solver
  runs: a frame's substeps captured once as a CUDA graph and replayed, the refits spread over CUDA
  streams (``solver.REFIT_STREAMS``) inside it; ``--profile K`` prints each solver's top K kernels over
  one more frame launched directly.
Newton is not a dependency of drape: ``pip install -e .[newton]`` (or ``pip install newton``) to run this benchmark.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from benchmarks.common import build_batch, load_runs


def _load_scene(path: str, name: str) -> dict:
    """The garment and the body of every simulated frame (the pipeline's schedule) of one scene."""
    from datagen.sim.scene import RunConfig, body_at, frame_schedule, scene_arrays

    runs = load_runs(path)
    if name not in runs["names"]:
        raise SystemExit(f"scene {name!r} is not in {path}: it has {', '.join(runs['names'])}")
    cfg = RunConfig()
    a = scene_arrays(runs["scenes"][runs["names"].index(name)], cfg.lead_in)
    schedule, recorded_from = frame_schedule(cfg, a.lead_frames, len(a.body_frames), a.fps)
    schedule = [0.0, *schedule]  # the state before step k of the schedule is frame k here (frame 0: the drape)
    frames = a.body_frames
    return {"garment": a.garment_vertices, "faces": a.garment_faces, "material": a.material.name,
            "frames": a.material_frames, "body_faces": a.body_faces, "body_face_part": a.body_face_part,
            "body_vertices": frames.shape[1],
            "body": lambda f: body_at(frames, schedule[f]).astype(np.float32), "frame_count": len(schedule),
            "recorded_from": recorded_from}


def _drape_batch(d, n: int, device, config):
    """``n`` copies of the scene ``d`` (:func:`_load_scene`) at its first frame, drape's solver at ``config``."""
    return build_batch(garment=d["garment"], faces=d["faces"], material=str(d["material"]), material_frames=d["frames"],
                       body=d["body"](0), body_faces=d["body_faces"], body_face_part=d["body_face_part"], n=n,
                       device=str(device), config=config)


def _summary(frames: list[dict], recorded_from: int) -> dict:
    pen = np.array([f["penetration_count"][0] for f in frames])
    if PER_FRAME:
        for k, f in enumerate(frames):
            print(f"    frame {k + 1:3d}: pen {f['penetration_count'][0]:4d} depth {1000 * f['penetration_depth'][0]:6.2f} mm "
                  f"self-x {f['self_intersections'][0]:4d} stretch max {f['stretch_max'][0]:7.3f} "
                  f"mean {f['stretch_mean'][0]:6.3f}", flush=True)
    return {
        "frames": len(frames),
        "recorded": len(frames[recorded_from:]),
        "frames_with_penetration": int((pen[recorded_from:] > 0).sum()),
        "frames_with_penetration_all": int((pen > 0).sum()),
        "max_penetrating_vertices": int(pen.max()),
        "max_depth_mm": 1000 * float(max(f["penetration_depth"][0] for f in frames)),
        "max_self_intersections": int(max(f["self_intersections"][0] for f in frames)),
        "max_stretch": float(max(f["stretch_max"][0] for f in frames)),
        "nan": bool(any(f["nan"][0] for f in frames)),
    }


class _Measure:
    """drape's metrics of scene 0 for garment positions from either solver."""

    def __init__(self, d, device):
        import warp as wp

        from datagen.sim.metrics import Metrics
        from datagen.sim.solver import SolverConfig

        one = _drape_batch(d, 1, device, SolverConfig())
        self.model, self.solver, self.state, self.ctrl = one.model, one.solver, one.a, one.control
        self.metrics = Metrics(self.model)
        self.wp = wp

    def __call__(self, positions: np.ndarray, velocities: np.ndarray, body: np.ndarray) -> dict:
        self.ctrl.set(body)
        self.solver.place_body(self.ctrl)
        self.state.positions.assign(positions.astype(np.float32))
        self.state.velocities.assign(velocities.astype(np.float32))
        return self.metrics.measure(self.state, self.solver)


DRAPE_OPTIONS: dict = {}
PROFILE = 0
"""Kernels to print per solver after its timed frames (``--profile``; 0: none)."""


def _profile(name: str, fn, device) -> None:
    """One more frame, ``fn``, launched directly under warp's CUDA kernel timers: its top ``PROFILE``
    kernels by time (warp's builtin ones, such as the BVH and mesh refits, included); CUDA only."""
    import warp as wp

    if not PROFILE or not wp.get_device(device).is_cuda:
        return
    wp.synchronize()
    wp.timing_begin(cuda_filter=wp.TIMING_KERNEL | wp.TIMING_KERNEL_BUILTIN | wp.TIMING_MEMCPY | wp.TIMING_MEMSET)
    fn()
    times: dict[str, list] = {}
    for r in wp.timing_end():
        times.setdefault(r.name, []).append(r.elapsed)
    total = sum(sum(v) for v in times.values())
    print(f"  {name}: one frame launched directly, {total:.1f} ms of kernels in {sum(map(len, times.values()))} launches",
          flush=True)
    for k, v in sorted(times.items(), key=lambda kv: -sum(kv[1]))[:PROFILE]:
        print(f"    {k[:52]:<52} {len(v):6d} launches {sum(v):8.2f} ms {1000 * sum(v) / len(v):8.1f} us/launch",
              flush=True)


def run_drape(d, n: int, self_col: bool, frames: int, device, measure: _Measure) -> dict:
    import warp as wp

    from datagen.sim.solver import SolverConfig

    body = d["body"]
    batch = _drape_batch(d, n, device, SolverConfig(**{**DRAPE_OPTIONS, "self_contact.enabled": self_col}))
    solver, a, c, ctrl = batch.solver, batch.a, batch.c, batch.control
    nv = len(d["garment"])
    rec, elapsed = [], 0.0
    for f in range(1, frames + 1):
        ctrl.set(np.tile(body(f), (n, 1)))
        wp.synchronize()
        t = time.perf_counter()
        solver.step(a, c, ctrl, 1 / 30)
        wp.synchronize()
        if f > WARM_FRAMES:
            elapsed += time.perf_counter() - t
        a, c = c, a
        rec.append((a.positions.numpy()[:nv].copy(), a.velocities.numpy()[:nv].copy()))
    ms = 1000 * elapsed / (frames - WARM_FRAMES)

    def direct():
        solver.config = dataclasses.replace(solver.config, cuda_graph=False)
        solver.step(a, c, ctrl, 1 / 30)
    _profile(f"drape, {n} scenes, self-collision {'on' if self_col else 'off'}", direct, device)
    mets = [measure(p, v, body(f + 1)) for f, (p, v) in enumerate(rec)]
    return {"ms_per_frame": ms, "garment_frames_per_s": 1000 * n / ms, **_summary(mets, d["recorded_from"])}


class _WorldFilters:
    """Newton's topological self-contact filters, built for one world and copied to the others.

    ``SolverVBD`` builds, in Python, per vertex the triangles and per edge the edges within two
    rings (``tri_mesh_collision.build_vertex_n_ring_tris_collision_filter`` and
    ``build_edge_n_ring_edge_collision_filter``): 35 s for 64 worlds of the T-shirt and 144 s for 256
    on a 2-core CPU, set-up that is not timed but that outlasted a device call. Every world of this
    benchmark is the same mesh at offsets of its vertex, triangle and edge counts, so the filters of
    world w are world 0's shifted by w times those counts. While this context is open, the two
    builders check that the mesh they are given is that repetition (else they build it Newton's
    way) and return the copies. ``check`` builds both ways for a small batch and compares them
    (``--check-filters``)."""

    copied = 0
    """Filters copied (not built) since the module was loaded, for ``check_world_filters``."""

    def __init__(self, worlds: int, vertices: int, triangles: int, edges: int):
        self.worlds, self.nv, self.nt, self.ne = worlds, vertices, triangles, edges

    class Copies(list):
        """World 0's filter sets standing for ``worlds`` copies shifted by ``shift`` each; only
        Newton's ``set_to_csr`` reads them (patched to tile world 0's rows)."""

        def __init__(self, one: list, worlds: int, shift: int):
            super().__init__(one)
            self.worlds, self.shift = worlds, shift

    def __enter__(self):
        from newton._src.geometry import tri_mesh_collision as T

        self.T = T
        self.saved = (T.build_vertex_n_ring_tris_collision_filter, T.build_edge_n_ring_edge_collision_filter,
                      T.set_to_csr)
        vt, ee, csr = self.saved
        T.build_vertex_n_ring_tris_collision_filter = lambda n, count, edges, *adj: self._vertex(vt, n, count, edges, *adj)
        T.build_edge_n_ring_edge_collision_filter = lambda n, edges, *adj: self._edge(ee, n, edges, *adj)
        T.set_to_csr = lambda sets, dtype=np.int32, sort=True: self._csr(csr, sets, dtype, sort)
        return self

    def __exit__(self, *exc):
        (self.T.build_vertex_n_ring_tris_collision_filter, self.T.build_edge_n_ring_edge_collision_filter,
         self.T.set_to_csr) = self.saved

    @staticmethod
    def _csr(set_to_csr, sets, dtype, sort):
        """Newton's CSR of the rows of every world: world 0's rows, shifted (sorted rows stay sorted)."""
        if not isinstance(sets, _WorldFilters.Copies) or not sort:
            return set_to_csr(sets, dtype, sort)
        flat, offsets = set_to_csr(list(sets), dtype, sort)
        total = int(offsets[-1])
        flat_all = np.concatenate([flat + w * sets.shift for w in range(sets.worlds)]).astype(dtype)
        offsets_all = np.concatenate([offsets[:-1] + w * total for w in range(sets.worlds)]
                                     + [np.array([sets.worlds * total])]).astype(dtype)
        return flat_all, offsets_all

    def _repeats(self, edges: np.ndarray) -> bool:
        e = np.asarray(edges)
        if self.worlds < 2 or len(e) != self.worlds * self.ne:
            return False
        one = e[:self.ne]
        shift = np.where(one >= 0, self.nv, 0)
        return all(np.array_equal(e[w * self.ne:(w + 1) * self.ne], one + w * shift) for w in range(self.worlds))

    def _one_world(self, v_adj: np.ndarray, offsets: np.ndarray, rows: int):
        """The first ``rows`` rows of a CSR adjacency (world 0's vertices)."""
        offsets = np.asarray(offsets)[:rows + 1]
        return np.asarray(v_adj)[:int(offsets[-1])], offsets

    def _vertex(self, build, n, count, edges, v_adj_edges, v_adj_edges_offsets, v_adj_tris, v_adj_tris_offsets):
        if count != self.worlds * self.nv or not self._repeats(edges):
            return build(n, count, edges, v_adj_edges, v_adj_edges_offsets, v_adj_tris, v_adj_tris_offsets)
        ae, aeo = self._one_world(v_adj_edges, v_adj_edges_offsets, self.nv)
        at, ato = self._one_world(v_adj_tris, v_adj_tris_offsets, self.nv)
        one = build(n, self.nv, np.asarray(edges)[:self.ne], ae, aeo, at, ato)
        if one is None:
            return None
        _WorldFilters.copied += 1
        return _WorldFilters.Copies(one, self.worlds, self.nt)

    def _edge(self, build, n, edges, v_adj_edges, v_adj_edges_offsets):
        if not self._repeats(edges):
            return build(n, edges, v_adj_edges, v_adj_edges_offsets)
        ae, aeo = self._one_world(v_adj_edges, v_adj_edges_offsets, self.nv)
        one = build(n, np.asarray(edges)[:self.ne], ae, aeo)
        if one is None:
            return None
        _WorldFilters.copied += 1
        return _WorldFilters.Copies(one, self.worlds, self.ne)


def _newton_setup(d, n: int, self_col: bool, device, iterations: int, replicate: bool = True):
    """Newton's model of n worlds of the scene, its collision pipeline and its VBD solver (the
    self-contact filters copied from world 0 when ``replicate``: :class:`_WorldFilters`)."""
    import newton
    import warp as wp

    from datagen.materials import material
    from datagen.sim.solver import SolverConfig

    cfg = SolverConfig()
    mat = material(str(d["material"]))
    E = 0.5 * (mat.stretch_warp + mat.stretch_weft)
    nu = mat.poisson
    mu, lam = E / (2 * (1 + nu)), E * nu / (1 - nu * nu)
    body, body_faces = d["body"], d["body_faces"].astype(np.int32)
    body0 = body(0).astype(np.float32)
    nb = len(body0)

    scene = newton.ModelBuilder(up_axis=newton.Axis.Y)
    world = newton.ModelBuilder(up_axis=newton.Axis.Y)
    world.add_cloth_mesh(pos=wp.vec3(0.0, 0.0, 0.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0, 0.0, 0.0),
                         vertices=d["garment"].astype(np.float32).tolist(), indices=d["faces"].reshape(-1).tolist(),
                         density=mat.density, tri_ke=mu, tri_ka=lam, tri_kd=mat.damping, edge_ke=mat.bending,
                         edge_kd=mat.damping, particle_radius=mat.thickness + cfg.body.margin)
    shape_cfg = newton.ModelBuilder.ShapeConfig(mu=mat.friction, has_shape_collision=False)
    world.add_shape_mesh(body=-1, mesh=newton.Mesh(body0, body_faces.reshape(-1)), cfg=shape_cfg)
    world.color()
    for _ in range(n):
        scene.add_world(world)
    wp.synchronize()
    dev = wp.get_device(device)
    mem0 = wp.get_mempool_used_mem_current(dev) if dev.is_cuda else 0
    model = scene.finalize(device=device)
    model.soft_contact_ke = cfg.body.stiffness
    model.soft_contact_kd = 0.0
    model.soft_contact_mu = mat.friction
    model.particle_mu = cfg.self_contact.friction

    # the body: one points array for every world's body mesh (slices), lerped per substep
    with wp.ScopedDevice(device):
        points = wp.array(np.tile(body0, (n, 1)), dtype=wp.vec3)
        vels = wp.zeros(n * nb, dtype=wp.vec3)
        start = wp.array(np.tile(body0, (n, 1)), dtype=wp.vec3)
        end = wp.array(np.tile(body0, (n, 1)), dtype=wp.vec3)
        tri = wp.array(body_faces.reshape(-1))
        meshes = [wp.Mesh(points=points[s * nb:(s + 1) * nb], velocities=vels[s * nb:(s + 1) * nb], indices=tri)
                  for s in range(n)]
        kinds = model.shape_type.numpy()
        body_shapes = np.flatnonzero(kinds == int(newton.GeoType.MESH))
        assert len(body_shapes) == n
        ptr = model.shape_source_ptr.numpy()
        ptr[body_shapes] = [m.id for m in meshes]
        model.shape_source_ptr.assign(ptr)
        lo, hi = model.shape_collision_aabb_lower.numpy(), model.shape_collision_aabb_upper.numpy()
        lo[body_shapes], hi[body_shapes] = -10.0, 10.0  # the body moves: no culling by its rest bounds
        model.shape_collision_aabb_lower.assign(lo)
        model.shape_collision_aabb_upper.assign(hi)
        radius = model.shape_collision_radius.numpy()
        radius[body_shapes] = 20.0
        model.shape_collision_radius.assign(radius)

        pipeline = newton.CollisionPipeline(model, soft_contact_gap=cfg.body.query)
        contacts = pipeline.contacts()
        with _WorldFilters(n if replicate else 0, len(d["garment"]), len(d["faces"]), model.edge_count // n):
            solver = newton.solvers.SolverVBD(
                model, iterations=iterations, particle_enable_self_contact=self_col,
                particle_self_contact_margin=cfg.self_contact.radius,
                particle_self_contact_gap=cfg.self_contact.query - cfg.self_contact.radius)
    mem = (wp.get_mempool_used_mem_current(dev) - mem0) / n / 2**20 if dev.is_cuda else float("nan")

    return model, solver, pipeline, contacts, meshes, points, vels, start, end, mem


def check_world_filters(d, worlds: int = 3) -> None:
    """Newton's self-contact filters for ``worlds`` worlds on the CPU, built its way and copied from
    world 0 (:class:`_WorldFilters`): the same lists, or an error."""
    before = _WorldFilters.copied
    built = [_newton_setup(d, worlds, True, "cpu", 1, replicate=r)[1].trimesh_collision_detector for r in (False, True)]
    if _WorldFilters.copied != before + 2:
        raise SystemExit("the filters were not copied: the worlds are not one mesh repeated")
    names = ("vertex_triangle_filtering_list", "vertex_triangle_filtering_list_offsets", "edge_filtering_list",
             "edge_filtering_list_offsets")
    for name in names:
        a, b = (getattr(x, name).numpy() for x in built)
        if not np.array_equal(a, b):
            raise SystemExit(f"copied filters differ from Newton's: {name}")
    print(f"Newton's self-contact filters for {worlds} worlds: copied from world 0 = built by Newton "
          f"({len(built[0].edge_filtering_list.numpy())} edge-edge and "
          f"{len(built[0].vertex_triangle_filtering_list.numpy())} vertex-triangle entries)", flush=True)


def run_newton(d, n: int, self_col: bool, frames: int, device, measure: _Measure, substeps: int = 10,
               iterations: int = 10, graph: bool = False) -> dict:
    """Newton's side. ``graph`` False: every substep launched from Python, the body meshes refitted
    one after another (as in the earlier sessions' figures). True (CUDA only): as drape's solver runs,
    a frame's substeps captured once as a CUDA graph and replayed, and the body meshes' refits spread
    over ``REFIT_STREAMS`` CUDA streams that fork from and join the main stream inside the graph."""
    import warp as wp

    from datagen.sim.solver import REFIT_STREAMS, refit_on_streams

    model, solver, pipeline, contacts, meshes, points, vels, start, end, mem = _newton_setup(d, n, self_col, device,
                                                                                           iterations)
    s0, s1 = model.state(), model.state()
    control = model.control()
    body, nb = d["body"], int(d["body_vertices"])
    dev = wp.get_device(device)
    if graph and not dev.is_cuda:
        raise SystemExit("--newton-launch graph needs a CUDA device")
    streams = [wp.Stream(dev) for _ in range(min(REFIT_STREAMS, n))] if graph else []

    sub_dt = 1 / 30 / substeps

    def frame(a, b):
        for k in range(substeps):
            wp.launch(_lerp_body, n * nb, inputs=[start, end, (k + 1) / substeps, 1.0 / (substeps * sub_dt)],
                      outputs=[points, vels], device=device)
            refit_on_streams(meshes, streams, dev)
            pipeline.collide(a, contacts)
            solver.step(a, b, control, contacts, sub_dt)
            a, b = b, a
        wp.copy(start, end)
        return a, b

    graphs: dict = {}  # by id of the frame's input state: the states alternate when substeps is odd
    nv = len(d["garment"])
    rec, elapsed = [], 0.0
    for f in range(1, frames + 1):
        end.assign(np.tile(body(f).astype(np.float32), (n, 1)))
        wp.synchronize()
        t = time.perf_counter()
        if graph and f > 1:  # frame 1 launched directly: Newton allocates what it needs on first use
            key = id(s0)
            if key not in graphs:
                with wp.ScopedCapture(device=dev) as cap:
                    out = frame(s0, s1)
                graphs[key] = (cap.graph, out)
            g, (s0, s1) = graphs[key]
            wp.capture_launch(g)
        else:
            s0, s1 = frame(s0, s1)
        wp.synchronize()
        if f > WARM_FRAMES:
            elapsed += time.perf_counter() - t
        rec.append((s0.particle_q.numpy()[:nv].copy(), s0.particle_qd.numpy()[:nv].copy()))
    ms = 1000 * elapsed / (frames - WARM_FRAMES)
    _profile(f"Newton, {n} worlds, self-contact {'on' if self_col else 'off'}, "
             f"{'refits on streams' if streams else 'refits one after another'}", lambda: frame(s0, s1), dev)
    mets = [measure(p, v, body(f + 1)) for f, (p, v) in enumerate(rec)]
    return {"ms_per_frame": ms, "garment_frames_per_s": 1000 * n / ms, "mb_per_scene": mem,
            **_summary(mets, d["recorded_from"])}


def _kernels():
    import warp as wp

    @wp.kernel
    def lerp_body(start: wp.array(dtype=wp.vec3), end: wp.array(dtype=wp.vec3), a: float, inv_frame: float,
                  points: wp.array(dtype=wp.vec3), vels: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        points[i] = start[i] + a * (end[i] - start[i])
        vels[i] = (end[i] - start[i]) * inv_frame

    return lerp_body


_lerp_body = None
PER_FRAME = False
WARM_FRAMES = 2
"""Frames neither solver is timed on: the first compiles kernels, and drape's solver captures a CUDA
graph on each of its first two (its two states alternate as input and output, one graph each);
Newton's, with ``--newton-launch graph``, captures its frame graph on frame 2."""


def main(argv=None) -> None:
    global _lerp_body, PER_FRAME, PROFILE
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--inputs", default="runs.pkl", help="scenes from sim prepare-runs")
    ap.add_argument("--scene", default="tshirt/walk", help="which of them")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--batches", default="1")
    ap.add_argument("--frames", type=int, default=0,
                    help="simulated frames to run (0: the whole schedule); the first two are not timed (WARM_FRAMES)")
    ap.add_argument("--self", default="on,off", help="self-collision settings to run: on, off or on,off")
    ap.add_argument("--solvers", default="drape,newton")
    ap.add_argument("--newton-launch", default="python",
                    help="how Newton's substeps are launched: python (each from Python, the body meshes refitted one "
                         "after another), graph (a frame captured as a CUDA graph, the refits on CUDA streams, as "
                         "drape's solver runs), or python,graph for both")
    ap.add_argument("--per-frame", action="store_true", help="print scene 0's metrics for every frame")
    ap.add_argument("--profile", type=int, default=0, metavar="K",
                    help="on CUDA, after each solver's timed frames, one more frame launched directly under warp's "
                         "kernel timers: its top K kernels")
    ap.add_argument("--check-filters", action="store_true",
                    help="first check, on the CPU at 3 worlds, that the copied self-contact filters are Newton's own")
    ap.add_argument("--drape-option", action="append", default=[], metavar="KEY=VALUE",
                    help="a SolverConfig field for drape's solver (e.g. body_projection=false); repeatable")
    args = ap.parse_args(argv)
    PER_FRAME = args.per_frame
    PROFILE = args.profile
    if not set(args.newton_launch.split(",")) <= {"python", "graph"}:
        raise SystemExit(f"--newton-launch takes python, graph or python,graph, not {args.newton_launch!r}")
    from datagen.config import load_config, parse_assignments
    from datagen.sim.solver import SolverConfig

    DRAPE_OPTIONS.update(parse_assignments(args.drape_option, "--drape-option"))
    load_config(SolverConfig, DRAPE_OPTIONS)  # unknown fields, wrong types and limits are refused here

    import warp as wp

    wp.config.quiet = True
    wp.init()
    _lerp_body = _kernels()
    d = _load_scene(args.inputs, args.scene)
    frames = min(args.frames, d["frame_count"] - 1) if args.frames else d["frame_count"] - 1
    if frames <= WARM_FRAMES:
        raise SystemExit(f"--frames must exceed {WARM_FRAMES}: the first {WARM_FRAMES} frames are not timed")
    dev = wp.get_device(args.device)
    measure = _Measure(d, dev)
    from datagen.sim.solver import SolverConfig

    cfg = SolverConfig(**DRAPE_OPTIONS)
    try:
        import newton

        newton_version = newton.__version__
    except ImportError:
        newton_version = "not installed"
    print(f"device {dev} ({dev.name}); warp {wp.__version__}; newton {newton_version}; scene {args.scene}: "
          f"{len(d['garment'])} vertices, {len(d['faces'])} faces, {d['material']}; body {d['body_vertices']} vertices; "
          f"{frames} frames at 30 fps ({frames - WARM_FRAMES} timed; recorded from frame {d['recorded_from']}), "
          f"{cfg.steps.substeps} substeps x {cfg.steps.iterations} iterations (both solvers)", flush=True)
    head = (f"{'solver':>7} {'batch':>5} {'self':>5} {'ms/frame':>9} {'g-frames/s':>10} {'pen frames':>10} "
            f"{'max pen v':>9} {'depth mm':>8} {'self-x':>6} {'stretch':>8} {'nan':>4}")
    if args.check_filters:
        check_world_filters(d)
    print(head, flush=True)
    for self_col in [s == "on" for s in args.self.split(",")]:
        for n in [int(b) for b in args.batches.split(",")]:
            for name in args.solvers.split(","):
                if name == "drape":
                    r = run_drape(d, n, self_col, frames, dev, measure)
                    _row(name, n, self_col, r)
                    continue
                for launch in args.newton_launch.split(","):
                    try:
                        r = run_newton(d, n, self_col, frames, dev, measure, substeps=cfg.steps.substeps,
                                       iterations=cfg.steps.iterations, graph=launch == "graph")
                    except Exception as exc:  # a capture Newton refuses: say so, and go on with the other rows
                        if launch != "graph":
                            raise
                        print(f"newton-g {n:5d} {'on' if self_col else 'off':>5} not measured: capturing Newton's "
                              f"frame as a CUDA graph failed: {type(exc).__name__}: {exc}", flush=True)
                        continue
                    _row("newton-g" if launch == "graph" else name, n, self_col, r)


def _row(name: str, n: int, self_col: bool, r: dict) -> None:
    """One line of the table: a solver's time and scene 0's quality at one batch size."""
    print(f"{name:>7} {n:5d} {'on' if self_col else 'off':>5} {r['ms_per_frame']:9.1f} "
          f"{r['garment_frames_per_s']:10.1f} {r['frames_with_penetration']:>4d}/{r['recorded']:<5d} "
          f"{r['max_penetrating_vertices']:9d} {r['max_depth_mm']:8.2f} {r['max_self_intersections']:6d} "
          f"{r['max_stretch']:8.3f} {'yes' if r['nan'] else 'no':>4}", flush=True)
