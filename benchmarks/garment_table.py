"""Tables 6/7/9 of paper 001's garment regressor from ``drape evaluate`` JSON files.

``python -m benchmarks garment-table OUT`` reads every ``OUT/eval_<RUN>_val.json`` and
``OUT/eval_<RUN>_test.json`` of a garment regressor run and prints, per template, one row per run
(validation RMSE; test RMSE, Hausdorff, STED, normal cosine and the share of vertices inside the
body) and the skinned template's test row (and the simulated garment's share inside, the reference:
eq. 4's test judges a vertex by its closest body vertex's normal), and marks per template the run with the lowest
validation RMSE: the choice is made on the validation split only, and the test split is reported
for every run beside it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def _inside(row: dict) -> str:
    """The share of garment vertices inside the body, % (evaluations from before it was reported: -)."""
    return f"{100 * row['inside_share']:8.2f}" if "inside_share" in row else f"{'-':>8s}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", type=Path, help="the folder of the eval_<RUN>_val.json and eval_<RUN>_test.json files")
    out = ap.parse_args(argv).out
    runs: dict[str, dict[str, dict]] = {}
    for path in sorted(out.glob("eval_*_*.json")):
        run, split = path.stem[len("eval_"):].rsplit("_", 1)
        e = json.loads(path.read_text())
        if e.get("kind") == "garment":
            runs.setdefault(run, {})[split] = e
    if not runs:
        print(f"no garment evaluations in {out}")
        return 1
    by_garment: dict[str, list[str]] = {}
    for run, e in runs.items():
        any_e = e.get("test") or e.get("val")
        by_garment.setdefault(any_e["garment"], []).append(run)
    head = (f"{'run':28s} {'frame':12s} {'BOS':8s} {'val RMSE cm':>11s} | {'test RMSE cm':>12s} {'Hausdorff dm':>12s} "
            f"{'STED x1e-2':>10s} {'normal cos':>10s} {'inside %':>8s}")
    for garment, names in sorted(by_garment.items()):
        val = {n: _rmse(runs[n]["val"]["model"]) for n in names if "val" in runs[n]}
        chosen = min(val, key=val.get) if val else None
        print(f"\n{garment}: chosen on the validation split: {chosen}")
        print(head)
        base = None
        for n in sorted(names):
            e = runs[n].get("test")
            v = f"{100 * val[n]:11.2f}" if n in val else f"{'-':>11s}"
            meta = e or runs[n]["val"]
            row = (f"{n + (' *' if n == chosen else ''):28s} {meta.get('relative_to', 'translation'):12s} "
                   f"{meta['bos']:8s} {v} | ")
            if e:
                m = e["model"]
                row += (f"{100 * _rmse(m):12.2f} {10 * m['hausdorff']:12.3f} {100 * m['sted']:10.1f} "
                        f"{m['normal_cosine']:10.4f} {_inside(m)}   ({e['segments']} segments)")
                base, e_base = e["skinned_baseline"], e
            else:
                row += "no test evaluation"
            print(row)
        if base:
            print(f"{'skinned template':28s} {'':12s} {'':8s} {'':11s} | {100 * _rmse(base):12.2f} "
                  f"{10 * base['hausdorff']:12.3f} {100 * base['sted']:10.1f} {base['normal_cosine']:10.4f} "
                  f"{_inside(base)}")
            if "simulated_inside_share" in e_base:
                print(f"{'simulated garment':28s} {'':12s} {'':8s} {'':11s} | {'':12s} {'':12s} {'':10s} {'':10s} "
                      f"{100 * e_base['simulated_inside_share']:8.2f}")
    return 0


def _rmse(row: dict) -> float:
    """The per-coordinate vertex RMSE of an evaluation row (``rmse`` in evaluations before issue 62)."""
    return row["vertex_rmse_per_coordinate"] if "vertex_rmse_per_coordinate" in row else row["rmse"]

