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
import os
import shutil
import time
from pathlib import Path

from datagen.errors import InputError
from datagen.generate.config import DatasetConfig, parse_garment
from datagen.generate.devices import parse_devices, run_on_devices
from datagen.generate.plan import Plan, open_writer, static_groups
from datagen.generate.sewing import sew_devices, sew_patterns
from datagen.generate.samples import default_workers, simulate_samples

log = logging.getLogger(__name__)

__all__ = ["generate"]


def generate(config: DatasetConfig, out: str | Path, *, executor: str = "local", device: str | None = None,
             workers: int | None = None, progress=None, time_limit: float | None = None) -> dict:
    """Make (or finish) the store ``out`` for ``config``; returns a summary dict.

    Args:
        executor: ``local`` (this process simulates; ``workers`` processes build garments, compute
            targets and stage alongside; with several devices, ``cuda:0,cuda:1``, one simulating
            process per device, each with its share of the workers: :mod:`datagen.generate.devices`)
            or ``ray`` (one Ray task per GPU, or per CPU on the CPU, each
            simulating a share: :mod:`datagen.generate.ray_executor`).
        workers: local: processes beside the simulating one (default
            :func:`~datagen.generate.samples.default_workers`; 0: everything in this process); ray: the
            local Ray cluster's CPUs (default: every core).
        progress: called as ``progress(kind, done, total, scenes)``: kind 0, a batch's simulated
            frames (``scenes`` in the batch); 1, samples staged by the devices of a
            several-device run; 2, pattern garment instances sewn (:func:`~datagen.generate.sewing.sew_patterns`).
        time_limit: local executor: minutes after which no new batch is started when the last
            batch's time per scene says it would not end in time; what was simulated stays staged
            and the same call resumes it (``complete`` is then False). For time-limited jobs.

    Returns:
        ``samples``, ``simulated``, ``seconds`` (wall time), ``complete``, and for the local
        executor ``simulate_seconds`` (inside the simulator), ``garment_frames`` (recorded frames
        of the samples that did not fail) and the rates ``garment_frames_per_second`` (end to end)
        and ``simulator_garment_frames_per_second``; for the ray executor ``tasks`` (per task its
        GPU, samples, seconds and simulator seconds), ``gpus`` and ``cpus``.
    """
    if executor not in ("local", "ray"):
        raise InputError(f"unknown executor {executor!r}; use local or ray")
    if time_limit is not None and (executor != "local" or not time_limit > 0):
        raise InputError(f"a time limit must be a positive number of minutes and needs the local executor; got "
                         f"{time_limit} with the {executor} executor")
    deadline = None if time_limit is None else time.perf_counter() + 60.0 * time_limit
    plan = Plan(config)
    preflight(plan, out, executor=executor, device=device, workers=workers)
    cluster = None
    if executor == "ray":  # Ray installed and the cluster fit for the device, before anything is written
        from datagen.generate.ray_executor import RayCluster

        cluster = RayCluster(device, workers)
    try:
        return _generate(plan, out, executor, device, workers, progress, cluster, deadline)
    finally:
        if cluster is not None:
            cluster.close()


BODY_BYTES_PER_VERTEX_FRAME = 12
"""Host memory of one posed body vertex in one simulated frame, kept for a batch (float32 3-vectors):
a batch poses each distinct (body, motion) once and its scenes share the frames."""

POSING_BYTES_PER_VERTEX_FRAME = 96
"""Host memory one posing takes while it runs, per body vertex and frame: float64 vertices and the
skinning's temporaries (four [3] float64 arrays); up to 16 posings run at once on the host."""

DISK_BYTES_PER_VERTEX_FRAME = 36
"""Disk one recorded garment vertex-frame takes at the peak of a run: staged uncompressed (two int32
3-vectors: detail and coarse, 24 bytes) while pack writes the compressed store (about 11 bytes
measured, 43.4 KiB per 4k-vertex garment-frame), rounded up."""

NOMINAL_GARMENT_VERTICES = 4_000
"""Vertices of a garment at its type's default edge length, for the disk estimate (the
default-resolution garments have 2.5-4k)."""


def simulated_frames(plan) -> int:
    """Frames a scene of ``plan`` simulates: settling in the rest pose, the lead-in, holding the first
    pose, the ramp and the recorded frames."""
    return sum(plan.run_config.phases(plan.config.frames, plan.config.fps).values())


