"""How many of a substep's cloth-cloth re-detections a scene could skip: the sweeps re-detect every
``detection_interval`` sweeps (renewing the contact lists and every vertex's move bound at the
current positions); a scene none of whose vertices has moved ``delta`` since its last detection
gains nothing from it when ``delta`` is at most half the gap between the contact registration
distance (1.5 x ``self_radius``) and the force range (``self_radius``): no pair unregistered then
can have come into range, and every vertex still has most of its bound (at least
0.45 x 6 mm = 2.7 mm) left. The probe runs one garment through the pipeline on the CPU and,
through ``SolverVBD.sweep_trace``, reads the positions after every sweep and replays that policy on
the moving substeps. An estimate for one scene, not a measurement of a solver that skips (its
own trajectory would differ a little).

    python benchmarks/detection_skip_probe.py [--garment tshirt] [--motion walk] [--frames 10]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


class Replay(list):
    """A ``SolverVBD.sweep_trace`` that replays the policy on the solver's real positions: after
    every sweep it reads the positions; at each scheduled re-detection it skips when no vertex is
    ``delta`` or more from where the policy's last detection saw it (the substep's first detection,
    at the substep's start, always happens). Keeps per substep how many were skipped."""

    def __init__(self, deltas: list[float], interval: int, iterations: int):
        super().__init__()
        self.deltas, self.interval, self.iterations = deltas, interval, iterations
        self.solver = None
        self.skipped: list[list[int]] = []  # per substep, per delta

    def append(self, item) -> None:
        _, it, _, _, _ = item
        x = self.solver._probe_x.numpy().astype(np.float64)
        if it == 0:
            self.ref = [self.solver.x_det.numpy().astype(np.float64) for _ in self.deltas]
            self.skipped.append([0] * len(self.deltas))
        if (it + 1) % self.interval == 0 and it + 1 < self.iterations:
            for k, delta in enumerate(self.deltas):
                if np.linalg.norm(x - self.ref[k], axis=1).max() < delta:
                    self.skipped[-1][k] += 1
                else:
                    self.ref[k] = x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--garment", default="tshirt")
    ap.add_argument("--motion", default="walk", help="comma-separated motion labels (seed 0)")
    ap.add_argument("--frames", type=int, default=10, help="recorded frames after settling, lead-in and ramp")
    ap.add_argument("--deltas", default="0.0005,0.001,0.002", help="thresholds to replay (m)")
    args = ap.parse_args()
    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.garment.types import make_garment
    from datagen.motion.library import make_motion
    from datagen.sim.scene import RunConfig, Scene, simulate
    from datagen.sim.solver import SolverVBD

    body = default_body()
    betas = resolve_betas(body, body="regular")[0]
    garment = make_garment(args.garment, body, betas, seed=0)
    rc = RunConfig()
    cfg = rc.solver
    print(f"{args.garment} ({garment.vertex_count} vertices) on the CPU, {cfg.substeps} substeps x {cfg.iterations} "
          f"sweeps, re-detection every {cfg.detection_interval} sweeps; self_radius {cfg.self_radius * 1e3:g} mm")
    print(f"{'motion':<14} {'delta mm':>8} {'skippable':>10} {'of':>6} {'share':>6}")
    for label in args.motion.split(","):
        motion = make_motion(label, seed=0, frames=rc.motion_frames(args.frames, 30.0), fps=30.0)
        deltas = [float(d) for d in args.deltas.split(",")]
        trace = Replay(deltas, cfg.detection_interval, cfg.iterations)
        original = SolverVBD._step

        def traced_step(self, state, control, dt):  # the positions the sweeps move, for the replay
            self._probe_x, trace.solver = state.positions, self
            return original(self, state, control, dt)

        SolverVBD.sweep_trace, SolverVBD._step = trace, traced_step
        t0 = time.perf_counter()
        try:
            simulate([Scene(garment=garment, body=body, betas=betas, motion=motion)], rc, device="cpu")
        finally:
            SolverVBD.sweep_trace, SolverVBD._step = None, original
        moving = np.array(trace.skipped[-(args.frames + rc.phases(args.frames, 30.0)["ramp"]) * cfg.substeps:])
        scheduled = len(moving) * ((cfg.iterations - 1) // cfg.detection_interval)
        for k, delta in enumerate(deltas):
            skipped = int(moving[:, k].sum())
            print(f"{label:<14} {delta * 1e3:8.2f} {skipped:10d} {scheduled:6d} {skipped / scheduled:6.1%}", flush=True)
        print(f"  ({time.perf_counter() - t0:.0f} s; {len(moving)} moving substeps)")


if __name__ == "__main__":
    main()
