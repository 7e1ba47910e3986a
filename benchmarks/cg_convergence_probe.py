"""How far the global step's conjugate gradients get, iteration by iteration, on the long runs' scenes.

For each scene of ``bench_sim.py prepare-runs`` named (default: the T-shirt and the denim pants
walking), drape's solver at its production settings steps the scene's schedule (settle, lead-in,
ramp, motion) for ``--frames`` frames with ``SolverVBD.cg_trace`` on, and prints, over every substep's
global step, how many iterations the preconditioned residual rᵀP⁻¹r took to fall below τ² of its
start for several τ (the iterations a per-scene stopping rule at τ would run), and where it ends
after all of them. A probe: the trace syncs the device after every iteration.

    python benchmarks/cg_convergence_probe.py --inputs .simbench/runs.pkl --frames 60
"""

from __future__ import annotations

import argparse
import time

import numpy as np

TAUS = (1e-1, 3e-2, 1e-2, 3e-3, 1e-3)


def probe(d, frames: int, device: str, options: dict) -> list[np.ndarray]:
    """The cg_trace of one scene over ``frames`` frames (one [iterations + 1] array a substep)."""
    from datagen.sim.model import ClothModelBuilder
    from datagen.sim.solver import SolverConfig, SolverVBD
    from datagen.sim.state import BodyControl, ClothState

    b = ClothModelBuilder()
    b.add_cloth(d["garment"], d["faces"], material_name=str(d["material"]), scene=0, material_frames=d["frames"])
    b.add_body(d["body"](0), d["body_faces"], scene=0, face_part=d["body_face_part"])
    m = b.finalize(device)
    solver = SolverVBD(m, SolverConfig(**options))
    solver.cg_trace = []
    a, c = ClothState.from_model(m), ClothState.from_model(m)
    ctrl = BodyControl.from_numpy(m, d["body"](0))
    solver.reset_body(ctrl)
    for f in range(1, frames + 1):
        ctrl.set(d["body"](f))
        solver.step(a, c, ctrl, 1 / 30)
        a, c = c, a
    return [t[:, 0] for t in solver.cg_trace]


def report(name: str, traces: list[np.ndarray]) -> None:
    rz = np.stack(traces)  # [substeps, iterations + 1]
    start = rz[:, :1]
    ratio = np.sqrt(np.maximum(rz, 0.0) / np.where(start > 0, start, 1.0))  # ‖r‖_P⁻¹ relative to its start
    iters = rz.shape[1] - 1
    print(f"{name}: {len(rz)} global steps of {iters} iterations; residual after all of them: median "
          f"{np.median(ratio[:, -1]):.2e}, 90th percentile {np.percentile(ratio[:, -1], 90):.2e}, "
          f"largest {ratio[:, -1].max():.2e}", flush=True)
    print(f"  {'tau':>7} {'reached':>8} {'iterations: median':>19} {'p90':>5} {'max':>5} {'mean':>6} "
          f"{'share of all':>12}", flush=True)
    for tau in TAUS:
        below = ratio <= tau
        reached = below.any(1)
        first = np.where(reached, below.argmax(1), iters)
        print(f"  {tau:7.0e} {reached.mean():8.1%} {np.median(first):19.0f} {np.percentile(first, 90):5.0f} "
              f"{first.max():5d} {first.mean():6.1f} {first.sum() / (iters * len(rz)):12.1%}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--inputs", default=".simbench/runs.pkl", help="scenes from bench_sim.py prepare-runs")
    ap.add_argument("--scenes", default="tshirt/walk,pants/walk")
    ap.add_argument("--frames", type=int, default=60, help="simulated frames of each scene's schedule")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a SolverConfig field")
    args = ap.parse_args()
    from bench_newton import _load_scene

    from datagen.config import load_config, parse_assignments
    from datagen.sim.solver import SolverConfig

    options = parse_assignments(args.set, "--set")
    load_config(SolverConfig, options)
    import warp as wp

    wp.config.quiet = True
    wp.init()
    for name in args.scenes.split(","):
        d = _load_scene(args.inputs, name)
        t = time.perf_counter()
        traces = probe(d, min(args.frames, d["frame_count"] - 1), args.device, options)
        print(f"[{name}, {d['material']}, {len(d['garment'])} vertices: {time.perf_counter() - t:.0f} s]", flush=True)
        report(name, traces)


if __name__ == "__main__":
    main()
