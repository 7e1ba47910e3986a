"""The plan of a dataset: its numbered scenes, bodies, motions and garment instances, the heavy
parts built on first use (body model, garments, correspondences), the static groups of its store,
and the store it writes (:func:`open_writer`). A pure function of the config."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from datagen.generate.config import DatasetConfig, motion_file, parse_body, parse_motion

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
        self._garments: dict[int, object] = {}  # instance -> GarmentMesh, built on first use
        self._correspondences: dict[int, dict] = {}  # instance -> garment_correspondence(...)
        self._motion_cache: dict[int, object] = {}  # motion index -> Motion, made on first use
        self.fit_diagnostics: dict | None = None  # set by static_groups()
        self.templates: list[np.ndarray] | None = None  # the garments settled at rest, set by static_groups()
        self.template_figures: dict | None = None
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
        """Motion m (made once per process: a batch's scenes that share it share one object, so
        the simulator poses the body over it once)."""
        if m not in self._motion_cache:
            self._motion_cache[m] = self._make_motion(m)
        return self._motion_cache[m]

    def _make_motion(self, m: int):
        from datagen.motion.library import make_motion

        frames = self.run_config.motion_frames(self.config.frames, self.config.fps)
        path = motion_file(self.motions[m])
        if path is not None:
            return load_motion_file(path, frames, self.config.fps)
        label, seed = parse_motion(self.motions[m])
        return make_motion(label, seed=seed, frames=frames, fps=self.config.fps)

    @property
    def run_config(self):
        """How every scene is run: the config's simulation settings (a :class:`RunConfig`)."""
        return self.config.simulation

    def has_garment(self, g: int) -> bool:
        """Whether garment instance g is built in this process already."""
        return g in self._garments

    def garment(self, g: int):
        """Garment instance g (built once per process)."""
        cache = self._garments
        if g not in cache:
            from datagen.generate.garments import build_garment

            b = self.bodies.index(self.instances[g][1])
            cache[g] = build_garment(self.entry(g), self.body_model, self.betas[b], self.config.garment_edge_length,
                                     self.run_config)
        return cache[g]

    def entry(self, g: int):
        """The parsed config entry of garment instance g (:class:`~datagen.generate.garments.GarmentEntry`)."""
        from datagen.generate.garments import parse_garment_entry

        return parse_garment_entry(self.instances[g][0])

    def template(self, g: int) -> np.ndarray:
        """Garment instance g's template [V, 3] (m): its settled drape at rest once
        :func:`static_groups` has settled the garments, else its construction."""
        return np.asarray(self.garment(g).vertices if self.templates is None else self.templates[g])

    def correspondence(self, g: int) -> dict:
        cache = self._correspondences
        if g not in cache:
            from datagen.targets import garment_correspondence

            b = self.bodies.index(self.instances[g][1])
            cache[g] = garment_correspondence(self.template(g), self.subdivided, self.betas[b])
        return cache[g]


# --------------------------------------------------------------------------------- static groups


_SEW_PLAN: dict = {}


def _sew_worker_init(config) -> None:
    from datagen.lifetime import die_with_parent

    die_with_parent()  # a kill -9 of drape generate ends this worker too
    _SEW_PLAN["plan"] = Plan(config)


def _sew_one(g: int) -> int:
    _SEW_PLAN["plan"].garment(g)  # sewn into the garment cache, where the main process reads it
    return g


