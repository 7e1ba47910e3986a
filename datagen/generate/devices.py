"""Several devices on one host with the local executor: ``--device cuda:0,cuda:1,cuda:2,cuda:3``.

One simulating process per device, each given a contiguous share of the scenes
(:func:`shares`) and running the same overlapped pipeline as a single device
(:func:`~datagen.generate.samples.simulate_samples`, with its share of the worker processes).
Each stages its own samples (process-unique temporary names, renamed into place with the
completion marker last: :mod:`datagen.store.layout`), and the driver packs once every process
is done. A scene's result does not depend on its batch, so the store equals the one-device
store. No Ray needed: this is for a single host with several GPUs (a cluster takes ``--executor
ray``). ``cpu`` may be named more than once (several simulating processes on the CPU, as the
tests do); a CUDA device only once.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import queue as queue_module
import time
from pathlib import Path

from datagen.errors import InputError


def parse_devices(device: str | None) -> list[str | None]:
    """The devices of a ``--device`` value: one, or several as a comma list.

    Raises:
        InputError: an empty name in the list, or a CUDA device named twice.
    """
    if device is None or "," not in str(device):
        return [device]
    names = [d.strip() for d in str(device).split(",")]
    if any(not d for d in names):
        raise InputError(f"--device {device!r}: an empty name in the list; give devices as cuda:0,cuda:1")
    cuda = [d for d in names if d.startswith("cuda")]
    if len(set(cuda)) < len(cuda):
        twice = sorted({d for d in cuda if cuda.count(d) > 1})
        raise InputError(f"--device {device!r} names {', '.join(twice)} more than once: one simulating process per "
                         "GPU; give each GPU once (cuda:0,cuda:1,...)")
    if "cuda" in names and len(cuda) > 1:
        raise InputError(f"--device {device!r}: 'cuda' is warp's default GPU, which may be one of the others; name "
                         "every GPU by number (cuda:0,cuda:1,...)")
    return names


def shares(indices: list[int], batch_size: int, slots: int) -> list[list[int]]:
    """Cut ``indices`` into contiguous shares, as even as possible: at least ``slots`` of them (one
    per GPU or CPU, when there are that many scenes) and none longer than ``batch_size``."""
    if not indices:
        return []
    n = max(min(slots, len(indices)), math.ceil(len(indices) / batch_size))
    base, extra = divmod(len(indices), n)
    out, start = [], 0
    for k in range(n):
        size = base + (1 if k < extra else 0)
        out.append(list(indices[start:start + size]))
        start += size
    return out


def stage_share(config_dict: dict, out: str, indices: list[int], device: str | None, workers: int, *,
                progress=None, seconds_left: float | None = None) -> dict:
    """Simulate and stage the scenes ``indices`` not yet staged, in this process: what a device's
    process (or a Ray task) runs. Returns ``samples`` (simulated here) and the pipeline's timings
    (:func:`~datagen.generate.samples.simulate_samples`)."""
    from datagen.config import load_config
    from datagen.generate.config import DatasetConfig
    from datagen.generate.plan import Plan, open_writer
    from datagen.generate.samples import simulate_samples

    plan = Plan(load_config(DatasetConfig, config_dict))
    writer = open_writer(plan, out)
    todo = writer.missing(indices)
    deadline = None if seconds_left is None else time.perf_counter() + seconds_left
    stats: dict = {}
    if todo:
        if workers > 0:
            stats = simulate_samples(plan, todo, device, progress=progress, out=out, workers=workers,
                                     deadline=deadline)
        else:
            stats = simulate_samples(plan, todo, device, lambda i, a, s: writer.stage_sample(i, a, s),
                                     progress=progress, deadline=deadline)
    return {"samples": len(todo) - len(writer.missing(todo)), "stats": stats}


def task_record(task: int, started: float, result: dict, **where) -> dict:
    """What one share's process (a device's, or a Ray task) reports: ``where`` it ran (``gpus``,
    ``cuda_visible_devices``, ...), its pid and host, and from :func:`stage_share`'s ``result`` the
    samples it simulated and the pipeline's timings; ``started``: its ``time.perf_counter()`` at the start."""
    stats = result["stats"]
    return {"task": task, **where, "pid": os.getpid(), "host": os.uname().nodename, "samples": result["samples"],
            "seconds": time.perf_counter() - started,
            "simulate_seconds": stats.get("simulate_seconds", 0.0), "garment_frames": stats.get("garment_frames", 0),
            "wait_seconds": stats.get("wait_seconds", 0.0), "batches": stats.get("batches", 0),
            "stopped": stats.get("stopped", 0)}


def pin_gpu(device: str | None) -> str | None:
    """In a device's own process, before CUDA starts: make ``cuda:N`` the only visible GPU (as Ray
    does for its tasks) and return ``cuda:0``, so that nothing in the process (warp's default
    device included) can touch another process's card. A ``CUDA_VISIBLE_DEVICES`` already set is
    respected: N counts among the GPUs it lists."""
    if not device or not str(device).startswith("cuda:"):
        return device
    n = int(str(device).split(":", 1)[1])
    visible = os.environ.get("CUDA_VISIBLE_DEVICES")
    ids = [v.strip() for v in visible.split(",") if v.strip()] if visible else []
    os.environ["CUDA_VISIBLE_DEVICES"] = ids[n] if n < len(ids) else str(n)
    return "cuda:0"


