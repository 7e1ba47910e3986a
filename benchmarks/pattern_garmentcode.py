"""GarmentCode specification files read, written back and read again (the largest difference), and
meshed flat at the given edge lengths (time, vertices, minimum and 1st-percentile angle, edge spread,
longest and shortest edge over the median).

    python -m benchmarks pattern-garmentcode FILE.json [...] [--edge-length 0.02 0.01]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np



def max_difference(p, q) -> float:
    """Largest coordinate difference [m] between two patterns of the same structure."""
    d = 0.0
    for a, b in zip(p.panels, q.panels):
        d = max(d, float(np.abs(np.subtract(a.vertices, b.vertices)).max()),
                float(np.abs(np.subtract(a.translation, b.translation)).max()))
        for e, g in zip(a.edges, b.edges):
            for attr in ("control", "control1", "control2", "radius"):
                if hasattr(e.curve, attr):
                    d = max(d, float(np.abs(np.subtract(getattr(e.curve, attr), getattr(g.curve, attr))).max()))
    return d


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--edge-length", type=float, nargs="+", default=[0.02, 0.01])
    args = ap.parse_args(argv)
    from datagen.garment.pattern.mesh import mesh_pattern, mesh_quality
    from datagen.garment.pattern.spec import read_spec, write_spec

    for f in args.files:
        p = read_spec(f)
        with tempfile.TemporaryDirectory() as tmp:
            q = read_spec(write_spec(p, Path(tmp) / "x_specification.json"))
        same = p.stitches == q.stitches and [x.name for x in p.panels] == [x.name for x in q.panels]
        print(f"{Path(f).name}: {len(p.panels)} panels, {len(p.stitches)} stitches; written and read again: "
              f"structure {'equal' if same else 'DIFFERENT'}, largest difference {max_difference(p, q):.1e} m")
        for h in args.edge_length:
            t = time.perf_counter()
            m = mesh_pattern(p, h)
            dt = time.perf_counter() - t
            qu = mesh_quality(m.rest_uv, m.faces)
            print(f"  {h * 1000:4.0f} mm: {dt:5.2f} s, {m.vertex_count:6d} vertices, {len(m.stitch_pairs):5d} sewn pairs, "
                  f"min angle {qu.min_angle:4.1f} deg (1st percentile {qu.angle_p1:4.1f}), edge spread "
                  f"{qu.edge_spread:.2f}, edges {qu.edge_min_ratio:.2f}-{qu.edge_max_ratio:.2f} x median")
    return 0


if __name__ == "__main__":
    sys.exit(main())
