"""The samples of a plan: scenes simulated in batches, each result turned into what the store keeps
(:func:`sample_arrays`) and staged.

Two ways to run (:func:`simulate_samples`):

- **Overlapped** (``drape generate``'s local executor): a pool of worker processes computes the
  targets of batch k and stages them into the store while batch k + 1 simulates, and builds the
  garments of batch k + 1 (into the garment cache) while batch k simulates. The simulating process
  only loads garments, runs the simulator and hands results over.
- **In process** (``on_sample``): each result goes to a callback after its batch (the Ray
  executor's tasks, tests).

Both give the same store: a sample is a pure function of its scene.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from datagen.errors import InputError
from datagen.generate.plan import SPLIT_CODES, Plan, ScenePlan

log = logging.getLogger(__name__)


def failure_code(failure) -> int:
    """The store's code of a :class:`~datagen.sim.metrics.Failure` (0 for None)."""
    from schemas.dataset import FAILURE_NAMES

    if failure is None:
        return 0
    if failure.code not in FAILURE_NAMES:
        raise InputError(f"simulator failure code {failure.code!r} has no entry in schemas.dataset.FAILURE_NAMES")
    return FAILURE_NAMES.index(failure.code)


@dataclass(frozen=True)
class Outcome:
    """What a sample needs of its scene's :class:`~datagen.sim.scene.SceneResult` (small enough to
    send to a worker: no body frames)."""

    positions: np.ndarray
    poses: np.ndarray
    trans: np.ndarray
    metrics: dict
    recorded_from: int
    failure_code: int
    failure_frame: int
    label: int
    seconds: float

    @classmethod
    def of(cls, result, label: int, seconds: float) -> Outcome:
        return cls(positions=result.positions, poses=result.poses, trans=result.trans, metrics=result.metrics,
                   recorded_from=result.recorded_from, failure_code=failure_code(result.failure),
                   failure_frame=result.failure_frame, label=int(label), seconds=seconds)

    @classmethod
    def not_simulated(cls, failure, label: int) -> Outcome:
        """A scene failed before it was simulated (its garment could not be sewn, ``failure``): no
        simulated frame, so no frames, metrics of length 0 and failure frame -1."""
        from schemas.dataset import ARRAYS

        from datagen.sim.metrics import METRIC_NAMES

        metrics = {k: np.zeros(0, ARRAYS[f"sim_frames/metric_{k}"].dtype) for k in METRIC_NAMES}
        return cls(positions=np.zeros((0, 0, 3), np.float32), poses=np.zeros((0, 24, 3)), trans=np.zeros((0, 3)),
                   metrics=metrics, recorded_from=0, failure_code=failure_code(failure), failure_frame=-1,
                   label=int(label), seconds=0.0)


def sample_arrays(plan: Plan, s: ScenePlan, o: Outcome) -> tuple[dict, dict]:
    """(arrays, scalars) of one sample, as ``StoreWriter.stage_sample`` takes them: the simulated
    positions, the coarse target and the joints (every other target is derived on read), the
    motion's pose, translation and label, and the metrics; a failed scene keeps its metrics only."""
    from datagen.targets import stored_targets

    arrays = {f"metric_{k}": np.asarray(v) for k, v in o.metrics.items()}
    arrays["metric_nan"] = arrays["metric_nan"].astype(np.uint8)
    if o.failure_code == 0:
        garment = plan.garment(s.garment)
        # the body model's joints equal the subdivided body's (its regressor ignores the midpoints)
        arrays.update(stored_targets(garment.faces, plan.body_model, plan.betas[s.body], o.poses, o.trans,
                                     o.positions))
        arrays.update(detail=o.positions.astype(np.float32), pose=o.poses.astype(np.float32),
                      trans=o.trans.astype(np.float32), label=np.full(len(o.positions), o.label, np.int32))
    scalars = {"garment": s.garment, "body": s.body, "motion": s.motion, "split": SPLIT_CODES[s.split],
               "failure": o.failure_code, "failure_frame": o.failure_frame, "recorded_from": o.recorded_from,
               "seconds": o.seconds}
    return arrays, scalars


# ------------------------------------------------------------------------------- worker processes

_WORKER: dict = {}


def _init_worker(config, out: str) -> None:
    from datagen.generate.plan import open_writer
    from datagen.lifetime import die_with_parent

    die_with_parent()  # a kill -9 of drape generate ends this worker too

    # one BLAS thread per worker: the workers themselves are the parallelism
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    if logging.getLogger().level > logging.DEBUG:  # warp's banner, compile lines and driver notice: once, from the main process
        with contextlib.suppress(ImportError):
            from datagen.sim.device import quiet_warp

            quiet_warp(logging.ERROR, initialise=True)
    plan = Plan(config)
    _WORKER.update(plan=plan, writer=open_writer(plan, out))


def _build_garments(garments: Sequence[int]) -> int:
    plan = _WORKER["plan"]
    for g in garments:
        plan.garment(g)  # built into the garment cache, where the simulating process finds it
    return len(garments)


def _finish(s: ScenePlan, o: Outcome) -> int:
    arrays, scalars = sample_arrays(_WORKER["plan"], s, o)
    _WORKER["writer"].stage_sample(s.index, arrays, scalars)
    return s.index


def default_workers() -> int:
    """Worker processes for the overlapped pipeline: the cores beside the simulating one, at most 16
    (with one batch they all work at once after it: at most 8 left a 16-core GPU host waiting 28 s
    for the targets of paper-motion's 252 scenes)."""
    return max(1, min(16, (os.cpu_count() or 2) - 1))


