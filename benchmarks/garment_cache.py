"""Build every body and garment instance of a dataset preset (or config) into drape's cache, and
nothing else: for a GPU host without pymeshlab or anny, which then finds them there
(``DRAPE_CACHE_DIR``; carry the directory) and only simulates.

    DRAPE_CACHE_DIR=.gpucache_gnn python -m benchmarks garment-cache --preset paper-gnn [--workers 2]

Each instance is built by the same call ``drape generate`` makes (``Plan.garment``), so the cache
keys are the ones it looks up. Prints each instance as it is done and the cache's size."""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

_PLAN = {}


def _plan(preset: str | None, config: str | None):
    from datagen.generate.config import resolve_config
    from datagen.generate.plan import Plan

    return Plan(resolve_config(config, None if config else preset))


def _init(preset, config) -> None:
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    _PLAN["plan"] = _plan(preset, config)


def _build(g: int) -> tuple[int, float]:
    t = time.perf_counter()
    _PLAN["plan"].garment(g)
    return g, time.perf_counter() - t


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="paper-gnn")
    ap.add_argument("--config", default=None, help="a dataset config file instead of a preset")
    ap.add_argument("--workers", type=int, default=max(1, (os.cpu_count() or 2)))
    args = ap.parse_args(argv)
    plan = _plan(args.preset, args.config)
    n = len(plan.instances)
    print(f"{n} garment instances on {len(plan.bodies)} bodies; cache {os.environ.get('DRAPE_CACHE_DIR', '(default)')}",
          flush=True)
    t0 = time.perf_counter()
    plan.betas  # the body built (or loaded) here first: the workers then load it instead of each building it
    with ProcessPoolExecutor(args.workers, initializer=_init, initargs=(args.preset, args.config)) as pool:
        futures = [pool.submit(_build, g) for g in range(n)]
        for k, f in enumerate(as_completed(futures), 1):
            g, dt = f.result()
            print(f"[{k}/{n}] {plan.instances[g][0]} on {plan.instances[g][1]}: {dt:.1f} s", flush=True)
    root = Path(os.environ.get("DRAPE_CACHE_DIR", Path.home() / ".cache" / "drape"))
    size = sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) if root.exists() else 0
    print(f"done in {time.perf_counter() - t0:.0f} s; {root}: {size / 2**20:.1f} MB")
