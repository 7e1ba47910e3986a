"""Compare two drape stores array by array (e.g. one made on one GPU against one made by the Ray
executor on several): which arrays are bitwise equal, and the largest difference of the others.

    python -m benchmarks compare-stores A.zarr B.zarr [--skip samples/seconds] [--json out.json]

Wall time per sample (``samples/seconds``) differs between any two runs and is skipped by default;
the ``checksums`` attribute differs with it. Garment positions are compared in the store's own
quantised steps (``vertex_frames/*``: int32 steps of ``POSITION_QUANTUM``) and in millimetres.
Exit status 0 when every compared array is equal, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from benchmarks.common import Benchmark
from schemas.dataset import ARRAYS, POSITION_QUANTUM

TIMING = ("samples/seconds",)
IGNORED_ATTRIBUTES = ("checksums", "provenance")
"""Root attributes that record the run, not the data: shard digests and where, when and how long it ran."""


def compare(a: Path, b: Path, skip=TIMING) -> dict:
    import zarr

    ra, rb = zarr.open_group(str(a), mode="r"), zarr.open_group(str(b), mode="r")
    rows = {}
    for name in ARRAYS:
        if name in skip:
            continue
        xa, xb = ra[name][...], rb[name][...]
        if xa.shape != xb.shape:
            rows[name] = {"equal": False, "shape": [list(xa.shape), list(xb.shape)]}
            continue
        equal = bool(np.array_equal(xa, xb, equal_nan=xa.dtype.kind == "f"))
        row = {"equal": equal, "shape": list(xa.shape)}
        if not equal and xa.dtype.kind in "fiu":
            d = np.abs(xa.astype(np.float64) - xb.astype(np.float64))
            d = d[np.isfinite(d)]
            row |= {"max_abs": float(d.max()) if d.size else 0.0, "differing": int((d > 0).sum())}
            if name.startswith("vertex_frames/"):
                row["max_mm"] = row["max_abs"] * POSITION_QUANTUM * 1e3
                row["mean_mm"] = float(d.mean()) * POSITION_QUANTUM * 1e3
        rows[name] = row
    attrs = {}
    for key in sorted(set(ra.attrs) | set(rb.attrs)):
        if key not in IGNORED_ATTRIBUTES:
            attrs[key] = ra.attrs.get(key) == rb.attrs.get(key)
    return {"arrays": rows, "attributes_equal": attrs,
            "all_equal": all(r["equal"] for r in rows.values()) and all(attrs.values())}


class CompareStores(Benchmark):
    description = __doc__

    def add_arguments(self, ap: argparse.ArgumentParser) -> None:
        ap.add_argument("a", type=Path)
        ap.add_argument("b", type=Path)
        ap.add_argument("--skip", nargs="*", default=list(TIMING))
        ap.add_argument("--json", type=Path, default=None)

    def run(self, args) -> tuple[argparse.Namespace, dict]:
        return args, compare(args.a, args.b, tuple(args.skip))

    def report(self, out) -> int:
        args, result = out
        for name, row in result["arrays"].items():
            if row["equal"]:
                continue
            extra = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()
                              if k not in ("equal",))
            print(f"  differs: {name}: {extra}")
        equal = [n for n, r in result["arrays"].items() if r["equal"]]
        print(f"{len(equal)} of {len(result['arrays'])} arrays bitwise equal (skipped: {', '.join(args.skip) or 'none'})")
        bad_attrs = [k for k, v in result["attributes_equal"].items() if not v]
        print("root attributes equal" if not bad_attrs else f"root attributes that differ: {', '.join(bad_attrs)}")
        if args.json:
            args.json.write_text(json.dumps(result, indent=1))
        return 0 if result["all_equal"] else 1


main = CompareStores().main
