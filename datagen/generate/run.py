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
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from datagen.errors import InputError
from datagen.generate.config import DatasetConfig, parse_body, parse_garment, parse_motion

log = logging.getLogger(__name__)

SPLIT_CODES = {"train": 0, "val": 1, "test": 2}


@dataclass(frozen=True)
class ScenePlan:
    index: int
    split: str
    garment: int  # instance index
    body: int
    motion: int


class Plan:
    """The numbered scenes, bodies, motions and garment instances of a config (cheap to build;
    the heavy parts — body model, garments — are built on first use and cached per process)."""

    def __init__(self, config: DatasetConfig):
        self.config = config
        self.bodies: list[str] = []
        self.motions: list[str] = []
        self.instances: list[tuple[str, str]] = []  # (garment "type:seed", body name)
        self.scenes: list[ScenePlan] = []
        index = lambda lst, item: lst.index(item) if item in lst else (lst.append(item) or len(lst) - 1)  # noqa: E731
        for split, s in config.splits.items():
            for g in s.garments:
                for b in s.bodies:
                    bi = index(self.bodies, b)
                    gi = index(self.instances, (g, b))
                    for m in s.motions:
                        mi = index(self.motions, m)
                        self.scenes.append(ScenePlan(len(self.scenes), split, gi, bi, mi))

    @property
    def sample_count(self) -> int:
        return len(self.scenes)

    # ----------------------------------------------------------------------------- heavy parts

    @cached_property
    def body_model(self):
        from datagen.body.cache import default_body

        return default_body()

    @cached_property
    def subdivided(self):
        return self.body_model.subdivided()

    @cached_property
    def betas(self) -> np.ndarray:
        from datagen.body.shapes import resolve_betas

        out = []
        for b in self.bodies:
            name, seed = parse_body(b)
            out.append(resolve_betas(self.body_model, body=name)[0] if seed is None else
                       resolve_betas(self.body_model, seed=seed)[0])
        return np.stack(out)

    def motion(self, m: int):
        from datagen.motion.library import make_motion

        label, seed = parse_motion(self.motions[m])
        _, extra = self.run_config.ramp_frames(self.config.fps)
        return make_motion(label, seed=seed, frames=self.config.frames + extra, fps=self.config.fps)

    @cached_property
    def run_config(self):
        from datagen.sim.scene import RunConfig
        from datagen.sim.solver import SolverConfig

        s = self.config.simulation
        return RunConfig(settle_rest=s.settle_rest, lead_in=s.lead_in, settle_pose=s.settle_pose, ramp=s.ramp,
                         solver=SolverConfig(substeps=s.substeps, iterations=s.iterations,
                                             self_collision=s.self_collision))

    _garments: dict

    def garment(self, g: int):
        """Garment instance g (built once per process)."""
        cache = self.__dict__.setdefault("_garments", {})
        if g not in cache:
            from datagen.garment.cache import cached_garment

            kind, seed = parse_garment(self.instances[g][0])
            b = self.bodies.index(self.instances[g][1])
            cache[g] = cached_garment(kind, self.body_model, self.betas[b], seed=seed,
                                      target_edge_length=self.config.garment_edge_length)
        return cache[g]

    def correspondence(self, g: int) -> dict:
        cache = self.__dict__.setdefault("_corr", {})
        if g not in cache:
            from datagen.targets import garment_correspondence

            b = self.bodies.index(self.instances[g][1])
            cache[g] = garment_correspondence(self.garment(g).vertices, self.subdivided, self.betas[b])
        return cache[g]


# --------------------------------------------------------------------------------- static groups


