"""The fit attribute α of a preset's garment instances, per split, against the training split's range:
where the test garments' α lies among the training garments' (no simulation: garments, bodies and
the factor analysis only; a few seconds with the garment cache).

    python benchmarks/alpha_of_preset.py [--preset medium | --config FILE]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from datagen.generate.config import resolve_config  # noqa: E402
from datagen.generate.plan import Plan, fit_alpha  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--preset", default="medium")
    ap.add_argument("--config", default=None, help="a dataset config file instead of a preset")
    args = ap.parse_args()
    plan = Plan(resolve_config(args.config, preset=None if args.config else args.preset))
    garments = [plan.garment(g) for g in range(len(plan.instances))]
    alpha, _, diagnostics = fit_alpha(plan, garments)
    splits: dict[int, set] = {}
    for s in plan.scenes:
        splits.setdefault(s.garment, set()).add(s.split)
    train = sorted(g for g, sp in splits.items() if "train" in sp)
    lo, hi = alpha[train].min(0), alpha[train].max(0)
    print(f"{args.config or args.preset}: {len(plan.instances)} garment instances, α fitted on {len(train)} training pairs; "
          f"training range {np.round(lo, 2)} .. {np.round(hi, 2)}")
    designs = {}
    for g in train:
        designs.setdefault(plan.instances[g][0], []).append(alpha[g])
    centres = {d: np.mean(a, 0) for d, a in designs.items()}
    print("split     garment              body       α                        outside the training range "
          "(share of it)   nearest training design (distance)")
    for g, (garment, body) in enumerate(plan.instances):
        a = alpha[g]
        out = np.where(a > hi, (a - hi) / (hi - lo), np.where(a < lo, (a - lo) / (hi - lo), 0.0))
        near = min(centres, key=lambda d: np.linalg.norm(centres[d] - a))
        print(f"{'/'.join(sorted(splits.get(g, ()))):9s} {garment:20s} {body:10s} {np.array2string(a, precision=2):24s} "
              f"{np.array2string(out, precision=2):38s} {near} ({np.linalg.norm(centres[near] - a):.2f})")
    names = list(centres)
    if len(names) > 1:
        gaps = [min(np.linalg.norm(centres[a] - centres[b]) for b in names if b != a) for a in names]
        print(f"training designs: {len(names)}; each one's distance to the nearest other: median {np.median(gaps):.2f}, "
              f"range {min(gaps):.2f} .. {max(gaps):.2f}")
    for w in diagnostics.get("warnings", []):
        print("warning:", w)


if __name__ == "__main__":
    main()
