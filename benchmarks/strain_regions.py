"""Where the strain of the six check runs sits: for each run, the triangles above its p99 strain
(largest principal strain against the rest mesh), their share per panel, per named opening (the
faces touching the loop), on boundaries and seams, and the p99 of each saved frame.

    python -m benchmarks sim run-scenes --inputs .simbench/runs.pkl --device cuda --out-dir DIR
    python -m benchmarks strain-regions .simbench/runs.pkl DIR
"""

from __future__ import annotations

import argparse
import pickle
from pathlib import Path

import numpy as np

from datagen.sim.metrics import principal_strain


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", help="the prepared runs (sim prepare-runs)")
    ap.add_argument("out_dir", help="the run's --out-dir (positions of every 10th recorded frame)")
    args = ap.parse_args(argv)
    with open(args.inputs, "rb") as fh:  # our own objects, from our own prepare step
        d = pickle.load(fh)
    for name, scene in zip(d["names"], d["scenes"]):
        path = Path(args.out_dir) / f"{name.replace('/', '_')}.npz"
        if not path.is_file():
            continue
        g = scene.garment
        s = principal_strain(g.vertices, g.faces, np.load(path)["positions"])
        high = s > np.percentile(s, 99)

        def share(face_mask):
            return round(float(high[:, face_mask].sum() / high.sum()), 2)

        panels = {g.region_names[r]: share(g.face_region == r) for r in range(len(g.region_names))}
        loops = {}
        for loop, verts in g.loops.items():
            on = np.zeros(len(g.vertices), bool)
            on[verts] = True
            loops[loop] = share(on[g.faces].any(1))
        seam = g.seam_vertex[g.faces].any(1)
        print(f"{name}: p99 {100 * np.percentile(s, 99):.1f} %; above it: panels {panels}, openings {loops}, "
              f"seams {share(seam)} (of faces {seam.mean():.2f})")
        print("   p99 per saved frame %: " + " ".join(f"{100 * np.percentile(f, 99):.0f}" for f in s))
