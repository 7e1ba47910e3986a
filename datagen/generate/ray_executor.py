"""``--executor ray``: scene batches as Ray tasks, each staging its own samples into the store.

Each task rebuilds the plan from the config (a pure function of it), simulates its batch and
stages every sample atomically (writers never share a file); the driver packs once all are
staged. On a Ray cluster, tasks ask for one GPU each when ``device`` is ``cuda``. Ray is optional:
``pip install 'drape[ray]'``.
"""

from __future__ import annotations

from pathlib import Path

from datagen.errors import InputError


def _import_ray():
    try:
        import ray
    except ImportError:
        raise InputError("--executor ray needs Ray: pip install 'drape[ray]' (or use --executor local)") from None
    return ray


def _task(config_dict: dict, out: str, indices: list[int], device: str | None) -> list[int]:
    from datagen.config import load_config
    from datagen.generate.config import DatasetConfig
    from datagen.generate.plan import Plan, open_writer
    from datagen.generate.samples import simulate_samples

    plan = Plan(load_config(DatasetConfig, config_dict))
    writer = open_writer(plan, out)
    todo = writer.missing(indices)
    simulate_samples(plan, todo, device, lambda i, a, s: writer.stage_sample(i, a, s))
    return todo


def run_ray(config, out: str | Path, indices: list[int], *, device: str | None = None, workers: int = 2,
            progress=None) -> None:
    """Stage the samples ``indices`` with Ray tasks of ``config.simulation.batch_size`` scenes.

    Uses the Ray cluster named by ``RAY_ADDRESS`` if set, else starts a local one with ``workers``
    CPUs."""
    import os

    ray = _import_ray()
    started = False
    if not ray.is_initialized():
        if os.environ.get("RAY_ADDRESS"):
            ray.init(address=os.environ["RAY_ADDRESS"], log_to_driver=False)
        else:
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
        started = True
    try:
        gpus = 1 if device and device.startswith("cuda") else 0
        remote = ray.remote(num_cpus=1, num_gpus=gpus, max_retries=2)(_task)
        bs = config.simulation.batch_size
        batches = [indices[i:i + bs] for i in range(0, len(indices), bs)]
        pending = [remote.remote(config.as_dict(), str(out), b, device) for b in batches]
        done = 0
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            done += len(ray.get(ready[0]))
            if progress:
                progress(1, done, len(indices), 0)
    finally:
        if started:
            ray.shutdown()
