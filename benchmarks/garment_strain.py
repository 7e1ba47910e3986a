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

from benchmarks.common import Benchmark, print_table
from datagen.sim.metrics import principal_strain
from datagen.store import open_store


class GarmentStrain(Benchmark):
    description = __doc__

    def add_arguments(self, ap: argparse.ArgumentParser) -> None:
        ap.add_argument("store")
        ap.add_argument("--every", type=int, default=1, help="use every k-th recorded frame")

    def setup(self, args):
        return open_store(args.store), args.every

    def run(self, inputs) -> tuple[list, dict]:
        """Per sample (index, garment type, material or failure, frames, strains (triangle-frames,)),
        and every material's strains."""
        store, every = inputs
        materials, types = store.names["material_names"], store.names["garment_type_names"]
        samples, per_material = [], defaultdict(list)
        for i in range(len(store)):
            sc = store.scalars(i)
            g = store.garment(int(sc["garment"]))
            if int(sc["failure"]) != 0:
                failure = f"failed: {store.names['failure_names'][int(sc['failure'])]} at frame {int(sc['failure_frame'])}"
                samples.append((i, types[int(g["type"])], failure, 0, None))
                continue
            x = store.sample(i, names=["detail"])["detail"][::every]
            cut = g.get("rest_uv")  # a pattern garment's cut per corner (NaN for a shell): the simulator's rest
            cut = cut if cut is not None and np.isfinite(cut).all() else None
            s = principal_strain(g["rest_vertices"], g["faces"], x, rest_corners=cut).ravel()
            mat = materials[int(g["material"])]
            per_material[mat].append(s)
            samples.append((i, types[int(g["type"])], mat, len(x), s))
        return samples, {m: np.concatenate(p) for m, p in sorted(per_material.items())}

    def report(self, result) -> None:
        samples, per_material = result
        pct = lambda s, q: f"{100 * np.percentile(s, q):.2f}"  # noqa: E731
        print_table(("sample", "garment", "material", "frames", "p50 %", "p99 %", "max %"),
                    [(i, kind, mat, n, *((pct(s, 50), pct(s, 99), pct(s, 100)) if s is not None else ("", "", "")))
                     for i, kind, mat, n, s in samples])
        print()
        print_table(("material", "triangle-frames", "median %", "p90 %", "p99 %", "max %"),
                    [(m, len(s), pct(s, 50), pct(s, 90), pct(s, 99), pct(s, 100)) for m, s in per_material.items()],
                    ("", ","))


main = GarmentStrain().main
