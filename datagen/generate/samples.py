"""The samples of a plan: scenes simulated in batches, each result turned into the targets of
:mod:`datagen.targets` and handed to a callback (which stages it)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from datagen.errors import InputError
from datagen.generate.plan import SPLIT_CODES, Plan


# --------------------------------------------------------------------------------------- samples


def failure_code(failure) -> int:
    """The store's code of a :class:`~datagen.sim.metrics.Failure` (0 for None)."""
    from schemas.dataset import FAILURE_NAMES

    if failure is None:
        return 0
    if failure.code not in FAILURE_NAMES:
        raise InputError(f"simulator failure code {failure.code!r} has no entry in schemas.dataset.FAILURE_NAMES")
    return FAILURE_NAMES.index(failure.code)


def simulate_samples(plan: Plan, indices: Sequence[int], device: str | None,
                     on_sample: Callable[[int, dict, dict], None], progress=None) -> None:
    """Simulate the scenes ``indices`` in batches; hand each sample's (arrays, scalars) to ``on_sample``."""
    from datagen.sim.scene import Scene, simulate
    from datagen.targets import sample_targets

    bs = plan.config.simulation.batch_size
    for start in range(0, len(indices), bs):
        batch = [plan.scenes[i] for i in indices[start:start + bs]]
        scenes = [Scene(garment=plan.garment(s.garment), body=plan.body_model, betas=plan.betas[s.body],
                        motion=plan.motion(s.motion)) for s in batch]
        t0 = time.perf_counter()
        results = simulate(scenes, plan.run_config, device=device,
                           progress=(lambda d, n, b=len(batch): progress(0, d, n, b)) if progress else None)
        for s, scene, r in zip(batch, scenes, results):
            arrays = {f"metric_{k}": np.asarray(v) for k, v in r.metrics.items()}
            arrays["metric_nan"] = arrays["metric_nan"].astype(np.uint8)
            garment = plan.garment(s.garment)
            if r.failure is None:
                # the simulator returns the recorded frames' poses and posed body (no posing again)
                t = sample_targets(garment.vertices, garment.faces, plan.subdivided, plan.betas[s.body], r.poses,
                                   r.trans, r.positions, indicator=plan.correspondence(s.garment)["indicator"])
                arrays.update({k: np.asarray(v, np.float32) for k, v in t.items()})
                arrays["detail"] = r.positions.astype(np.float32)
                arrays.update(pose=r.poses.astype(np.float32), trans=r.trans.astype(np.float32),
                              label=np.full(len(r.positions), scene.motion.label, np.int32),
                              body_vertices=r.body_vertices.astype(np.float32))
            else:  # a failed scene keeps its metrics and reason, no frames
                V, B = len(garment.vertices), plan.body_model.vertex_count
                z = lambda *shape: np.zeros(shape, np.float32)  # noqa: E731
                arrays.update({k: z(0, V, 3) for k in ("detail", "coarse", "anchor", "anchor_normal", "anchor_skin",
                                                       "coarse_normal", "skin")})
                arrays.update(joint_distance=z(0, V, 24), joints=z(0, 24, 3), pose=z(0, 24, 3), trans=z(0, 3),
                              label=np.zeros(0, np.int32), body_vertices=z(0, B, 3))
            scalars = {"garment": s.garment, "body": s.body, "motion": s.motion, "split": SPLIT_CODES[s.split],
                       "failure": failure_code(r.failure), "failure_frame": r.failure_frame,
                       "recorded_from": r.recorded_from,
                       "seconds": (time.perf_counter() - t0) / len(batch)}
            on_sample(s.index, arrays, scalars)
