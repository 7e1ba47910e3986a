"""Random pattern designs sewn on the thin/regular/fat bodies at rest: how many sew, settle and pass.

For every (design, body): the program's pattern is meshed and placed around the body at rest
(:func:`datagen.garment.pattern.garment.pattern_garment`, the sewing placement
:data:`datagen.sim.sewing.PLACEMENT`), then :func:`datagen.sim.sewing.sew` leads the stitched vertices
together without gravity (body and self contact on), welds the seams once the largest gap is under
1 mm, relaxes and settles the welded garment under gravity until static (99 % of its vertices under
``static_speed`` over a frame, 5 frames running). One line per garment: sewn?, frames to close, the
largest principal strain (all faces, faces at a seam, faces at a seam corner: a vertex where three or
more panel vertices are welded) and crossings once sewn, folded triangles (normal against its
neighbours') sewn and at the end, crossings at the end, frames to static, failure, seconds; then
the totals: sewn, static, passed the gates, the causes of failures counted, seconds per garment,
and the strain/fold figures over the sewn garments.

    python -m benchmarks sewing-survey [--designs 9] [--programs trousers,dress] [--bodies thin,regular,fat]
        [--device cpu|cuda] [--workers 2] [--settle-frames 30] [--edge-length 0.03] [--json out.json]

``--workers N`` sews N garments at once in separate processes (CPU; each process runs one
garment at a time; with ``--device cuda`` they share the GPU). ``--designs`` draws designs from the
programs in turn (``--programs``: all nine by default), each with a random seed from ``--seed``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import time
from collections import Counter

import numpy as np

from benchmarks.common import PRESET_BODIES

_STATE: dict = {}


def _init(device: str) -> None:
    """A worker's bodies, built once (and warp on the run's device)."""
    from benchmarks.common import preset_bodies
    from datagen.body.cache import default_body
    from datagen.body.skeleton import face_parts

    model = default_body()
    _STATE.update(bodies=preset_bodies(model), parts=face_parts(model.weights, model.faces), device=device)


def _one(job: tuple) -> dict:
    """Sew one (program, seed, body): the survey's row."""
    prog, seed, body, opts = job
    if not _STATE:
        _init(opts["device"])
    from datagen.errors import DrapeError
    from datagen.garment.pattern.garment import pattern_garment
    from datagen.garment.pattern.programs import make_pattern
    from datagen.sim.sewing import PLACEMENT, SewConfig, sew

    bv, bf, meas, betas = _STATE["bodies"][body]
    cfg = SewConfig(method=opts["method"], sew_frames=opts["sew_frames"], settle_frames=opts["settle_frames"],
                    static_speed=opts["static_speed"])
    row = {"program": prog, "seed": seed, "body": body}
    t0 = time.perf_counter()
    try:
        g = pattern_garment(make_pattern(prog, seed, meas), bv, bf, edge_length=opts["edge_length"],
                            mode=opts["placement"] or PLACEMENT, seed=seed, betas=betas)
        r = sew(g, bv, bf, body_face_part=_STATE["parts"], config=cfg, device=_STATE["device"])
    except DrapeError as exc:
        row.update(failure=f"error: {exc}", seconds=time.perf_counter() - t0)
        return row
    # the frame the garment is sewn and relaxed (before gravity), or the last one sewing got to
    k = min(max(r.sew_frames, 0) + (cfg.relax_frames if opts["method"] == "stitch" else 0), len(r.stretch)) - 1
    row.update(vertices=g.vertex_count, welded_vertices=r.garment.vertex_count, gap0_mm=1000 * float(r.gap[0]),
               sew_frames=r.sew_frames, settle_frames=r.settle_frames,
               stretch_sewing_max=float(r.stretch[: max(r.sew_frames, 0)].max(initial=0.0)),
               stretch_sewn=float(r.stretch[k]), seam_stretch_sewn=float(r.seam_stretch[k]),
               corner_stretch_sewn=float(r.corner_stretch[k]), crossings_sewn=int(r.self_intersections[k]),
               folded_sewn=int(r.folded[k]), stretch_end=float(r.stretch[-1]),
               seam_stretch_end=float(r.seam_stretch[-1]), corner_stretch_end=float(r.corner_stretch[-1]),
               crossings_end=int(r.self_intersections[-1]), folded_end=int(r.folded[-1]),
               speed_end=float(r.speed[-1]), failure=None if r.failure is None else str(r.failure),
               seconds=time.perf_counter() - t0)
    return row


def _line(row: dict) -> str:
    head = f"{row['program']:<15} {row['seed']:>10} {row['body']:<8}"
    if "sew_frames" not in row:
        return f"{head} {row['failure']}"
    return (f"{head} {row['vertices']:>5} {row['gap0_mm']:7.0f} {'yes' if row['sew_frames'] >= 0 else 'no':>4} "
            f"{row['sew_frames']:>4} {row['stretch_sewn']:6.2f} {row['seam_stretch_sewn']:6.2f} "
            f"{row['corner_stretch_sewn']:6.2f} {row['crossings_sewn']:>5} {row['folded_sewn']:>4} "
            f"{row['stretch_end']:6.2f} {row['corner_stretch_end']:6.2f} {row['crossings_end']:>5} {row['folded_end']:>4} "
            f"{'yes' if row['settle_frames'] >= 0 else 'no':>6} {row['settle_frames']:>4} {row['seconds']:6.1f}  "
            f"{row['failure'] or ''}")


