"""Garments over many seeds and bodies: vertex counts, build time, mesh quality, check failures.

    python -m benchmarks garments --seeds 10 --bodies thin,regular,fat [--types all] [--jobs 2]

Per type: vertex count range, mean build time per garment (construction only; checks excluded),
the worst minimum angle and its 1st percentile, edge-length spread, minimum clearance, the
smallest share of outward-facing area, and how many garments failed which check (topology,
boundary loops, self-intersection, penetration, orientation). ``--jobs N`` builds in N processes
(each loads the body once); a progress bar goes to stderr.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import sys
import time
from collections import Counter, defaultdict

import numpy as np

from datagen.garment.types import GARMENT_TYPES

_STATE: dict = {}


def _init(body_names: list[str]) -> None:
    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas

    model = default_body()
    _STATE["model"] = model
    _STATE["betas"] = {b: resolve_betas(model, body=b)[0] for b in body_names}
    _STATE["shaped"] = {b: np.asarray(model.shaped(beta))[0] for b, beta in _STATE["betas"].items()}


def _one(task: tuple[str, str, int, float | None]) -> dict:
    from datagen.garment.checks import check_garment
    from datagen.garment.types import make_garment

    kind, body, seed, edge = task
    model = _STATE["model"]
    t0 = time.perf_counter()
    try:
        g = make_garment(kind, model, _STATE["betas"][body], seed=seed, target_edge_length=edge)
    except Exception as exc:  # noqa: BLE001 - a build that raises is a failure to report, not to hide
        return {"kind": kind, "body": body, "seed": seed, "error": f"build error {type(exc).__name__}: {exc}"}
    seconds = time.perf_counter() - t0
    c = check_garment(g, _STATE["shaped"][body], model.faces)
    return {"kind": kind, "body": body, "seed": seed, "seconds": seconds, "vertices": g.vertex_count, **c}


def _short(failure: str) -> str:
    if "penetrates" in failure or "normals face" in failure:
        return failure.split(" (")[0]
    if "loops" in failure:
        return failure.split(",")[0]
    if "self-intersecting" in failure:
        return "self-intersecting faces"
    return failure


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--bodies", default="thin,regular,fat")
    ap.add_argument("--types", default="all", help="comma-separated types, or 'all'")
    ap.add_argument("--edge-length", type=float, default=None, help="default: each type's own")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes")
    args = ap.parse_args(argv)
    from tqdm import tqdm

    kinds = list(GARMENT_TYPES) if args.types == "all" else args.types.split(",")
    unknown = [k for k in kinds if k not in GARMENT_TYPES]
    if unknown:
        ap.error(f"unknown type(s) {', '.join(unknown)}; types: {', '.join(GARMENT_TYPES)}")
    bodies = args.bodies.split(",")
    tasks = [(k, b, s, args.edge_length) for k in kinds for b in bodies for s in range(args.seeds)]
    results: dict[str, list[dict]] = defaultdict(list)
    t0 = time.perf_counter()
    if args.jobs > 1:
        with mp.get_context("spawn").Pool(args.jobs, initializer=_init, initargs=(bodies,)) as pool:
            for r in tqdm(pool.imap_unordered(_one, tasks), total=len(tasks), desc="garments", file=sys.stderr):
                results[r["kind"]].append(r)
    else:
        _init(bodies)
        for task in tqdm(tasks, desc="garments", file=sys.stderr):
            r = _one(task)
            results[r["kind"]].append(r)
    wall = time.perf_counter() - t0
    print(f"{args.seeds} seeds x {len(bodies)} bodies ({args.bodies}) per type, edge length "
          f"{args.edge_length or 'each type default'}, {args.jobs} job(s), {wall:.0f} s wall")
    head = (f"{'type':18s} {'n':>4s} {'vertices':>11s} {'build s':>7s} {'min angle':>9s} {'p1 angle':>8s} "
            f"{'spread':>6s} {'clear mm':>8s} {'outward':>7s} {'failed':>6s}  failures")
    print(head)
    print("-" * len(head))
    total_fail = 0
    for kind in kinds:
        rs = results[kind]
        ok = [r for r in rs if "error" not in r]
        fails = Counter(r["error"].split(":")[0] for r in rs if "error" in r)
        failed = len(rs) - len(ok)
        for r in ok:
            if not r["ok"]:
                failed += 1
                fails.update(_short(f) for f in r["failures"])
        total_fail += failed
        if ok:
            v = [r["vertices"] for r in ok]
            print(f"{kind:18s} {len(rs):4d} {min(v):5d}-{max(v):<5d} {np.mean([r['seconds'] for r in ok]):7.2f} "
                  f"{min(r['min_angle_deg'] for r in ok):9.1f} {np.mean([r['angle_p1_deg'] for r in ok]):8.1f} "
                  f"{np.mean([r['edge_spread'] for r in ok]):6.2f} {1000 * min(r['min_clearance'] for r in ok):8.1f} "
                  f"{min(r['outward_area_fraction'] for r in ok):7.3f} {failed:6d}  "
                  f"{'; '.join(f'{k} x{n}' for k, n in fails.items())}", flush=True)
        else:
            print(f"{kind:18s} {len(rs):4d} all failed: {'; '.join(f'{k} x{n}' for k, n in fails.items())}")
    print(f"failed garments in all: {total_fail}")
    for kind in kinds:
        for r in sorted(results[kind], key=lambda r: (r.get("body", ""), r.get("seed", -1))):
            if "error" in r or not r["ok"]:
                what = r["error"] if "error" in r else "; ".join(r["failures"])
                print(f"  failed: {kind} body={r.get('body')} seed={r.get('seed')}: {what}")
