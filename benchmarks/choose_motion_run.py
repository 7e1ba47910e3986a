"""Choose the motion-generator run and latent by the validation split's generation figures.

``python -m benchmarks choose-motion-run OUT RUN...`` reads ``OUT/eval_<RUN>_val.json`` (``drape evaluate
RUN --split val --json ...``) for each run, prints one line per (run, latent) with FID, recognition
accuracy, diversity and multimodality, and last the run and latent with the lowest generated FID (the
Fréchet distance to the real motions in the recogniser's feature space: realism and label fidelity
at once). Only the validation split is read, so the test split stays unseen by the choice.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", type=Path, help="the folder of the eval_<RUN>_val.json files")
    ap.add_argument("runs", nargs="+", help="the runs' names")
    args = ap.parse_args(argv)
    out, runs = args.out, args.runs
    rows = []
    for run in runs:
        path = out / f"eval_{run}_val.json"
        if not path.is_file():
            print(f"{run}: no {path.name} (its evaluation failed?)")
            continue
        e = json.loads(path.read_text())
        for key, latent in (("generation", "prior"), ("generation_posterior", "posterior")):
            g = e.get(key)
            if not g:
                continue
            r = g["generated"]
            rows.append((r["fid"]["mean"], run, latent))
            speed = (f"speed {r['speed']['mean'] / g['real']['speed']['mean']:4.2f}x of real  "
                     if "speed" in r and g["real"].get("speed", {}).get("mean") else "")
            print(f"{run:16s} {latent:9s} FID {r['fid']['mean']:8.2f}  accuracy {100 * r['accuracy']['mean']:5.1f} %  "
                  f"diversity {r['diversity']['mean']:6.2f}  multimodality {r['multimodality']['mean']:6.2f}  {speed}"
                  f"(real: FID {g['real']['fid']['mean']:.2f}, diversity {g['real']['diversity']['mean']:.2f}, "
                  f"multimodality {g['real']['multimodality']['mean']:.2f})")
    if not rows:
        print("no validation evaluation to choose from", file=sys.stderr)
        return 1
    _, run, latent = min(rows)
    print(f"{run} {latent}")
    return 0
