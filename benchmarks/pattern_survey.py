"""Survey of the sewing-pattern garments: N random designs x the thin, regular and fat bodies.

For every (design, body): the program builds the pattern (outline and stitch lengths validated on
construction), the panels are meshed flat and placed around the body, and the pattern garment's
checks run (minimum angle, longest edge, every panel one disc, no vertex inside the body). Prints
how many build, mesh and pass, the time per garment, vertex counts, mesh quality, the mean distance
between sewn vertices for the wrapped and the flat placement, and every failure counted by its
message (numbers replaced by #).

    python -m benchmarks pattern-survey [--designs 300] [--edge-length 0.02] [--seed 0] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from benchmarks.common import PRESET_BODIES as BODIES
from benchmarks.common import preset_bodies



def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--designs", type=int, default=300, help="random designs, each on every body")
    ap.add_argument("--edge-length", type=float, default=0.02)
    ap.add_argument("--seed", type=int, default=0, help="draws the programs and their seeds")
    ap.add_argument("--json", help="also write every garment's figures here")
    args = ap.parse_args(argv)

    from datagen.body.cache import default_body
    from datagen.errors import DrapeError
    from datagen.garment.pattern.garment import check_pattern_garment, pattern_garment
    from datagen.garment.pattern.mesh import mesh_pattern
    from datagen.garment.pattern.placement import place, placement_report
    from datagen.garment.pattern.programs import PROGRAMS, make_pattern

    model = default_body()
    bodies = preset_bodies(model)
    rng = np.random.default_rng(args.seed)
    names = list(PROGRAMS)
    draws = [(names[i % len(names)], int(rng.integers(0, 2**31 - 1))) for i in range(args.designs)]
    rows, failures = [], Counter()
    t_all = time.perf_counter()
    for k, (prog, seed) in enumerate(draws):
        for b in BODIES:
            bv, bf, meas, betas = bodies[b]
            row = {"program": prog, "seed": seed, "body": b, "stage": "build"}
            t0 = time.perf_counter()
            try:
                pattern = make_pattern(prog, seed, meas)
                row["stage"] = "mesh"
                garment = pattern_garment(pattern, bv, bf, edge_length=args.edge_length, seed=seed, betas=betas)
                row["stage"] = "check"
                c = check_pattern_garment(garment, bv, bf)
                row.update({key: c[key] for key in ("min_angle_deg", "angle_p1_deg", "edge_spread", "edge_max_ratio",
                                                    "vertices_inside", "stitch_gap_mean", "panels", "openings")})
                row["vertices"] = garment.vertex_count
                row["seconds"] = time.perf_counter() - t0
                flat = mesh_pattern(pattern, args.edge_length)  # the flat placement, for comparison
                rep = placement_report(flat, place(flat, bv, bf, mode="flat"), bv, bf)
                row["flat_stitch_gap_mean"] = rep.stitch_gap_mean
                if c["ok"]:
                    row["stage"] = "ok"
                else:
                    for msg in c["failures"]:
                        failures[f"check: {re.sub(r'[0-9.]+', '#', msg)}"] += 1
            except DrapeError as exc:
                failures[f"{row['stage']}: {re.sub(r'[0-9]+([.][0-9]+)?', '#', str(exc))[:200]}"] += 1
                row["error"] = str(exc)
            rows.append(row)
        if (k + 1) % 25 == 0:
            print(f"  {k + 1}/{len(draws)} designs, {time.perf_counter() - t_all:.0f} s", flush=True)
    n = len(rows)
    stage = Counter(r["stage"] for r in rows)
    built = n - stage["build"]
    meshed = built - stage["mesh"]
    ok = [r for r in rows if r["stage"] == "ok"]
    print(f"\npattern survey: {args.designs} designs x {len(BODIES)} bodies = {n} garments, edge {args.edge_length * 1000:g} mm, "
          f"seed {args.seed}, {time.perf_counter() - t_all:.0f} s")
    print(f"built {built}/{n}, meshed and placed {meshed}/{n}, passed the checks {len(ok)}/{n}")
    done = [r for r in rows if "seconds" in r]
    if done:
        sec = np.array([r["seconds"] for r in done])
        vert = np.array([r["vertices"] for r in done])
        ang = np.array([r["min_angle_deg"] for r in done])
        p1 = np.array([r["angle_p1_deg"] for r in done])
        spread = np.array([r["edge_spread"] for r in done])
        emax = np.array([r["edge_max_ratio"] for r in done])
        gap_w = np.array([r["stitch_gap_mean"] for r in done])
        gap_f = np.array([r["flat_stitch_gap_mean"] for r in done])
        pct = lambda a: f"{np.percentile(a, 5):.3g} / {np.median(a):.3g} / {np.percentile(a, 95):.3g} (min {a.min():.3g}, max {a.max():.3g})"  # noqa: E731
        print("figures over the meshed garments: 5th percentile / median / 95th percentile")
        print(f"  seconds per garment (build + mesh + place + checks): {pct(sec)}")
        print(f"  vertices:                                            {pct(vert)}")
        print(f"  minimum angle [deg]:                                 {pct(ang)}")
        print(f"  1st-percentile angle [deg]:                          {pct(p1)}")
        print(f"  edge spread (p95 - p5) / median:                     {pct(spread)}")
        print(f"  longest edge / median:                               {pct(emax)}")
        print(f"  vertices inside the body:                            {sum(r['vertices_inside'] for r in done)} in all")
        print(f"  mean stitch gap, wrapped [m]:                        {pct(gap_w)}")
        print(f"  mean stitch gap, flat [m]:                           {pct(gap_f)}")
        print("per program: garments ok / total, median vertices, median seconds, worst minimum angle")
        for prog in names:
            rs = [r for r in rows if r["program"] == prog]
            ds = [r for r in rs if "seconds" in r]
            if ds:
                print(f"  {prog:15s} {sum(r['stage'] == 'ok' for r in rs):4d} / {len(rs):4d}  "
                      f"{np.median([r['vertices'] for r in ds]):7.0f}  {np.median([r['seconds'] for r in ds]):5.2f} s  "
                      f"{min(r['min_angle_deg'] for r in ds):5.1f} deg")
            else:
                print(f"  {prog:15s}    0 / {len(rs):4d}")
    print("failures by message:" if failures else "failures: none")
    for msg, count in failures.most_common():
        print(f"  {count:4d}  {msg}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
