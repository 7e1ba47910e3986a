"""Strain in a store's recorded garments, per material: the largest principal strain of every
triangle of every recorded frame against its garment's rest mesh
(:func:`datagen.sim.metrics.principal_strain`), as median, p90, p99 and max, per material and per
sample. Reads the store through its reader alone.

    python -m benchmarks garment-strain STORE [--every 1]
"""

from __future__ import annotations

import argparse
from collections import defaultdict

import numpy as np

from datagen.sim.metrics import principal_strain
from datagen.store import open_store


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("store")
    ap.add_argument("--every", type=int, default=1, help="use every k-th recorded frame")
    args = ap.parse_args(argv)
    store = open_store(args.store)
    materials, types = store.names["material_names"], store.names["garment_type_names"]
    per_material = defaultdict(list)
    print(f"{'sample':>6} {'garment':<14} {'material':<10} {'frames':>6} {'p50 %':>7} {'p99 %':>7} {'max %':>7}")
    for i in range(len(store)):
        sc = store.scalars(i)
        if int(sc["failure"]) != 0:
            g = store.garment(int(sc["garment"]))
            print(f"{i:6d} {types[int(g['type'])]:<14} failed: {store.names['failure_names'][int(sc['failure'])]} at "
                  f"frame {int(sc['failure_frame'])}")
            continue
        g = store.garment(int(sc["garment"]))
        x = store.sample(i, names=["detail"])["detail"][::args.every]
        s = principal_strain(g["rest_vertices"], g["faces"], x).ravel()
        mat = materials[int(g["material"])]
        per_material[mat].append(s)
        print(f"{i:6d} {types[int(g['type'])]:<14} {mat:<10} {len(x):6d} "
              f"{100 * np.median(s):7.2f} {100 * np.percentile(s, 99):7.2f} {100 * s.max():7.2f}")
    print(f"\n{'material':<10} {'triangle-frames':>16} {'median %':>9} {'p90 %':>7} {'p99 %':>7} {'max %':>7}")
    for mat, parts in sorted(per_material.items()):
        s = np.concatenate(parts)
        print(f"{mat:<10} {len(s):16,d} {100 * np.median(s):9.2f} {100 * np.percentile(s, 90):7.2f} "
              f"{100 * np.percentile(s, 99):7.2f} {100 * s.max():7.2f}")
