"""Sewing a dataset's pattern garments before its static groups (``drape generate``): every pattern
garment instance of a :class:`~datagen.generate.plan.Plan` sewn on its body at rest
(:func:`datagen.generate.garments.sewn_garment`) into the garment cache, where every process of the
run then reads it, with progress; on the run's GPU, or on CPU processes side by side."""

from __future__ import annotations

import logging
import time

from datagen.generate.plan import Plan

log = logging.getLogger(__name__)

_SEW_PLAN: dict = {}


def _sew_worker_init(config, devices) -> None:
    """A sewing process: its plan and the device it sews on, taken from ``devices`` (a queue of
    device names, one per process): ``cpu``, or a GPU, made the process's only visible one before
    CUDA starts (:func:`~datagen.generate.devices.pin_gpu`)."""
    import contextlib
    import os

    from datagen.lifetime import die_with_parent

    die_with_parent()  # a kill -9 of drape generate ends this worker too

    from datagen.generate.devices import pin_gpu

    device = pin_gpu(devices.get())
    os.environ.setdefault("OMP_NUM_THREADS", "1")  # the processes themselves are the parallelism
    if logging.getLogger().level > logging.DEBUG:  # warp's banner and compile lines: once, from the main process
        with contextlib.suppress(ImportError):
            from datagen.sim.device import quiet_warp

            quiet_warp(logging.ERROR, initialise=True)
    plan = Plan(config)
    plan.sew_device = device
    _SEW_PLAN["plan"] = plan


def _sew_one(g: int):
    """Sew instance g into the garment cache (where the main process reads it): (g, seconds, its
    :class:`~datagen.generate.garments.SewingRecord`)."""
    t = time.perf_counter()
    record = _SEW_PLAN["plan"].sewing(g)
    return g, time.perf_counter() - t, record


def sew_devices(devices) -> tuple[list[str], bool]:
    """(devices, on_gpu): where pattern garments are sewn for a run on ``devices`` (a
    :func:`~datagen.generate.devices.parse_devices` list): its CUDA devices, one sewing process on
    each (one: the main process, which simulates there anyway), else the CPU, ``workers`` processes
    side by side."""
    from datagen.sim.device import warp_device

    names = [warp_device(d) for d in devices]
    cuda = list(dict.fromkeys(n for n in names if n.startswith("cuda")))
    return (cuda, True) if cuda else (["cpu"], False)


def sew_patterns(plan: Plan, workers: int | None, devices=(None,), progress=None) -> None:
    """Sew the plan's pattern garment instances (into the garment cache) before the static groups.

    On a run's GPU (``devices``: :func:`sew_devices`) they are sewn there: in this process for one
    GPU (:attr:`Plan.sew_device`), or one process per GPU, each seeing only its own card. On the CPU,
    ``workers`` processes at once (a design sews in a minute or two on one core; one by one they hold
    up the start), or this process when ``workers`` < 2 or one is left. A design that cannot be sewn
    stops nothing: it is logged with the reason and its scenes are recorded as failed
    (:meth:`Plan.sew_failure`). ``progress(done, total)`` is called as each instance is done."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    todo = [g for g in range(len(plan.instances)) if plan.entry(g).is_pattern and not plan.has_garment(g)]
    if not todo:
        return
    names, on_gpu = sew_devices(devices)
    procs = len(names) if on_gpu else min(len(todo), workers if workers is not None else 1)
    t0 = time.perf_counter()
    failed = 0

    def done(k: int, g: int, seconds: float, record) -> None:
        nonlocal failed
        failed += record.failure is not None
        what = (f"could not be sewn ({record.failure}; its scenes are recorded as failed)" if record.failure else
                f"sewn, static after {record.settle_frames} settling frames" if record.static else
                "sewn, not static when settling stopped (its template is settled again)")
        log.info("sewing %d/%d: %s on %s %s, %.0f s (%.0f s so far)", k, len(todo), *plan.instances[g], what,
                 seconds, time.perf_counter() - t0)
        if progress:
            progress(k, len(todo))

    where = f"{procs} GPU processes ({', '.join(names)})" if on_gpu and procs > 1 else (
        names[0] if on_gpu or procs < 2 else f"{procs} CPU processes")
    log.info("sewing %d pattern garment instances on %s", len(todo), where)
    if progress:
        progress(0, len(todo))
    if procs < 2:
        plan.sew_device = names[0]
        for k, g in enumerate(todo, 1):
            t = time.perf_counter()
            record = plan.sewing(g)
            done(k, g, time.perf_counter() - t, record)
    else:
        ctx = multiprocessing.get_context("spawn")
        queue = ctx.Queue()  # each process takes its device (its own GPU, or the CPU) before anything starts
        for n in names if on_gpu else ["cpu"] * procs:
            queue.put(n)
        with ProcessPoolExecutor(procs, mp_context=ctx, initializer=_sew_worker_init,
                                 initargs=(plan.config, queue)) as pool:
            futures = [pool.submit(_sew_one, g) for g in todo]
            for k, f in enumerate(as_completed(futures), 1):
                done(k, *f.result())
    log.info("sewn %d pattern garment instances in %.0f s: %d could not be sewn", len(todo) - failed,
             time.perf_counter() - t0, failed)