def _cause(row: dict, settle_frames: int) -> str | None:
    if "sew_frames" not in row:
        return f"error: {re.sub(r'[0-9.]+', '#', row['failure'])[:80]}"
    if row["failure"] is not None:
        return re.sub(r"[0-9.]+", "#", row["failure"])
    if row["settle_frames"] < 0:
        return f"not static after {settle_frames} frames (passed the gates)"
    return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--designs", type=int, default=9, help="random designs (programs in turn), each on every body")
    ap.add_argument("--programs", default="", help="comma-separated pattern programs (default: all)")
    ap.add_argument("--bodies", default=",".join(PRESET_BODIES), help="comma-separated body presets")
    ap.add_argument("--seed", type=int, default=0, help="draws the designs")
    ap.add_argument("--device", default="cpu", help="warp device of the simulation (cpu, cuda, cuda:1)")
    ap.add_argument("--workers", type=int, default=1, help="garments sewn at once, in separate processes")
    ap.add_argument("--placement", default="", choices=("", "flat", "wrap"),
                    help="pattern_garment's placement mode (default: sewing's, datagen.sim.sewing.PLACEMENT)")
    ap.add_argument("--edge-length", type=float, default=0.03, help="target edge length of the flat mesh [m]")
    ap.add_argument("--method", default="stitch", choices=("stitch", "weld"))
    ap.add_argument("--sew-frames", type=int, default=60)
    ap.add_argument("--settle-frames", type=int, default=30)
    ap.add_argument("--static-speed", type=float, default=0.02,
                    help="speed under which 99 %% of a static garment's vertices move over a frame [m/s]")
    ap.add_argument("--json", default="", help="write the rows here")
    args = ap.parse_args(argv)

    from datagen.garment.pattern.programs import PROGRAMS

    names = [p for p in args.programs.split(",") if p] or list(PROGRAMS)
    unknown = sorted(set(names) - set(PROGRAMS))
    if unknown:
        ap.error(f"unknown programs {unknown}; known: {', '.join(PROGRAMS)}")
    bodies = [b for b in args.bodies.split(",") if b]
    rng = np.random.default_rng(args.seed)
    draws = [(names[i % len(names)], int(rng.integers(0, 2**31 - 1))) for i in range(args.designs)]
    opts = {"device": args.device, "method": args.method, "sew_frames": args.sew_frames,
            "settle_frames": args.settle_frames, "static_speed": args.static_speed, "edge_length": args.edge_length,
            "placement": args.placement}
    jobs = [(p, s, b, opts) for p, s in draws for b in bodies]
    print(f"sewing survey: {args.designs} designs x {','.join(bodies)} ({len(jobs)} garments), edge "
          f"{args.edge_length * 100:g} cm, method {args.method}, placement {args.placement or 'sewing default'}, at most "
          f"{args.sew_frames} frames to sew and {args.settle_frames} to settle (static: 99 % of vertices under "
          f"{args.static_speed:g} m/s over a frame, 5 frames running); device {args.device}, {args.workers} worker(s)")
    print("strain = largest principal strain (all faces / at a seam / at a seam corner); sewn = after the weld and "
          "relaxing, before gravity; end = after settling")
    print(f"{'program':<15} {'seed':>10} {'body':<8} {'V':>5} {'gap0mm':>7} {'sewn':>4} {'fr':>4} {'strain':>6} "
          f"{'seam':>6} {'corner':>6} {'xing':>5} {'fold':>4} {'endstr':>6} {'endcor':>6} {'xing':>5} {'fold':>4} "
          f"{'static':>6} {'fr':>4} {'s':>6}  failure")
    t0 = time.perf_counter()
    rows = []
    if args.workers > 1:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        os.environ.setdefault("OMP_NUM_THREADS", "1")
        with ProcessPoolExecutor(args.workers, mp_context=mp.get_context("spawn"), initializer=_init,
                                 initargs=(args.device,)) as pool:
            for row in pool.map(_one, jobs):
                rows.append(row)
                print(_line(row), flush=True)
    else:
        _init(args.device)
        for job in jobs:
            rows.append(_one(job))
            print(_line(rows[-1]), flush=True)
    wall = time.perf_counter() - t0
    causes = Counter(c for c in (_cause(r, args.settle_frames) for r in rows) if c)
    ok = [r for r in rows if "sew_frames" in r]
    sewn = [r for r in ok if r["sew_frames"] >= 0]
    passed = [r for r in sewn if r["failure"] is None]
    static = [r for r in passed if r["settle_frames"] >= 0]
    secs = np.array([r["seconds"] for r in rows])
    fr = [r["sew_frames"] for r in sewn]
    print(f"\n{len(rows)} garments: {len(sewn)} sewn (largest gap < 1 mm; frames to sew median "
          f"{np.median(fr) if fr else float('nan'):.0f}, max {max(fr, default=-1)}), {len(passed)} sewn and through the "
          f"gates, {len(static)} of them static within {args.settle_frames} frames; {np.median(secs):.1f} s a garment "
          f"(median; max {secs.max():.1f}), {wall:.0f} s wall with {args.workers} worker(s)")
    if sewn:
        def q(key):
            v = np.array([r[key] for r in sewn], dtype=float)
            return f"median {np.median(v):.2f}, max {v.max():.2f}"

        print(f"  sewn garments: strain sewn {q('stretch_sewn')}; at seam corners sewn {q('corner_stretch_sewn')}, "
              f"end {q('corner_stretch_end')}; crossings sewn {q('crossings_sewn')}, end {q('crossings_end')}; folded "
              f"triangles sewn {q('folded_sewn')}, end {q('folded_end')}; strain while leading {q('stretch_sewing_max')}")
    for why, n in causes.most_common():
        print(f"  {n:4d}  {why}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