def sew_patterns(plan: Plan, workers: int | None) -> None:
    """Sew the plan's pattern garment instances not in the garment cache yet, ``workers`` processes at
    once (a design sews in a minute or two on one CPU core; one by one they would hold up the start).
    A design that cannot be sewn is refused here, before any scene is simulated."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    todo = [g for g in range(len(plan.instances)) if plan.entry(g).is_pattern and not plan.has_garment(g)]
    workers = min(len(todo), workers if workers is not None else 1)
    if len(todo) < 2 or workers < 2:
        return  # built one by one where they are first needed
    t0 = time.perf_counter()
    log.info("sewing %d pattern garment instances on %d processes", len(todo), workers)
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"), initializer=_sew_worker_init,
                             initargs=(plan.config,)) as pool:
        for done, g in enumerate(pool.map(_sew_one, todo), 1):
            log.info("sewn %d/%d (%s on %s), %.0f s so far", done, len(todo), *plan.instances[g], time.perf_counter() - t0)


def static_groups(plan: Plan, device: str | None = None) -> dict[str, tuple[dict, dict | None]]:
    """group -> (arrays, names) for every static group of the store (the fit group's diagnostics are
    :meth:`Plan.fit_diagnostics` once this has run). The garments are settled at rest on ``device``
    first (:mod:`datagen.generate.templates`): their templates give ``garments/rest_vertices``, the
    indicator, the skinning weights and the fit attribute."""
    from datagen.body.subdivide import subdivision_edges
    from datagen.generate.garments import pattern_arrays, store_type_names
    from datagen.generate.templates import settle_templates
    from datagen.materials import MATERIALS
    from datagen.motion.labels import LABELS

    m = plan.body_model
    f32 = np.float32
    body = {"v_template": m.v_template.astype(f32), "shapedirs": m.shapedirs.astype(f32),
            "J_regressor": np.asarray(m.J_regressor.todense() if hasattr(m.J_regressor, "todense") else m.J_regressor,
                                      dtype=f32),
            "weights": m.weights.astype(f32), "parents": np.asarray(m.parents, dtype=np.int32),
            "faces": m.faces.astype(np.int32)}
    body["parents"][0] = -1
    edges = subdivision_edges(m.faces)
    fine = plan.subdivided
    B = m.vertex_count
    if len(fine.v_template) != B + len(edges) or not np.allclose(
            fine.v_template[B:], 0.5 * (m.v_template[edges[:, 0]] + m.v_template[edges[:, 1]]), rtol=0, atol=1e-12):
        raise RuntimeError("the subdivided body's midpoints are not in subdivision_edges order (trimesh changed?)")
    body["subdivision_edges"] = edges
    body["subdivided_faces"] = fine.faces.astype(np.int32)
    motions = [plan.motion(i) for i in range(len(plan.motions))]
    motion_arrays = {"label": np.array([mo.label for mo in motions], np.int32),
                     "seed": np.array([parse_motion(s)[1] for s in plan.motions], np.int32),
                     "frame_count": np.array([mo.frame_count for mo in motions], np.int32)}
    # every motion's recorded frames, whatever its scenes do: the motion generator's data (schema 5)
    rec = plan.run_config.recorded_motion_frames(plan.config.frames, plan.config.fps)
    motion_arrays["pose"] = np.stack([np.asarray(mo.poses, f32).reshape(mo.frame_count, -1, 3)[rec] for mo in motions])
    motion_arrays["trans"] = np.stack([np.asarray(mo.trans, f32).reshape(mo.frame_count, 3)[rec] for mo in motions])
    garments = []
    t0 = time.perf_counter()
    for g in range(len(plan.instances)):  # built (or read from the garment cache) one by one: say so
        t = time.perf_counter()
        garments.append(plan.garment(g))
        seconds = time.perf_counter() - t
        if seconds > 1.0 or g + 1 == len(plan.instances):
            log.info("garment %d/%d (%s on %s): %d vertices, %.1f s (%.0f s so far)", g + 1, len(plan.instances),
                     *plan.instances[g], len(garments[-1].vertices), seconds, time.perf_counter() - t0)
    regions = sorted({r for g in garments for r in g.region_names})
    materials = list(MATERIALS)
    templates, settled, plan.template_figures = settle_templates(plan, garments, device)
    plan.templates = templates
    alpha, fa, plan.fit_diagnostics = fit_alpha(plan, garments)
    type_names = store_type_names()
    entries = [plan.entry(g) for g in range(len(garments))]
    vs = np.concatenate([[0], np.cumsum([len(g.vertices) for g in garments])]).astype(np.int64)
    fs = np.concatenate([[0], np.cumsum([len(g.faces) for g in garments])]).astype(np.int64)
    garment_arrays = {
        "vertex_start": vs, "face_start": fs,
        "rest_vertices": np.concatenate(templates).astype(f32),
        "built_vertices": np.concatenate([g.vertices for g in garments]).astype(f32),
        "settled": settled,
        "faces": np.concatenate([g.faces for g in garments]).astype(np.int32),
        "uv": np.concatenate([g.uv for g in garments]).astype(f32),
        "region": np.concatenate([np.array([regions.index(g.region_names[r]) for r in g.vertex_region], np.int32)
                                  for g in garments]),
        "seam": np.concatenate([g.seam_vertex for g in garments]).astype(np.uint8),
        "indicator": np.concatenate([plan.correspondence(g)["indicator"] for g in range(len(garments))]).astype(
            np.int32),
        "skin_weights": np.concatenate([plan.correspondence(g)["skin_weights"] for g in range(len(garments))]).astype(
            f32),
        "type": np.array([type_names.index(e.type_name) for e in entries], np.int32),
        "seed": np.array([e.seed for e in entries], np.int32),
        "body": np.array([plan.bodies.index(i[1]) for i in plan.instances], np.int32),
        "material": np.array([materials.index(g.material.name) for g in garments], np.int32),
        "alpha": alpha,
        "rest_area": np.array([_area(g.vertices, g.faces) if g.metadata.rest_area_m2 is None else g.metadata.rest_area_m2
                               for g in garments], f32),
        **pattern_arrays(entries, garments),
    }
    return {
        "body": (body, None),
        "bodies": ({"betas": plan.betas.astype(f32)}, {"body_names": list(plan.bodies)}),
        "motions": (motion_arrays, {"label_names": list(LABELS)}),
        "garments": (garment_arrays, {"garment_type_names": type_names, "material_names": materials,
                                      "region_names": regions}),
        "fit": ({"components": fa["components"].astype(f32), "mean": fa["mean"].astype(f32),
                 "noise_variance": fa["noise_variance"].astype(f32), "subsample": fa["subsample"]}, None),
    }


def fit_alpha(plan: Plan, garments: list) -> tuple[np.ndarray, dict, dict]:
    """(α [G, 3] float32, the fit group's arrays, diagnostics): a factor analysis over the training
    split's garment-body pairs, or NaN α, D = 0 arrays and {} when the config has no fit attribute."""
    import logging

    from datagen.generate.config import FIT_FACTORS
    from datagen.targets import fit_attribute, fit_attribute_model, fit_diagnostics, fit_pair

    G = len(garments)
    if not plan.config.fit_attribute:
        none = {"components": np.zeros((FIT_FACTORS, 0)), "mean": np.zeros(0), "noise_variance": np.zeros(0),
                "subsample": np.zeros(3, np.int64)}
        return np.full((G, FIT_FACTORS), np.nan, np.float32), none, {}
    pairs = []
    for g in range(G):
        b = plan.bodies.index(plan.instances[g][1])
        pairs.append(fit_pair(plan.template(g), garments[g].faces, plan.subdivided, plan.betas[b],
                              indicator=plan.correspondence(g)["indicator"]))
    train = [pairs[g] for g in sorted({s.garment for s in plan.scenes if s.split == "train"})]
    fit = fit_attribute_model(train, factor_count=FIT_FACTORS, subsample_count=min(len(g.vertices) for g in garments),
                              subsample_seed=plan.config.seed, random_state=plan.config.seed)
    alpha = np.stack([fit_attribute(fit, p) for p in pairs]).astype(np.float32)
    diagnostics = fit_diagnostics(train, pairs, fit, random_state=plan.config.seed)
    for w in diagnostics["warnings"]:
        logging.getLogger(__name__).warning("fit attribute: %s", w)
    return alpha, fit.as_arrays(), diagnostics


def _area(v: np.ndarray, f: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum())


def load_motion_file(path: Path, frames: int, fps: float):
    """A motion file as a scene's motion: resampled to ``fps``, its first ``frames`` frames, its
    label as drape's class (-1 when the name is not one of drape's labels)."""
    from dataclasses import replace

    from datagen.errors import InputError
    from datagen.motion.labels import LABELS
    from datagen.motion.motion import Motion

    m = Motion.load_npz(path)
    if abs(m.fps - fps) > 1e-6:
        m = m.resample(fps)
    if m.frame_count < frames:
        raise InputError(f"motion file {path} has {m.frame_count} frames at {fps:g} fps; a scene of this config needs "
                         f"{frames} (the recorded frames and the ramp into the motion): lower frames or give a "
                         "longer motion (drape sample motion samples the length it was trained on)")
    label = LABELS.index(m.label_name) if m.label_name in LABELS else -1
    return replace(m, poses=m.poses[:frames], trans=m.trans[:frames], label=label)


def input_digest(plan: Plan) -> str:
    """A 16-hex-digit digest of the motion files a plan reads ("" when it reads none): part of the
    store's identity, so a store is never resumed with a changed motion file."""
    import hashlib

    files = [motion_file(m) for m in plan.motions if motion_file(m) is not None]
    if not files:
        return ""
    h = hashlib.blake2b(digest_size=8)
    for f in files:
        h.update(str(f).encode())
        h.update(Path(f).read_bytes())
    return h.hexdigest()


def open_writer(plan: Plan, out: str | Path):
    """The store ``out`` for ``plan`` (created, or reopened when its identity matches: the config
    without execution-only fields, the code version, seed, sample count and segment length)."""
    from datagen.generate.identity import code_version, identity_config
    from datagen.store import StoreWriter

    config = plan.config
    inputs = input_digest(plan)
    version = code_version() + (f"+inputs-{inputs}" if inputs else "")
    return StoreWriter.open(out, config=identity_config(config.as_dict()), code_version=version,
                            seed=config.seed, sample_count=plan.sample_count, segment_length=config.segment_length)


