"""``drape generate``: from a :class:`~datagen.generate.config.DatasetConfig` to a packed store.

1. Plan: the scenes of every split (garment x body x motion), numbered in a fixed order; sample i
   is scene i. Bodies, motions and garment instances (a garment type and seed made for one body)
   are numbered in order of first use.
2. Static groups: the body model, the bodies' β, the motions, the garment instances (rest
   meshes, labels, the indicator into the subdivided body, skinning weights) and the
   fit-attribute model, a factor analysis fitted on the training split's garment-body pairs only
   and applied to every instance (α).
3. Samples: scenes are simulated in batches (same frame count); each result becomes the targets
   of :mod:`datagen.targets` and is staged atomically. Failed scenes are staged with their reason
   and metrics and no frames.
4. Pack (one process).

Everything is a pure function of the config: the staged samples of a killed run are kept and
the run resumes with the missing ones; a store made from another config is refused.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

from datagen.errors import InputError
from datagen.generate.config import DatasetConfig
from datagen.generate.plan import Plan, open_writer, static_groups
from datagen.generate.samples import simulate_samples

log = logging.getLogger(__name__)

__all__ = ["generate"]


def generate(config: DatasetConfig, out: str | Path, *, executor: str = "local", device: str | None = None,
             workers: int = 2, progress=None) -> dict:
    """Make (or finish) the store ``out`` for ``config``; returns a summary dict."""
    plan = Plan(config)
    writer = open_writer(plan, out)
    if writer.is_complete:
        return {"samples": plan.sample_count, "simulated": 0, "seconds": 0.0, "complete": True}
    t0 = time.perf_counter()
    if writer.missing_static():
        for group, (arrays, names) in static_groups(plan).items():
            writer.stage_static(group, arrays, names=names)
    todo = writer.missing(range(plan.sample_count))
    log.info("%d of %d samples to simulate", len(todo), plan.sample_count)
    if executor == "local":
        simulate_samples(plan, todo, device, lambda i, a, s: writer.stage_sample(i, a, s), progress=progress)
    elif executor == "ray":
        from datagen.generate.ray_executor import run_ray

        run_ray(config, out, todo, device=device, workers=workers, progress=progress)
    else:
        raise InputError(f"unknown executor {executor!r}; use local or ray")
    missing = writer.missing(range(plan.sample_count))
    if missing:
        raise InputError(f"{len(missing)} samples were not staged (first {missing[:5]}); run the command again to "
                         "resume")
    writer.pack()
    return {"samples": plan.sample_count, "simulated": len(todo), "seconds": time.perf_counter() - t0,
            "complete": True}