def static_groups(plan: Plan) -> dict[str, tuple[dict, dict | None]]:
    """group -> (arrays, names) for every static group of the store."""
    from datagen.garment.materials import MATERIALS
    from datagen.garment.types import GARMENT_TYPES
    from datagen.motion.labels import LABELS
    from datagen.targets import fit_attribute, fit_attribute_model, fit_pair

    m = plan.body_model
    f32 = np.float32
    body = {"v_template": m.v_template.astype(f32), "shapedirs": m.shapedirs.astype(f32),
            "J_regressor": np.asarray(m.J_regressor.todense() if hasattr(m.J_regressor, "todense") else m.J_regressor,
                                      dtype=f32),
            "weights": m.weights.astype(f32), "parents": np.asarray(m.parents, dtype=np.int32),
            "faces": m.faces.astype(np.int32)}
    body["parents"][0] = -1
    motions = [plan.motion(i) for i in range(len(plan.motions))]
    motion_arrays = {"label": np.array([LABELS.index(parse_motion(s)[0]) for s in plan.motions], np.int32),
                     "seed": np.array([parse_motion(s)[1] for s in plan.motions], np.int32),
                     "frame_count": np.array([mo.frame_count for mo in motions], np.int32)}
    garments = [plan.garment(g) for g in range(len(plan.instances))]
    regions = sorted({r for g in garments for r in g.region_names})
    materials = list(MATERIALS)
    pairs = []
    for g in range(len(garments)):
        b = plan.bodies.index(plan.instances[g][1])
        pairs.append(fit_pair(garments[g].vertices, garments[g].faces, plan.subdivided, plan.betas[b],
                              indicator=plan.correspondence(g)["indicator"]))
    train = sorted({s.garment for s in plan.scenes if s.split == "train"})
    fit = fit_attribute_model([pairs[g] for g in train], subsample_count=min(len(g.vertices) for g in garments),
                              subsample_seed=plan.config.seed, random_state=plan.config.seed)
    alpha = np.stack([fit_attribute(fit, p) for p in pairs]).astype(f32)
    vs = np.concatenate([[0], np.cumsum([len(g.vertices) for g in garments])]).astype(np.int64)
    fs = np.concatenate([[0], np.cumsum([len(g.faces) for g in garments])]).astype(np.int64)
    garment_arrays = {
        "vertex_start": vs, "face_start": fs,
        "rest_vertices": np.concatenate([g.vertices for g in garments]).astype(f32),
        "faces": np.concatenate([g.faces for g in garments]).astype(np.int32),
        "uv": np.concatenate([g.uv for g in garments]).astype(f32),
        "region": np.concatenate([np.array([regions.index(g.region_names[r]) for r in g.vertex_region], np.int32)
                                  for g in garments]),
        "seam": np.concatenate([g.seam_vertex for g in garments]).astype(np.uint8),
        "indicator": np.concatenate([plan.correspondence(g)["indicator"] for g in range(len(garments))]).astype(
            np.int32),
        "skin_weights": np.concatenate([plan.correspondence(g)["skin_weights"] for g in range(len(garments))]).astype(
            f32),
        "type": np.array([list(GARMENT_TYPES).index(parse_garment(i[0])[0]) for i in plan.instances], np.int32),
        "seed": np.array([parse_garment(i[0])[1] for i in plan.instances], np.int32),
        "body": np.array([plan.bodies.index(i[1]) for i in plan.instances], np.int32),
        "material": np.array([materials.index(g.material.name) for g in garments], np.int32),
        "alpha": alpha,
        "rest_area": np.array([g.metadata.get("rest_area", _area(g.vertices, g.faces)) for g in garments], f32),
    }
    fa = fit.as_arrays()
    return {
        "body": (body, None),
        "bodies": ({"betas": plan.betas.astype(f32)}, {"body_names": list(plan.bodies)}),
        "motions": (motion_arrays, {"label_names": list(LABELS)}),
        "garments": (garment_arrays, {"garment_type_names": list(GARMENT_TYPES), "material_names": materials,
                                      "region_names": regions}),
        "fit": ({"components": fa["components"].astype(f32), "mean": fa["mean"].astype(f32),
                 "noise_variance": fa["noise_variance"].astype(f32), "subsample": fa["subsample"]}, None),
    }


def _area(v: np.ndarray, f: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum())


# --------------------------------------------------------------------------------------- samples


def failure_code(reason: str | None) -> int:
    from schemas.dataset import FAILURE_NAMES

    if reason is None:
        return 0
    head = reason.split(":")[0].strip()
    if head not in FAILURE_NAMES:
        raise InputError(f"simulator failure {reason!r} has no code in schemas.dataset.FAILURE_NAMES")
    return FAILURE_NAMES.index(head)


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
            motion = scene.motion
            k0 = r.motion_from
            frames = np.arange(k0, k0 + len(r.positions))
            if r.failure is None:
                corr = plan.correspondence(s.garment)
                poses, trans = motion.poses[frames], motion.trans[frames]
                t = sample_targets(plan.garment(s.garment).vertices, plan.garment(s.garment).faces, plan.subdivided,
                                   plan.betas[s.body], poses, trans, r.positions, indicator=corr["indicator"])
                body_v, _ = plan.body_model.pose(np.repeat(plan.betas[s.body][None], len(frames), 0),
                                                 poses.reshape(len(frames), -1), trans)
                arrays.update({k: np.asarray(v, np.float32) for k, v in t.items()})
                arrays["detail"] = r.positions.astype(np.float32)
                arrays.update(pose=poses.astype(np.float32), trans=trans.astype(np.float32),
                              label=np.full(len(frames), motion.label, np.int32),
                              body_vertices=body_v.astype(np.float32))
            else:  # a failed scene keeps its metrics and reason, no frames
                V, B = len(plan.garment(s.garment).vertices), plan.body_model.vertex_count
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


# ------------------------------------------------------------------------------------------ main


def open_writer(plan: Plan, out: str | Path):
    """The store ``out`` for ``plan`` (created, or reopened when its identity matches: the config
    without execution-only fields, the code version, seed, sample count and segment length)."""
    from datagen.generate.identity import code_version, identity_config
    from datagen.store import StoreWriter

    config = plan.config
    return StoreWriter.open(out, config=identity_config(config.as_dict()), code_version=code_version(),
                            seed=config.seed, sample_count=plan.sample_count, segment_length=config.segment_length)


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