# ------------------------------------------------------------------------------------ the loop


def simulate_samples(plan: Plan, indices: Sequence[int], device: str | None,
                     on_sample: Callable[[int, dict, dict], None] | None = None, progress=None, *,
                     out: str | Path | None = None, workers: int = 0, deadline: float | None = None) -> dict:
    """Simulate the scenes ``indices`` in batches of ``simulation.batch_size`` and stage their samples.

    Args:
        plan: the dataset's plan.
        indices: scene indices to simulate.
        device: warp device (``None``: warp's default).
        on_sample: in-process mode: called with (index, arrays, scalars) of every sample.
        progress: called as ``progress(done_batches, done_frames, total_frames, scenes)`` by the simulator.
        out: overlapped mode: the store the workers stage into (with ``workers > 0``).
        workers: worker processes of the overlapped mode.
        deadline: a ``time.perf_counter()`` time: no batch is started that the last batch's time
            per scene says would end after it (the first batch always runs); ``None``: no limit.

    A scene whose garment could not be sewn (:meth:`~datagen.generate.plan.Plan.sew_failure`) is not
    simulated: it is staged as failed with that reason (code ``seam``), no frames and no metrics.

    Returns:
        timings: ``simulate_seconds`` (inside the simulator), ``garment_frames`` (recorded, ok
        samples), ``wait_seconds`` (the simulating process waiting for workers), ``batches`` (run),
        ``stopped`` (batches left out at the deadline).
    """
    from datagen.sim.scene import Scene, simulate

    if (on_sample is None) == (out is None or workers <= 0):
        raise InputError("give either on_sample (in process) or out and workers > 0 (overlapped)")
    bs = plan.config.simulation.batch_size
    batches = [list(indices[k:k + bs]) for k in range(0, len(indices), bs)]
    stats = {"simulate_seconds": 0.0, "garment_frames": 0, "wait_seconds": 0.0, "batches": 0, "stopped": 0}
    per_scene = None  # seconds a scene of the last batch took, wall time
    pool = None
    if on_sample is None:
        pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_init_worker, initargs=(plan.config, str(out)))
    try:
        garments_ready: Future | None = None
        pending: list[Future] = []
        if pool is not None and batches:
            garments_ready = _prefetch(pool, plan, batches[0], workers)
        for k, idx in enumerate(batches):
            if deadline is not None and per_scene is not None and time.perf_counter() + per_scene * len(idx) > deadline:
                stats["stopped"] = len(batches) - k
                log.info("time limit: %d of %d batches left for the next run", len(batches) - k, len(batches))
                break
            started = time.perf_counter()
            batch = [plan.scenes[i] for i in idx]
            if garments_ready is not None:
                t = time.perf_counter()
                for f in garments_ready:
                    f.result()
                stats["wait_seconds"] += time.perf_counter() - t
            if pool is not None and k + 1 < len(batches):  # the next batch's garments while this one runs
                garments_ready = _prefetch(pool, plan, batches[k + 1], workers)
            unsewn = [s for s in batch if plan.sew_failure(s.garment) is not None]
            for s in unsewn:  # its garment could not be sewn: failed with the reason, not simulated
                o = Outcome.not_simulated(plan.sew_failure(s.garment), plan.motion(s.motion).label)
                if pool is not None:
                    pending.append(pool.submit(_finish, s, o))
                else:
                    on_sample(s.index, *sample_arrays(plan, s, o))
            batch = [s for s in batch if plan.sew_failure(s.garment) is None]
            scenes = [Scene(garment=plan.garment(s.garment), body=plan.body_model, betas=plan.betas[s.body],
                            motion=plan.motion(s.motion)) for s in batch]
            t0 = time.perf_counter()
            results = simulate(scenes, plan.run_config, device=device,
                               progress=(lambda d, n, b=len(batch): progress(0, d, n, b)) if progress else None
                               ) if scenes else []
            seconds = time.perf_counter() - t0
            stats["simulate_seconds"] += seconds if scenes else 0.0
            for s, scene, r in zip(batch, scenes, results, strict=True):
                o = Outcome.of(r, scene.motion.label, seconds / len(batch))
                stats["garment_frames"] += len(r.positions) if o.failure_code == 0 else 0
                if pool is not None:
                    pending.append(pool.submit(_finish, s, o))
                else:
                    on_sample(s.index, *sample_arrays(plan, s, o))
            del results, scenes
            pending = _collect(pending, block=False)
            stats["batches"] += 1
            per_scene = (time.perf_counter() - started) / len(idx)
        t = time.perf_counter()
        _collect(pending, block=True)
        stats["wait_seconds"] += time.perf_counter() - t
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    return stats


def _prefetch(pool: ProcessPoolExecutor, plan: Plan, batch: list[int], workers: int) -> list[Future]:
    """Build the batch's garments not yet in this process, spread over the workers."""
    todo = sorted(g for g in {plan.scenes[i].garment for i in batch} if not plan.has_garment(g))
    return [pool.submit(_build_garments, todo[w::workers]) for w in range(min(workers, len(todo)))]


def _collect(pending: list[Future], *, block: bool) -> list[Future]:
    """Raise the first worker error; return the futures not yet done (none when ``block``)."""
    left = []
    for f in pending:
        if block or f.done():
            f.result()
        else:
            left.append(f)
    return left
