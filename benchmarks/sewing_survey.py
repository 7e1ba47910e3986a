"""Random pattern designs sewn on the thin/regular/fat bodies at rest: how many sew, settle and pass.

For every (design, body): the program's pattern is meshed and placed around the body at rest
(:func:`datagen.garment.pattern.garment.pattern_garment`), then :func:`datagen.sim.sewing.sew`
leads the stitched vertices together without gravity (body and self contact on), welds the
seams once the largest gap is under 1 mm, relaxes and settles the welded garment under gravity
until static (99 % of its vertices under ``static_speed`` over a frame, 5 frames running). Prints one line per
garment (frames to sew, largest stretch next to the seams and crossings when sewn, frames to
static, failure) and the totals: sewn, settled, passed the gates, the causes of failures, seconds
per garment.

    python -m benchmarks sewing-survey [--designs 9] [--bodies regular] [--placement flat|wrap] [--edge-length 0.03]
        [--settle-frames 30] [--method stitch|weld] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import re
import time
from collections import Counter

import numpy as np

from benchmarks.common import PRESET_BODIES, preset_bodies


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--designs", type=int, default=9, help="random designs (programs in turn), each on every body")
    ap.add_argument("--bodies", default=",".join(PRESET_BODIES), help="comma-separated body presets")
    ap.add_argument("--seed", type=int, default=0, help="draws the designs")
    ap.add_argument("--placement", default="flat", choices=("flat", "wrap"), help="pattern_garment's placement mode")
    ap.add_argument("--edge-length", type=float, default=0.03, help="target edge length of the flat mesh [m]")
    ap.add_argument("--method", default="stitch", choices=("stitch", "weld"))
    ap.add_argument("--sew-frames", type=int, default=60)
    ap.add_argument("--settle-frames", type=int, default=30)
    ap.add_argument("--static-speed", type=float, default=0.02,
                    help="speed under which 99 %% of a static garment's vertices move over a frame [m/s]")
    ap.add_argument("--json", default="", help="write the rows here")
    args = ap.parse_args(argv)

    from datagen.body.cache import default_body
    from datagen.body.skeleton import face_parts
    from datagen.errors import DrapeError
    from datagen.garment.pattern.garment import pattern_garment
    from datagen.garment.pattern.programs import PROGRAMS, make_pattern
    from datagen.sim.sewing import SewConfig, sew

    model = default_body()
    bodies = preset_bodies(model)
    parts = face_parts(model.weights, model.faces)
    rng = np.random.default_rng(args.seed)
    names = list(PROGRAMS)
    draws = [(names[i % len(names)], int(rng.integers(0, 2**31 - 1))) for i in range(args.designs)]
    cfg = SewConfig(method=args.method, sew_frames=args.sew_frames, settle_frames=args.settle_frames,
                    static_speed=args.static_speed)
    rows, causes = [], Counter()
    print(f"sewing survey: {args.designs} designs x {args.bodies}, edge {args.edge_length * 100:g} cm, method "
          f"{args.method}, placement {args.placement}, at most {args.sew_frames} frames to sew and {args.settle_frames} "
          f"to settle (static: 99 % of vertices under {args.static_speed:g} m/s over a frame, 5 frames running); CPU")
    print(f"{'program':<15} {'seed':>10} {'body':<8} {'V':>5} {'gap0 mm':>8} {'sew fr':>6} {'seam str':>8} "
          f"{'xing':>5} {'settle fr':>9} {'p99 v m/s':>9} {'s':>6}  failure")
    for prog, seed in draws:
        for b in args.bodies.split(","):
            bv, bf, meas, betas = bodies[b]
            row = {"program": prog, "seed": seed, "body": b}
            t0 = time.perf_counter()
            try:
                g = pattern_garment(make_pattern(prog, seed, meas), bv, bf, edge_length=args.edge_length,
                                    mode=args.placement, seed=seed,
                                    betas=betas)
                r = sew(g, bv, bf, body_face_part=parts, config=cfg)
            except DrapeError as exc:
                row.update(failure=f"error: {exc}", seconds=time.perf_counter() - t0)
                causes[f"error: {re.sub(r'[0-9.]+', '#', str(exc))[:80]}"] += 1
                rows.append(row)
                print(f"{prog:<15} {seed:>10} {b:<8} error: {exc}")
                continue
            k = max(r.sew_frames, 0) + (cfg.relax_frames if args.method == "stitch" else 0)
            row.update(vertices=g.vertex_count, welded_vertices=r.garment.vertex_count, gap0_mm=1000 * float(r.gap[0]),
                       sew_frames=r.sew_frames, settle_frames=r.settle_frames,
                       seam_stretch_sewn=float(r.seam_stretch[min(k, len(r.seam_stretch)) - 1]) if len(r.seam_stretch) else 0.0,
                       crossings_sewn=int(r.self_intersections[min(k, len(r.self_intersections)) - 1]) if len(r.self_intersections) else 0,
                       stretch_end=float(r.stretch[-1]), crossings_end=int(r.self_intersections[-1]),
                       speed_end=float(r.speed[-1]), failure=None if r.failure is None else str(r.failure),
                       seconds=time.perf_counter() - t0)
            if r.failure is not None:
                causes[re.sub(r"[0-9.]+", "#", r.failure.message)] += 1
            elif r.settle_frames < 0:
                causes[f"not static after {args.settle_frames} frames"] += 1
            rows.append(row)
            print(f"{prog:<15} {seed:>10} {b:<8} {g.vertex_count:>5} {row['gap0_mm']:8.0f} {r.sew_frames:>6} "
                  f"{row['seam_stretch_sewn']:8.2f} {row['crossings_sewn']:>5} {r.settle_frames:>9} {row['speed_end']:9.3f} "
                  f"{row['seconds']:6.1f}  {row['failure'] or ''}", flush=True)
    ok = [r for r in rows if "sew_frames" in r]
    sewn = [r for r in ok if r["sew_frames"] >= 0]
    settled = [r for r in sewn if r["settle_frames"] >= 0]
    passed = [r for r in settled if r["failure"] is None]
    secs = np.array([r["seconds"] for r in rows])
    print(f"\n{len(rows)} garments: {len(sewn)} sewn (largest gap < 1 mm; frames to sew median "
          f"{np.median([r['sew_frames'] for r in sewn]) if sewn else float('nan'):.0f}, max "
          f"{max([r['sew_frames'] for r in sewn], default=-1)}), {len(settled)} static within {args.settle_frames} frames, "
          f"{len(passed)} sewn + static + through the gates; {np.median(secs):.1f} s a garment (median; max {secs.max():.1f})")
    for why, n in causes.most_common():
        print(f"  {n:4d}  {why}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
