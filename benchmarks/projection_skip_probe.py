"""How many of the projection's inside tests the skip leaves out (``projection_kernels.may_have_entered``), per
frame, on the first scene of ``bench_sim.py prepare``'s inputs, and whether the positions are
bitwise those of testing every vertex (``projection_skip=false``) in the same run.

    python benchmarks/projection_skip_probe.py [--inputs .simbench/sim_inputs.npz] [--frames 12]

(`docs/bench/projection_skip_cpu/`: 13 of 13 frames bitwise equal on the T-shirt walk.)

Printed per frame: the vertices skipped in the frame's last substep, the median and 10th percentile
of the vertices' distance bounds (the smallest over body parts), and the largest body part's move
relative to the scene's reference vertex in the frame (the sum of its substeps' largest moves).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import warp as wp

sys.path.insert(0, str(Path(__file__).parent))
from bench_sim import _batch, _play  # noqa: E402

from datagen.sim.solver import SolverConfig  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--inputs", default=".simbench/sim_inputs.npz")
ap.add_argument("--frames", type=int, default=12)
ap.add_argument("--device", default="cpu")
args = ap.parse_args()
wp.config.quiet = True
wp.init()
d = np.load(args.inputs)
runs = {}
for skip in (True, False):
    m, solver, _metrics, a, c, ctrl, frames = _batch(d, 1, args.device, args.frames,
                                                     SolverConfig(cuda_graph=False, projection_skip=skip))
    xs, last = [], np.zeros(m.body_part_count)
    for k in range(len(frames)):
        a, c = _play(solver, a, c, ctrl, frames[k:k + 1])
        xs.append(a.positions.numpy().copy())
        if skip:
            skipped = int(solver.projection_skipped.numpy().sum())
            bound = solver.check_bound.numpy().min(1)
            travel = solver.body_travel.numpy()[0]
            known = bound[bound > 0]
            print(f"frame {k}: tests skipped {skipped} of {len(bound)}; distance bound median "
                  f"{1000 * np.median(known) if len(known) else 0:.1f} mm, p10 "
                  f"{1000 * np.percentile(known, 10) if len(known) else 0:.1f} mm; largest part's move "
                  f"{1000 * (travel - last).max():.1f} mm")
            last = travel.copy()
    runs[skip] = xs
same = [np.array_equal(p, q) for p, q in zip(runs[True], runs[False])]
print(f"positions with the skip bitwise those without it in {sum(same)} of {len(same)} frames")
