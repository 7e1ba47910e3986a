"""Cloth simulator throughput: one T-shirt on the regular body walking, and batches of such scenes;
and the long-run check scenes (the six 300-frame runs).

Two steps, so the GPU host needs only numpy and warp:

    python -m benchmarks sim prepare --out sim_inputs.npz      # here: garment, body frames
    python -m benchmarks sim run --inputs sim_inputs.npz --device cuda --batches 1,16,64,256
    python -m benchmarks sim profile --inputs sim_inputs.npz --device cuda --batches 64,256
    python -m benchmarks sim prepare-runs --out runs.pkl --frames 300   # garments x motions
    python -m benchmarks sim run-scenes --inputs runs.pkl --device cuda [--out-dir DIR]

``run`` prints, per batch size and with self-collision on and off: ms per frame, garment-frames
per second, device memory per scene, and the metrics (penetrating vertices, self-intersections,
max stretch) of the last frame of scene 0. ``profile``: each kernel's and each phase's ms per frame.
``run-scenes``: per scene its summary (failure, crossings, penetration, strain) as JSON.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import pickle
import time

import numpy as np

from benchmarks.common import load_runs, play, prepared_batch, run_output, scene_name, solver_settings


def prepare(args) -> None:
    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.body.skeleton import face_parts
    from datagen.garment.types import make_garment
    from datagen.motion.library import make_motion

    model = default_body()
    betas = resolve_betas(model, body="regular")[0]
    g = make_garment(args.garment, model, betas, seed=0, target_edge_length=args.edge)
    motion, _lead = make_motion(args.motion, seed=0, frames=args.frames).with_lead_in(args.lead_in)
    poses = motion.poses.reshape(motion.frame_count, -1)
    verts, _ = model.pose(np.repeat(betas[None], motion.frame_count, 0), poses, motion.trans)
    shift = (verts[0] - np.asarray(model.shaped(betas[None]))[0]).mean(0)
    np.savez_compressed(args.out, garment=g.vertices + shift, faces=g.faces, frames=g.material_frames(),
                        material=g.material.name, body=verts.astype(np.float32), body_faces=model.faces,
                        body_face_part=face_parts(model.weights, model.faces), kind=args.garment, motion=args.motion)
    print(f"wrote {args.out}: {args.garment} {g.vertex_count} vertices, body {verts.shape[1]} vertices x {len(verts)} "
          f"frames of {args.motion}")


def run(args) -> None:
    import warp as wp

    from datagen.sim.metrics import Metrics
    from datagen.sim.solver import SolverConfig

    d = np.load(args.inputs)
    body = d["body"]
    wp.init()
    dev = wp.get_device(args.device)
    print(f"device {dev} ({dev.name}); {scene_name(d)} {len(d['garment'])} vertices, {len(d['faces'])} faces; body "
          f"{body.shape[1]} vertices; {min(args.frames, len(body) - 1)} timed frames at 30 fps, {SolverConfig().substeps} substeps x "
          f"{SolverConfig().iterations} iterations")
    print(f"{'batch':>5} {'self':>5} {'graph':>5} {'ms/frame':>9} {'garment-frames/s':>17} {'MB/scene':>9} {'pen':>5} {'self-x':>6} "
          f"{'stretch':>8}")
    on_off = {"on": True, "off": False}  # a value other than on or off fails here (KeyError)
    for self_col, graph, n in [(on_off[sc], on_off[g], int(b)) for sc in args.self.split(",")
                               for g in args.cuda_graph.split(",")
                               for b in args.batches.split(",")]:
        wp.synchronize()
        mem0 = wp.get_mempool_used_mem_current(dev) if dev.is_cuda else 0
        batch, frames = prepared_batch(d, n, str(dev), args.frames,
                                       SolverConfig(**{**solver_settings(args.set), "self_collision": self_col,
                                                       "cuda_graph": graph}))
        m, solver, a, c, ctrl = batch.model, batch.solver, batch.a, batch.c, batch.control
        metrics = Metrics(m)
        for _ in range(2):  # warm-up: compiles kernels, captures the two graphs (a -> c, c -> a)
            solver.step(a, c, ctrl, 1 / 30)
            a, c = c, a
        wp.synchronize()
        t = time.perf_counter()
        a, c = play(solver, a, c, ctrl, frames[1:])
        wp.synchronize()
        dt = (time.perf_counter() - t) / (len(frames) - 1)
        mem = (wp.get_mempool_used_mem_current(dev) - mem0) / n / 2**20 if dev.is_cuda else float("nan")
        fr = metrics.measure(a, solver)
        print(f"{n:5d} {'on' if self_col else 'off':>5} {'on' if graph else 'off':>5} {dt * 1000:9.1f} {n / dt:17.1f} {mem:9.1f} "
              f"{fr['penetration_count'][0]:5d} {fr['self_intersections'][0]:6d} {fr['stretch_max'][0]:8.3f}",
              flush=True)
        # free this batch's device memory now, not while the next batch is being measured (its
        # MB/scene read -4,586 when the 256-scene batch's pool was released inside the next one's)
        del batch, m, solver, metrics, a, c, ctrl, frames
        gc.collect()
        wp.synchronize()


PHASES = {  # kernel (or native call) -> phase of a substep (the first key found in its name)
    # the body meshes' refit with their winding-number data (before 2026-11-27 counted as detection)
    "bvh_refit_with_solid_angle": "body: pose and refit",
    "body_parts_moved": "body: projection", "add_travel": "body: projection",
    "interpolate_body": "body: pose and refit", "mesh_refit": "body: pose and refit",
    "detect_body": "body: contact query", "predict_body_friction": "body: contact query",
    "body_contact_force": "body: contact query", "project_out_of_body": "body: projection",
    "test_inside_body": "body: projection", "move_out_of_body": "body: projection",
    "face_bounds": "cloth-cloth detection", "edge_bounds": "cloth-cloth detection", "bvh_refit": "cloth-cloth detection",
    "detect_vertex_triangle": "cloth-cloth detection", "detect_edge_edge": "cloth-cloth detection",
    "sort_lists": "cloth-cloth detection", "count_needed": "cloth-cloth detection", "finish_bounds": "cloth-cloth detection",
    "solve_colour": "sweeps", "copy_colour": "sweeps", "chebyshev": "sweeps", "contour_gradients": "untangle", "apply_untangle": "untangle",
}


def _phase(name: str) -> str:
    for key, phase in PHASES.items():
        if key in name:
            return phase
    if any(k in name for k in ("membrane_product", "bending_product", "gather_product", "chunk_dot", "scene_sum", "scene_dot",
                               "cg_", "_linearise", "vertex_force_diagonal", "element_diagonal", "invert_blocks", "apply_step",
                               "warm_start", "record_correction")):
        return "global step"
    if "refit" in name.lower() or "bvh" in name.lower() or "mesh" in name.lower():
        return "BVH/mesh builtins"
    if "memcpy" in name.lower() or "memset" in name.lower() or name.startswith(("copy", "fill", "zero")):
        return "copies and fills"
    return "other per-substep"


def profile(args) -> None:
    """Where a frame's time goes: per kernel and per phase, at each batch size.

    On CUDA, warp's kernel timers (CUDA events around every launch, warp's own builtin kernels
    such as the BVH refits included) time the step launched without a CUDA graph; the same step
    replayed as a graph is timed beside it, the rate the pipeline gets. On the CPU every launch is
    synchronous, so each launch (and each native refit) is timed by the wall clock around it.
    """
    import warp as wp

    from datagen.sim.solver import SolverConfig

    d = np.load(args.inputs)
    wp.init()
    dev = wp.get_device(args.device)
    on_off = {"on": True, "off": False}
    kw = solver_settings(args.set)
    print(f"device {dev} ({dev.name}); {scene_name(d)} {len(d['garment'])} vertices; {args.frames} profiled frames; "
          f"{SolverConfig(**kw)}")
    for self_col, n in [(on_off[sc], int(b)) for sc in args.self.split(",") for b in args.batches.split(",")]:
        launched = SolverConfig(self_collision=self_col, cuda_graph=False, **kw)
        batch, frames = prepared_batch(d, n, str(dev), args.frames + 2, launched)
        m, solver, a, c, ctrl = batch.model, batch.solver, batch.a, batch.c, batch.control
        graph_ms = float("nan")
        for _ in range(2):
            solver.step(a, c, ctrl, 1 / 30)
            a, c = c, a
        if dev.is_cuda:  # the rate as the pipeline runs it: replayed graphs
            solver.config = dataclasses.replace(launched, cuda_graph=True)
            a, c = play(solver, a, c, ctrl, frames[1:3])
            wp.synchronize()
            t = time.perf_counter()
            a, c = play(solver, a, c, ctrl, frames[3:])
            wp.synchronize()
            graph_ms = 1000 * (time.perf_counter() - t) / (len(frames) - 3)
            solver.config = launched
        times: dict[str, list] = {}
        wp.synchronize()
        t = time.perf_counter()
        if dev.is_cuda:
            wp.timing_begin(cuda_filter=wp.TIMING_KERNEL | wp.TIMING_KERNEL_BUILTIN | wp.TIMING_MEMCPY
                            | wp.TIMING_MEMSET)
            a, c = play(solver, a, c, ctrl, frames[3:])
            for r in wp.timing_end():
                times.setdefault(r.name, []).append(r.elapsed)
        else:
            launch, mesh_refit, bvh_refit = wp.launch, wp.Mesh.refit, wp.Bvh.refit

            def timed(name, fn):
                def call(*a_, **k_):
                    t0 = time.perf_counter()
                    out = fn(*a_, **k_)
                    times.setdefault(name(*a_), []).append(1000 * (time.perf_counter() - t0))
                    return out
                return call
            wp.launch = timed(lambda kernel, *_: kernel.key, launch)
            wp.Mesh.refit = timed(lambda *_: "mesh_refit (native)", mesh_refit)
            wp.Bvh.refit = timed(lambda *_: "bvh_refit (native)", bvh_refit)
            try:
                a, c = play(solver, a, c, ctrl, frames[3:])
            finally:
                wp.launch, wp.Mesh.refit, wp.Bvh.refit = launch, mesh_refit, bvh_refit
        wp.synchronize()
        wall_ms = 1000 * (time.perf_counter() - t) / (len(frames) - 3)
        nf = len(frames) - 3
        total = sum(sum(v) for v in times.values()) / nf
        print(f"\n== batch {n}, self-collision {'on' if self_col else 'off'}: {wall_ms:.1f} ms/frame launched "
              f"one by one (timed), {graph_ms:.1f} ms/frame as a CUDA graph, {n / graph_ms * 1000 if dev.is_cuda else n / wall_ms * 1000:.1f} "
              f"garment-frames/s; timed work {total:.1f} ms/frame in {sum(len(v) for v in times.values()) / nf:.0f} launches")
        phases: dict[str, float] = {}
        for name, v in times.items():
            phases[_phase(name)] = phases.get(_phase(name), 0.0) + sum(v) / nf
        for ph, ms in sorted(phases.items(), key=lambda kv: -kv[1]):
            print(f"  {ph:<28} {ms:9.2f} ms/frame {100 * ms / total:5.1f} %")
        print(f"  {'kernel':<44} {'launches/frame':>14} {'ms/frame':>9} {'share':>6} {'us/launch':>9}")
        for name, v in sorted(times.items(), key=lambda kv: -sum(kv[1]))[:args.top]:
            ms = sum(v) / nf
            print(f"  {name[:44]:<44} {len(v) / nf:14.0f} {ms:9.2f} {100 * ms / total:5.1f}% {1000 * ms / (len(v) / nf):9.1f}")
        del batch, m, solver, a, c, ctrl, frames
        gc.collect()
        wp.synchronize()


def prepare_runs(args) -> None:
    """Scenes for the long-run check: each garment on the regular body doing each motion. A garment is
    a shell type (``tshirt``) or a config entry (``pattern:top:0``: a pattern garment, sewn here on the
    CPU with the production settings before it is pickled)."""
    from datagen.body.cache import default_body
    from datagen.generate.garments import build_garment, parse_garment_entry
    from datagen.body.shapes import resolve_betas
    from datagen.garment.types import make_garment
    from datagen.motion.library import make_motion
    from datagen.sim.scene import RunConfig, Scene

    model = default_body()
    body = args.body
    betas = (resolve_betas(model, seed=int(body.split(":", 1)[1])) if body.startswith("seed:")
             else resolve_betas(model, body=body))[0]
    scenes, names = [], []
    for kind in args.garments.split(","):
        if ":" in kind:
            g = build_garment(parse_garment_entry(kind), model, betas, args.edge, RunConfig())
        else:
            g = make_garment(kind, model, betas, seed=args.garment_seed, target_edge_length=args.edge)
        for label in args.motions.split(","):
            motion = make_motion(label, seed=args.motion_seed, frames=RunConfig().motion_frames(args.frames, 30.0))
            scenes.append(Scene(garment=g, body=model, betas=betas, motion=motion))
            names.append(f"{kind}/{label}")
            print(f"{names[-1]}: {g.vertex_count} vertices, {args.frames} frames", flush=True)
    with open(args.out, "wb") as fh:  # our own objects for our own run step (numpy, torch, warp on the host)
        pickle.dump({"scenes": scenes, "names": names}, fh)
    print(f"wrote {args.out}")


def run_scenes(args) -> None:
    """Simulate the prepared scenes as one batch; print each scene's summary and save its metrics."""
    import json
    from pathlib import Path

    from datagen.sim.scene import RunConfig, simulate
    from datagen.sim.solver import SolverConfig

    d = load_runs(args.inputs)
    scenes, names = d["scenes"], d["names"]
    if args.material:
        import dataclasses

        from datagen.config import parse_assignments

        kw = parse_assignments(args.material)
        scenes = [dataclasses.replace(sc, garment=dataclasses.replace(
            sc.garment, material=dataclasses.replace(sc.garment.material, **kw))) for sc in scenes]
        print(f"every garment's material with {kw}")
    lead_in = RunConfig().lead_in if args.lead_in is None else args.lead_in
    config = RunConfig(lead_in=lead_in, freeze_failed=args.freeze_failed,
                       solver=SolverConfig(self_collision=not args.no_self_collision,
                                           body_projection=not args.no_projection,
                                           body_friction=not args.no_body_friction,
                                           **({} if args.friction_pressure is None else
                                              {"friction_pressure": args.friction_pressure}),
                                           **({} if args.global_iterations is None else
                                              {"global_iterations": args.global_iterations}),
                                           **solver_settings(args.set)))
    print(f"{len(scenes)} scenes in one batch, device {args.device}, {config}", flush=True)
    t0 = time.perf_counter()

    def progress(done, total):
        if done % 50 == 0 or done == total:
            el = time.perf_counter() - t0
            print(f"  frame {done}/{total}  {el:.0f} s  {1000 * el / done:.0f} ms/frame", flush=True)

    results = simulate(scenes, config, device=args.device, progress=progress)
    out = Path(args.out_dir) if args.out_dir else None
    if out:
        out.mkdir(parents=True, exist_ok=True)
    from datagen.sim.metrics import principal_strain

    frames = len(results[0].metrics["nan"])
    print(f"{1000 * results[0].seconds / frames:.1f} ms per batch frame ({frames} frames, {len(scenes)} scenes)")
    for name, scene, r in zip(names, scenes, results):
        summary = r.summary()
        # the largest principal strain of every triangle against the garment's rest shape (a pattern
        # garment's cut, per corner), recorded frames
        strain = principal_strain(scene.garment.vertices, scene.garment.faces, r.positions,
                                  rest_corners=scene.garment.face_uv if getattr(scene.garment, "kind", "shell") == "pattern"
                                  else None)
        summary.update({f"strain_{q}": float(np.percentile(strain, v)) for q, v in (("p50", 50), ("p90", 90),
                                                                                    ("p99", 99))},
                       strain_max=float(strain.max()), material=scene.garment.material.name)
        print(f"{name}: {json.dumps(summary)}")
        if out:
            np.savez_compressed(run_output(out, name),
                                **{f"metric_{k}": v for k, v in r.metrics.items()}, recorded_from=r.recorded_from,
                                positions=r.positions[::10], body=r.body_vertices[::10])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("prepare")
    p.add_argument("--out", default="sim_inputs.npz")
    p.add_argument("--frames", type=int, default=30)
    p.add_argument("--edge", type=float, default=0.016, help="garment edge length (m): 0.016 gives about 4,000 vertices")
    p.add_argument("--lead-in", type=float, default=0.3, help="seconds from the rest pose to the motion's first pose")
    p.add_argument("--garment", default="tshirt", help="garment type (seed 0, on the regular body)")
    p.add_argument("--motion", default="walk", help="motion label (seed 0)")
    p.set_defaults(func=prepare)
    p = sub.add_parser("run")
    p.add_argument("--inputs", default="sim_inputs.npz")
    p.add_argument("--device", default="cpu")
    p.add_argument("--batches", default="1")
    p.add_argument("--frames", type=int, default=30, help="timed frames (after two warm-up frames)")
    p.add_argument("--cuda-graph", default="on", help="on, off or on,off: replay each step as a CUDA graph (CUDA only)")
    p.add_argument("--self", default="on,off", help="self-collision settings to run: on, off or on,off")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a SolverConfig field (repeatable)")
    p.set_defaults(func=run)
    p = sub.add_parser("profile", help="time per kernel and per phase of a frame")
    p.add_argument("--inputs", default="sim_inputs.npz")
    p.add_argument("--device", default="cpu")
    p.add_argument("--batches", default="1")
    p.add_argument("--frames", type=int, default=3, help="profiled frames (after warm-up frames)")
    p.add_argument("--self", default="on", help="self-collision settings to run: on, off or on,off")
    p.add_argument("--top", type=int, default=25, help="kernels listed")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a SolverConfig field (repeatable)")
    p.set_defaults(func=profile)
    p = sub.add_parser("prepare-runs", help="scenes for the long-run check (garments x motions)")
    p.add_argument("--out", default="sim_runs.pkl")
    p.add_argument("--garments", default="tshirt,dress,pants")
    p.add_argument("--motions", default="walk,dance_disco")
    p.add_argument("--frames", type=int, default=300)
    p.add_argument("--body", default="regular")
    p.add_argument("--garment-seed", type=int, default=0)
    p.add_argument("--edge", type=float, default=None, help="garment edge length (m); default: the type's")
    p.add_argument("--motion-seed", type=int, default=0)
    p.set_defaults(func=prepare_runs)
    p = sub.add_parser("run-scenes", help="simulate prepared scenes in one batch, print their summaries")
    p.add_argument("--inputs", default="sim_runs.pkl")
    p.add_argument("--device", default="cpu")
    p.add_argument("--no-self-collision", action="store_true")
    p.add_argument("--no-projection", action="store_true", help="turn the end-of-substep body projection off")
    p.add_argument("--no-body-friction", action="store_true", help="turn friction with the body off (diagnosis)")
    p.add_argument("--lead-in", type=float, default=None, help="seconds (default: RunConfig's)")
    p.add_argument("--freeze-failed", action="store_true",
                   help="stop simulating a scene once it fails, as drape generate does (default here: run every "
                        "scene to the end, so a failed scene's later metrics are reported as before)")
    p.add_argument("--friction-pressure", type=float, default=None, help="Pa (default: SolverConfig's)")
    p.add_argument("--global-iterations", type=int, default=None,
                   help="conjugate-gradient iterations of the global step (default: SolverConfig's; 0: sweeps alone)")
    p.add_argument("--out-dir", default=None, help="per-scene metrics (.npz) go here")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a SolverConfig field (repeatable)")
    p.add_argument("--material", action="append", default=[], metavar="KEY=VALUE",
                   help="a Material field set on every scene's garment (repeatable; a sweep)")
    p.set_defaults(func=run_scenes)
    args = ap.parse_args(argv)
    args.func(args)
