"""``drape generate``: from a :class:`~datagen.generate.config.DatasetConfig` to a packed store.

1. Plan: the scenes of every split (garment x body x motion), numbered in a fixed order; sample i
   is scene i. Bodies, motions and garment instances (a garment type and seed made for one body)
   are numbered in order of first use.
2. Static groups: the body model, the bodies' β, the motions, the garment instances (rest
   meshes, labels, the indicator into the subdivided body, skinning weights) and the
   fit-attribute model, a factor analysis fitted on the training split's garment-body pairs only
   and applied to every instance (α).
3. Samples: scenes are simulated in batches (same frame count); each result becomes what the
   store keeps (:func:`~datagen.generate.samples.sample_arrays`) and is staged atomically, by
   worker processes while the next batch simulates (:mod:`datagen.generate.samples`). Failed
   scenes are staged with their reason and metrics and no frames.
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
from datagen.generate.samples import default_workers, simulate_samples

log = logging.getLogger(__name__)

__all__ = ["generate"]


def generate(config: DatasetConfig, out: str | Path, *, executor: str = "local", device: str | None = None,
             workers: int | None = None, progress=None) -> dict:
    """Make (or finish) the store ``out`` for ``config``; returns a summary dict.

    Args:
        executor: ``local`` (this process simulates; ``workers`` processes build garments, compute
            targets and stage alongside) or ``ray`` (one Ray task per GPU, or per CPU on the CPU, each
            simulating a share: :mod:`datagen.generate.ray_executor`).
        workers: local: processes beside the simulating one (default
            :func:`~datagen.generate.samples.default_workers`; 0: everything in this process); ray: the
            local Ray cluster's CPUs (default: every core).

    Returns:
        ``samples``, ``simulated``, ``seconds`` (wall time), ``complete``, and for the local
        executor ``simulate_seconds`` (inside the simulator), ``garment_frames`` (recorded frames
        of the samples that did not fail) and the rates ``garment_frames_per_second`` (end to end)
        and ``simulator_garment_frames_per_second``; for the ray executor ``tasks`` (per task its
        GPU, samples, seconds and simulator seconds), ``gpus`` and ``cpus``.
    """
    if executor not in ("local", "ray"):
        raise InputError(f"unknown executor {executor!r}; use local or ray")
    cluster = None
    if executor == "ray":  # Ray installed and the cluster fit for the device, before anything is written
        from datagen.generate.ray_executor import RayCluster

        cluster = RayCluster(device, workers)
    try:
        return _generate(config, out, executor, device, workers, progress, cluster)
    finally:
        if cluster is not None:
            cluster.close()


def _generate(config, out, executor, device, workers, progress, cluster) -> dict:
    plan = Plan(config)
    writer = open_writer(plan, out)
    if writer.is_complete:
        return {"samples": plan.sample_count, "simulated": 0, "seconds": 0.0, "complete": True}
    t0 = time.perf_counter()
    if writer.missing_static():
        for group, (arrays, names) in static_groups(plan).items():
            writer.stage_static(group, arrays, names=names,
                                **({"diagnostics": plan.fit_diagnostics} if group == "fit" else {}))
    todo = writer.missing(range(plan.sample_count))
    log.info("%d of %d samples to simulate", len(todo), plan.sample_count)
    stats = {}
    if executor == "local":
        workers = default_workers() if workers is None else workers
        if workers > 0 and todo:
            stats = simulate_samples(plan, todo, device, progress=progress, out=out, workers=workers)
        else:
            stats = simulate_samples(plan, todo, device, lambda i, a, s: writer.stage_sample(i, a, s),
                                     progress=progress)
    elif todo:
        ray_summary = cluster.run(config, out, todo, progress=progress)
    missing = writer.missing(range(plan.sample_count))
    if missing:
        raise InputError(f"{len(missing)} samples were not staged (first {missing[:5]}); run the command again to "
                         "resume")
    writer.pack()
    seconds = time.perf_counter() - t0
    summary = {"samples": plan.sample_count, "simulated": len(todo), "seconds": seconds, "complete": True}
    if executor == "ray" and todo:
        summary |= ray_summary
    if stats.get("simulate_seconds"):
        summary |= stats
        summary["garment_frames_per_second"] = stats["garment_frames"] / seconds
        summary["simulator_garment_frames_per_second"] = stats["garment_frames"] / stats["simulate_seconds"]
    return summary