def _device_process(config_dict, out, indices, device, workers, task, seconds_left, messages) -> None:
    """A device's process: its share, progress and its result (or its error) as messages."""
    from datagen.lifetime import die_with_parent

    die_with_parent()  # a kill -9 of drape generate ends this process (and so its own workers) too
    t0 = time.perf_counter()
    name, device = device, pin_gpu(device)

    def progress(kind, done, total, scenes):
        if kind == 0 and (done % 20 == 0 or done == total):
            messages.put(("progress", task, done, total, scenes))

    try:
        result = stage_share(config_dict, out, indices, device, workers, progress=progress, seconds_left=seconds_left)
        messages.put(("done", task, task_record(task, t0, result, device=name, gpus=[],
                                                cuda_visible_devices=os.environ.get("CUDA_VISIBLE_DEVICES"))))
    except BaseException as exc:  # noqa: BLE001 (reported to the driver, which raises it)
        messages.put(("error", task, f"{type(exc).__name__}: {exc}", isinstance(exc, InputError)))


def workers_per_device(workers: int | None, devices: int) -> int:
    """Pipeline workers beside each device's simulating process: ``workers`` shared out, or by
    default the host's cores beside the simulating processes, at most 8 a device (0: in process)."""
    if workers is not None:
        return workers // devices
    return max(0, min(8, ((os.cpu_count() or 2) - devices) // devices))


def run_on_devices(config, out: str | Path, indices: list[int], devices: list[str], *, workers: int | None = None,
                   progress=None, seconds_left: float | None = None) -> dict:
    """Stage the samples ``indices`` with one process per device, each a contiguous share.

    Args:
        progress: called as ``progress(0, frame, frames, scenes)`` from any device's simulator, and
            ``progress(1, samples_done, samples, 0)`` as devices finish.
        seconds_left: no device starts a batch that would end after this many seconds.

    Returns:
        ``tasks`` (per device: its name, pid, samples, seconds, simulator seconds, garment-frames,
        batches) and the sums the one-device summary has: ``simulate_seconds`` (the longest
        device's), ``garment_frames``, ``wait_seconds``, ``batches``, ``stopped``, and
        ``simulator_garment_frames_per_second`` (the devices' rates added).

    Raises:
        InputError: a device's process failed (what it said); the samples staged so far are kept.
    """
    parts = shares(list(indices), len(indices) or 1, len(devices))
    each = workers_per_device(workers, len(devices))
    ctx = multiprocessing.get_context("spawn")
    messages = ctx.Queue()
    procs = [ctx.Process(target=_device_process, daemon=False,
                         args=(config.as_dict(), str(out), part, devices[k], each, k, seconds_left, messages))
             for k, part in enumerate(parts)]
    for p in procs:
        p.start()
    tasks: dict[int, dict] = {}
    done_samples = 0
    try:
        while len(tasks) < len(procs):
            try:
                msg = messages.get(timeout=1.0)
            except queue_module.Empty:
                dead = [k for k, p in enumerate(procs) if not p.is_alive() and p.exitcode not in (0, None)
                        and k not in tasks]
                if dead:
                    k = dead[0]
                    raise InputError(f"the process simulating on {devices[k]} died (exit code {procs[k].exitcode}); "
                                     "the samples staged so far are kept: run the command again to resume")
                continue
            kind, task = msg[0], msg[1]
            if kind == "progress" and progress:
                progress(0, msg[2], msg[3], msg[4])
            elif kind == "done":
                tasks[task] = msg[2]
                done_samples += msg[2]["samples"]
                if progress:
                    progress(1, done_samples, len(indices), 0)
            elif kind == "error":
                what = msg[2]
                if msg[3]:
                    raise InputError(f"on {devices[task]}: {what.split(': ', 1)[1]}")
                raise InputError(f"the process simulating on {devices[task]} failed: {what}; the samples staged so far "
                                 "are kept: run the command again to resume")
    finally:
        for p in procs:
            if p.is_alive() and len(tasks) < len(procs):
                p.terminate()
        for p in procs:
            p.join()
    ordered = [tasks[k] for k in sorted(tasks)]
    return {"tasks": ordered,
            "simulate_seconds": max((t["simulate_seconds"] for t in ordered), default=0.0),
            "garment_frames": sum(t["garment_frames"] for t in ordered),
            "wait_seconds": sum(t["wait_seconds"] for t in ordered),
            "batches": sum(t["batches"] for t in ordered),
            "stopped": sum(t["stopped"] for t in ordered),
            "simulator_garment_frames_per_second": sum(t["garment_frames"] / t["simulate_seconds"]
                                                       for t in ordered if t["simulate_seconds"])}
