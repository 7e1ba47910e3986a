"""``--executor ray``: the scenes shared out as Ray tasks, one per GPU (or per CPU), each staging its
own samples into the store.

Placement. With ``device`` ``cuda`` every task asks Ray for one GPU; Ray sets the task's
``CUDA_VISIBLE_DEVICES`` to that GPU alone, so the task's warp device ``cuda:0`` is its own card
and no two tasks share one. The scenes are cut into at least as many contiguous shares as the
cluster has GPUs (more when a share would exceed ``simulation.batch_size``), so every GPU gets a
batch from the start. Each GPU task runs the same overlapped pipeline as the local executor
(:func:`~datagen.generate.samples.simulate_samples`) with its share of the CPUs as workers. On the
CPU every task is one CPU simulating one share in its own process.

Staging. Every sample is written under a temporary name unique to its process
(:func:`~datagen.store.layout.unique_temporary`: pid and a random suffix) and renamed into place
with its completion marker last, so tasks on different GPUs never share a staging file, and a
sample staged twice (a retried task) is staged once. The driver packs once every task is done.
A task is a pure function of the config and its scene indices: the store equals the local one.

Ray is optional: ``pip install 'drape[ray]'``. ``RAY_ADDRESS`` names an existing cluster;
otherwise a local one is started with ``workers`` CPUs and the GPUs Ray finds.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from datagen.errors import InputError
from datagen.generate.devices import shares, stage_share, task_record

__all__ = ["RayCluster", "import_ray", "shares", "uses_gpu"]


def import_ray():
    """The ``ray`` module, or an :class:`InputError` saying how to install it."""
    try:
        import ray
    except ImportError:
        raise InputError("--executor ray needs Ray: pip install 'drape[ray]' (or use --executor local)") from None
    return ray


def uses_gpu(device: str | None) -> bool:
    return bool(device) and str(device).startswith("cuda")


def _task(config_dict: dict, out: str, indices: list[int], device: str | None, workers: int, task: int,
          queue) -> dict:
    t0 = time.perf_counter()
    visible = os.environ.get("CUDA_VISIBLE_DEVICES")
    gpus = []
    if uses_gpu(device):
        import ray

        gpus = [int(g) if str(g).isdigit() else str(g) for g in ray.get_gpu_ids()]
        device = "cuda:0"  # Ray made this task's GPU the only visible one

    def progress(_kind, done, total, scenes):
        if queue is not None and (done % 20 == 0 or done == total):
            queue.put_nowait((task, done, total, scenes))

    result = stage_share(config_dict, out, indices, device, workers, progress=progress)
    return task_record(task, t0, result, gpus=gpus, cuda_visible_devices=visible)


class RayCluster:
    """A Ray cluster joined (``RAY_ADDRESS``) or started locally, checked for what ``device`` needs.

    Opened before the store is touched, so a missing Ray or a GPU-less cluster is an error before
    anything is written."""

    def __init__(self, device: str | None = None, workers: int | None = None):
        self.ray = ray = import_ray()
        self.device = device
        self.started = False
        if not ray.is_initialized():
            if os.environ.get("RAY_ADDRESS"):
                ray.init(address=os.environ["RAY_ADDRESS"], log_to_driver=False)
            else:
                ray.init(num_cpus=workers or os.cpu_count() or 1, include_dashboard=False, log_to_driver=False)
            self.started = True
        resources = ray.cluster_resources()
        self.cpus, self.gpus = int(resources.get("CPU", 1)), int(resources.get("GPU", 0))
        if uses_gpu(device) and self.gpus == 0:
            self.close()
            raise InputError(f"--device {device} with --executor ray, but the Ray cluster has no GPU (Ray found "
                             f"{self.cpus} CPUs); run on a host with CUDA GPUs or use --device cpu")

    def close(self) -> None:
        if self.started:
            self.ray.shutdown()
            self.started = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def run(self, config, out: str | Path, indices: list[int], *, progress=None) -> dict:
        """Stage the samples ``indices`` with Ray tasks: one per GPU (``device`` cuda) or per CPU.

        Args:
            progress: called as ``progress(0, frame, frames, scenes)`` from any task's simulator, and
                ``progress(1, samples_done, samples, 0)`` as tasks finish.

        Returns:
            ``tasks``: per task its GPU ids, ``CUDA_VISIBLE_DEVICES``, samples, seconds, simulator
            seconds and garment-frames; ``gpus`` and ``cpus``: what the cluster offered.
        """
        ray, device = self.ray, self.device
        if uses_gpu(device):
            per_task = max(1, self.cpus // self.gpus)
            options = {"num_cpus": per_task, "num_gpus": 1}
            pipeline_workers, slots = per_task - 1, self.gpus
        else:
            options = {"num_cpus": 1, "num_gpus": 0}
            pipeline_workers, slots = 0, self.cpus
        from ray.util.queue import Empty, Queue

        queue = Queue(actor_options={"num_cpus": 0})
        remote = ray.remote(max_retries=2)(_task).options(**options)
        parts = shares(list(indices), config.simulation.batch_size, slots)
        pending = [remote.remote(config.as_dict(), str(out), part, device, pipeline_workers, k, queue)
                   for k, part in enumerate(parts)]
        tasks, done = [], 0
        while pending:
            ready, pending = ray.wait(pending, num_returns=1, timeout=1.0)
            while True:
                try:
                    _task_no, frame, frames, scenes = queue.get_nowait()
                except Empty:
                    break
                if progress:
                    progress(0, frame, frames, scenes)
            for ref in ready:
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayTaskError as exc:
                    cause = exc.cause if getattr(exc, "cause", None) is not None else exc
                    if isinstance(cause, InputError):
                        raise cause from None
                    raise InputError(f"a Ray task failed: {type(cause).__name__}: {cause}; the samples staged so "
                                     "far are kept: run the command again to resume") from None
                tasks.append(result)
                done += result["samples"]
                if progress:
                    progress(1, done, len(indices), 0)
        return {"tasks": sorted(tasks, key=lambda t: t["task"]), "gpus": self.gpus, "cpus": self.cpus}
