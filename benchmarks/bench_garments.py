"""Garments over many seeds and bodies: vertex counts, build time, mesh quality, check failures.

    python benchmarks/bench_garments.py --seeds 10 --bodies thin,regular,fat

Per type: vertex count range, mean build time per garment (construction only; checks excluded),
the worst minimum angle and its 1st percentile, edge-length spread, minimum clearance, and how
many garments failed which check (topology, boundary loops, self-intersection, penetration).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from datagen.body.cache import default_body
from datagen.body.shapes import resolve_betas
from datagen.garment.checks import check_garment
from datagen.garment.types import GARMENT_TYPES, make_garment


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--bodies", default="thin,regular,fat")
    ap.add_argument("--types", default=",".join(GARMENT_TYPES))
    ap.add_argument("--edge-length", type=float, default=None, help="default: each type's own")
    args = ap.parse_args()
    model = default_body()
    bodies = {b: resolve_betas(model, body=b)[0] for b in args.bodies.split(",")}
    shaped = {b: np.asarray(model.shaped(beta))[0] for b, beta in bodies.items()}
    print(f"{args.seeds} seeds x {len(bodies)} bodies ({args.bodies}) per type, edge length {args.edge_length or 'each type default'}")
    head = (f"{'type':18s} {'n':>4s} {'vertices':>11s} {'build s':>7s} {'min angle':>9s} {'p1 angle':>8s} "
            f"{'spread':>6s} {'clear mm':>8s} {'failed':>6s}  failures")
    print(head)
    print("-" * len(head))
    total_fail = 0
    for kind in args.types.split(","):
        counts, times, angles, p1, spread, clear, fails = [], [], [], [], [], [], Counter()
        failed = 0
        for body, betas in bodies.items():
            for seed in range(args.seeds):
                t0 = time.perf_counter()
                try:
                    g = make_garment(kind, model, betas, seed=seed, target_edge_length=args.edge_length)
                except Exception as exc:  # a build that raises is a failure to report, not to hide
                    fails[f"build error {type(exc).__name__}"] += 1
                    failed += 1
                    continue
                times.append(time.perf_counter() - t0)
                c = check_garment(g, shaped[body], model.faces)
                counts.append(g.vertex_count)
                angles.append(c["min_angle_deg"])
                p1.append(c["angle_p1_deg"])
                spread.append(c["edge_spread"])
                clear.append(c["min_clearance"])
                if not c["ok"]:
                    failed += 1
                    for f in c["failures"]:
                        fails[f.split(" (")[0] if "penetrates" in f else (f.split(",")[0] if "loops" in f else f)] += 1
        total_fail += failed
        n = len(bodies) * args.seeds
        print(f"{kind:18s} {n:4d} {min(counts):5d}-{max(counts):<5d} {np.mean(times):7.2f} {min(angles):9.1f} "
              f"{np.mean(p1):8.1f} {np.mean(spread):6.2f} {1000 * min(clear):8.1f} {failed:6d}  "
              f"{'; '.join(f'{k} x{v}' for k, v in fails.items())}", flush=True)
    print(f"failed garments in all: {total_fail}")


if __name__ == "__main__":
    main()