def preflight(plan, out: str | Path, *, executor: str, device: str | None, workers: int | None) -> None:
    """Everything that can be checked before the store directory is created: the output path, the
    worker count, the device (local executor), motion files, host memory for a batch and disk for
    the run.

    Raises:
        InputError: with what is wrong, the figures, and what to do.
    """
    out = Path(out)
    if workers is not None and workers < 0:
        raise InputError(f"--workers must be 0 or more, got {workers}")
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} is a file; give a directory for the store")
    if executor == "local":
        from datagen.sim.device import warp_device

        for d in parse_devices(device):
            warp_device(d)
    elif device is not None and "," in str(device):
        raise InputError(f"--device {device}: a list of devices is for the local executor; the ray executor gives "
                         "each task a GPU of its own: give --device cuda")
    for m, entry in enumerate(plan.motions):  # motion files: long enough at the config's frame rate
        if entry.startswith("file:"):
            plan.motion(m)
    c = plan.config
    procs = len(parse_devices(device)) if executor == "local" else 1  # simulating processes on this host
    batch = min(c.simulation.batch_size, -(-plan.sample_count // procs))
    frames = simulated_frames(plan)
    body_vertices = int(plan.body_model.v_template.shape[0])
    posings = min(batch, len({(sc.body, sc.motion) for sc in plan.scenes}))  # distinct bodies in motion
    need = procs * frames * body_vertices * (posings * BODY_BYTES_PER_VERTEX_FRAME
                                             + min(16, posings, os.cpu_count() or 1) * POSING_BYTES_PER_VERTEX_FRAME)
    from datagen.sim.device import available_ram

    free = available_ram()
    if executor == "local" and free is not None and need > free:
        each = f"{procs} simulating processes, each with a batch" if procs > 1 else "a batch"
        raise InputError(f"{each} of {batch} scenes of {frames} simulated frames needs about {need / 2**30:,.1f} GiB "
                         f"of memory for the posed bodies alone, and this machine has {free / 2**30:,.1f} GiB "
                         "available; lower frames or simulation.batch_size in the config"
                         + (", or name fewer devices" if procs > 1 else ""))
    edge_scale = 1.0
    if c.garment_edge_length is not None:
        from datagen.garment.types import GARMENT_TYPES
        from datagen.generate.garments import PATTERN_EDGE_LENGTH

        kinds = {parse_garment(g)[0] for s in c.splits.values() for g in s.garments}
        default = min(GARMENT_TYPES[k].edge_length if k in GARMENT_TYPES else PATTERN_EDGE_LENGTH for k in kinds)
        edge_scale = (default / c.garment_edge_length) ** 2
    disk = plan.sample_count * c.frames * NOMINAL_GARMENT_VERTICES * edge_scale * DISK_BYTES_PER_VERTEX_FRAME
    where = out if out.exists() else next((p for p in out.absolute().parents if p.exists()), Path("/"))
    disk_free = shutil.disk_usage(where).free
    if disk > disk_free:
        raise InputError(f"this dataset needs about {disk / 2**30:,.1f} GiB of disk while it is made (staged samples "
                         f"and the packed store; {plan.sample_count} scenes x {c.frames} frames), and {where} has "
                         f"{disk_free / 2**30:,.1f} GiB free; free some space or give --out on a larger disk")


def _generate(plan, out, executor, device, workers, progress, cluster, deadline=None) -> dict:
    config = plan.config
    writer = open_writer(plan, out)
    if writer.is_complete:
        writer.pack()  # nothing to pack; removes what an interrupted cleanup left in staging/
        return {"samples": plan.sample_count, "simulated": 0, "seconds": 0.0, "complete": True}
    t0 = time.perf_counter()
    devices = parse_devices(device)
    if any(plan.entry(g).is_pattern for g in range(len(plan.instances))):
        plan.sew_device = sew_devices(devices)[0][0]  # where a garment missing from the garment cache is sewn
    if writer.missing_static():
        sew_patterns(plan, default_workers() if workers is None else workers, devices,
                     progress=(lambda done, total: progress(2, done, total, 0)) if progress else None)
        for group, (arrays, names) in static_groups(plan, parse_devices(device)[0]).items():
            writer.stage_static(group, arrays, names=names,
                                **({"diagnostics": plan.fit_diagnostics} if group == "fit" else {}))
    todo = writer.missing(range(plan.sample_count))
    log.info("%d of %d samples to simulate", len(todo), plan.sample_count)
    stats = {}
    if executor == "local" and len(devices) > 1 and todo:
        stats = run_on_devices(config, out, todo, devices, workers=workers, progress=progress,
                               seconds_left=None if deadline is None else deadline - time.perf_counter())
    elif executor == "local":
        workers = default_workers() if workers is None else workers
        if workers > 0 and todo:
            stats = simulate_samples(plan, todo, device, progress=progress, out=out, workers=workers,
                                     deadline=deadline)
        else:
            stats = simulate_samples(plan, todo, device, lambda i, a, s: writer.stage_sample(i, a, s),
                                     progress=progress, deadline=deadline)
    elif todo:
        ray_summary = cluster.run(config, out, todo, progress=progress)
    missing = writer.missing(range(plan.sample_count))
    if missing and stats.get("stopped"):
        log.info("time limit: %d of %d samples staged", plan.sample_count - len(missing), plan.sample_count)
        return {"samples": plan.sample_count, "simulated": len(todo) - len(missing), "seconds": time.perf_counter() - t0,
                "complete": False, "left": len(missing)} | stats
    if missing:
        raise InputError(f"{len(missing)} samples were not staged (first {missing[:5]}); run the command again to "
                         "resume")
    from datagen.sim.device import warp_device
    from datagen.store.card import provenance

    writer.pack(provenance=provenance(device=device if device is not None else warp_device(None), executor=executor))
    seconds = time.perf_counter() - t0
    summary = {"samples": plan.sample_count, "simulated": len(todo), "seconds": seconds, "complete": True}
    if executor == "ray" and todo:
        summary |= ray_summary
    if stats.get("simulate_seconds"):
        summary |= stats
        summary["garment_frames_per_second"] = stats["garment_frames"] / seconds
        if "tasks" not in stats:  # (several devices give their rates added: run_on_devices)
            summary["simulator_garment_frames_per_second"] = stats["garment_frames"] / stats["simulate_seconds"]
    return summary
