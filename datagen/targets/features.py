"""Garment-body correspondence, node features and per-frame targets of paper 000 (§4.1-4.4).

For one sample (a garment instance on a body, a pose sequence and the simulated garment) this
module computes, as pure functions on arrays:

- the indicator I (§4.1): each garment vertex's closest vertex of the *subdivided* body in the
  rest pose (shaped by β), :func:`garment_indicator`;
- the anchor ``I M_b`` (eq. 5) with its vertex normals n^{b'} (§4.3), posing only the body rows
  that are needed (:func:`pose_body_rows`; LBS is per vertex, so this is exact);
- relative skinning features ``p = Σ_s w_s G_s(θ) G_s(θ*)^-1 p̄`` (§4.3, [LSK21]) of the anchor
  body vertices and of the garment vertices (:func:`relative_skinning`);
- the coarse target (:mod:`datagen.targets.coarse`), its vertex normals and the distances from
  every coarse garment vertex to every posed joint (§4.4, :func:`joint_distances`).

:func:`sample_targets` is the entry point for one sample; :func:`garment_correspondence` gives
what depends on the garment instance only (indicator, skinning weights, rest distances).

G_s is SMPL's world transform of joint s (a 4x4 rigid transform: the rotations composed along
the kinematic chain and the joint positions J(β)), as in SMPL's ``G'_k = G_k(θ, J) G_k(θ*, J)^-1``
which the paper's formula copies; it does not include the root translation ``trans``. So
``G_s(θ) G_s(θ*)^-1`` is exactly the skinning transform of :func:`datagen.body.lbs.rigid_transforms_np`,
and the feature is the linearly skinned rest position without the translation: unchanged when the
body is moved (paper: "when the body is moved to an arbitrary location (no rotation), the body
vertex position changes while the relative skinning feature remains the same"), equal to p̄ in
the rest pose. p̄ is the shaped rest position ``T + B_s(β)`` (no pose blend shapes), so for a body
without pose blend shapes (drape's default) ``anchor_skin = anchor - trans`` exactly.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from datagen.body.lbs import rigid_transforms_np
from datagen.body.model import BodyModel
from datagen.errors import InputError
from datagen.geometry.rotations import axis_angle_to_matrix_np
from datagen.targets.coarse import SmoothingConfig, coarse_from_detail

__all__ = [
    "garment_body_distances",
    "garment_correspondence",
    "garment_indicator",
    "garment_skin_weights",
    "joint_distances",
    "pose_body_rows",
    "relative_skinning",
    "TARGET_NAMES",
    "sample_targets",
    "skinning_transforms",
    "stored_targets",
    "vertex_normals",
]


# ----------------------------------------------------------------------------- geometry

def _face_normal_sums(vertices: np.ndarray, faces: np.ndarray, vertex_count: int) -> np.ndarray:
    """Σ over incident faces of the face cross product (2 x area x unit normal): [..., V, 3]."""
    tri = vertices[..., faces, :]  # [..., F, 3, 3]
    fn = np.cross(tri[..., 1, :] - tri[..., 0, :], tri[..., 2, :] - tri[..., 0, :])  # [..., F, 3]
    F = faces.shape[0]
    incidence = sp.csr_matrix((np.ones(3 * F), (faces.T.ravel(), np.tile(np.arange(F), 3))),
                              shape=(vertex_count, F))
    lead = fn.shape[:-2]
    cols = np.moveaxis(fn.reshape((-1, F, 3)), 1, 0).reshape(F, -1)  # [F, B*3]
    out = (incidence @ cols).reshape(vertex_count, -1, 3)
    return np.moveaxis(out, 0, 1).reshape(lead + (vertex_count, 3))


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.maximum(n, 1e-30)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals [..., V, 3] of a triangle mesh.

    The normal of vertex i is the normalised sum of ``(x_b - x_a) x (x_c - x_a)`` over the faces
    around it (each face's normal weighted by its area; PyTorch3D's ``verts_normals``); it points
    to the side the faces' winding makes outward. A vertex without faces gets zeros.

    Args:
        vertices: positions [..., V, 3] (m); leading dimensions are batches (frames).
        faces: triangles [F, 3] (int).
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    return _unit(_face_normal_sums(vertices, faces, vertices.shape[-2]))


# ----------------------------------------------------------------------------- correspondence

def _betas_row(model: BodyModel, betas) -> np.ndarray:
    b = np.asarray(betas, dtype=np.float64).reshape(-1)
    if b.size > model.shape_dim or b.size == 0:
        raise InputError(f"betas must have 1..{model.shape_dim} values, got {b.size}")
    return b


def _rest_body(model: BodyModel, betas) -> np.ndarray:
    return np.asarray(model.shaped(_betas_row(model, betas)[None]))[0]


def garment_indicator(garment_rest: np.ndarray, subdivided_model: BodyModel, betas) -> np.ndarray:
    """The indicator I of paper 000 §4.1 as indices: each garment vertex's closest vertex of the
    subdivided body in its rest pose (θ = 0, shaped by β), int32 [V].

    ``I`` in the paper is the one-hot matrix [N_g, N_b] with ``I[i, indicator[i]] = 1``.

    Args:
        garment_rest: garment rest vertices [V, 3] (m), placed on the body in its rest pose.
        subdivided_model: the subdivided body (``BodyModel.subdivided()``), built once by the caller.
        betas: body shape β [S] (or [1, S]).
    """
    g = np.asarray(garment_rest, dtype=np.float64)
    if g.ndim != 2 or g.shape[1] != 3:
        raise InputError(f"garment rest vertices must be [V, 3], got {g.shape}")
    _, idx = cKDTree(_rest_body(subdivided_model, betas)).query(g)
    return idx.astype(np.int32)


def garment_skin_weights(indicator: np.ndarray, subdivided_model: BodyModel) -> np.ndarray:
    """Skinning weights of the garment vertices [V, J] (float32): each from its indicator body vertex."""
    return np.asarray(subdivided_model.weights)[np.asarray(indicator)].astype(np.float32)


def garment_body_distances(garment_rest: np.ndarray, body_rest: np.ndarray, indicator: np.ndarray) -> np.ndarray:
    """``d = ||M̄_g - I M̄_b||`` of paper 000 §4.1: rest-pose distance of every garment vertex to its
    indicator body vertex, [V] (m, float64).

    Args:
        garment_rest: garment rest vertices [V, 3] (m).
        body_rest: rest-pose (shaped) subdivided body vertices [N_b, 3] (m).
        indicator: [V] indices into ``body_rest``.
    """
    return np.linalg.norm(np.asarray(garment_rest, dtype=np.float64) - np.asarray(body_rest)[indicator], axis=-1)


def garment_correspondence(garment_rest: np.ndarray, subdivided_model: BodyModel, betas) -> dict[str, np.ndarray]:
    """What depends on the garment instance only (not on frames).

    Returns:
        ``indicator`` int32 [V] (index into the subdivided body's vertices),
        ``skin_weights`` float32 [V, 24] (from the indicator body vertex; rows sum to 1),
        ``body_distance`` float32 [V] (m, the §4.1 distance vector d the fit attribute is made of).
    """
    indicator = garment_indicator(garment_rest, subdivided_model, betas)
    body_rest = _rest_body(subdivided_model, betas)
    return {
        "indicator": indicator,
        "skin_weights": garment_skin_weights(indicator, subdivided_model),
        "body_distance": garment_body_distances(garment_rest, body_rest, indicator).astype(np.float32),
    }


# ----------------------------------------------------------------------------- posing

def _check_motion(model: BodyModel, poses, trans) -> tuple[np.ndarray, np.ndarray]:
    J = model.joint_count
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim == 2 and poses.shape[1] == 3 * J:
        poses = poses.reshape(-1, J, 3)
    if poses.ndim != 3 or poses.shape[1:] != (J, 3):
        raise InputError(f"poses must be [T, {J}, 3] axis-angle (radians), got {poses.shape}")
    T = poses.shape[0]
    trans = np.zeros((T, 3)) if trans is None else np.asarray(trans, dtype=np.float64)
    if trans.shape != (T, 3):
        raise InputError(f"trans must be [T={T}, 3] (m), got {trans.shape}")
    if not (np.isfinite(poses).all() and np.isfinite(trans).all()):
        raise InputError("poses and trans must be finite")
    return poses, trans


def skinning_transforms(model: BodyModel, betas, poses) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward kinematics of the body for a pose sequence (no root translation).

    Returns:
        rest joints J(β) [J, 3] (m), posed joints [T, J, 3] (m, without ``trans``) and the
        skinning transforms ``G_s(θ) G_s(θ*)^-1`` [T, J, 4, 4] (rigid, rest pose θ* = 0).
    """
    poses, _ = _check_motion(model, poses, None)
    shaped = _rest_body(model, betas)
    rest_joints = np.asarray(model.J_regressor @ shaped)  # dense or scipy-sparse regressor
    T = poses.shape[0]
    rot = axis_angle_to_matrix_np(poses)
    posed_joints, rel = rigid_transforms_np(rot, np.repeat(rest_joints[None], T, axis=0), model.parents)
    return rest_joints, posed_joints, rel


def _blend(weights: np.ndarray, transforms: np.ndarray) -> np.ndarray:
    """Per-vertex blended [3, 4] transforms [T, V, 3, 4] = Σ_s w_vs transforms[:, s, :3]."""
    T, J = transforms.shape[:2]
    stacked = transforms[:, :, :3, :].transpose(1, 0, 2, 3).reshape(J, T * 12)  # one GEMM for all frames
    blended = np.asarray(weights, dtype=np.float64) @ stacked  # [V, T * 12]
    return blended.reshape(-1, T, 3, 4).transpose(1, 0, 2, 3)


def _apply(blended: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``blended [T, V, 3, 4] @ (points [T|1, V, 3], 1)`` -> [T, V, 3]."""
    return (blended[..., 0] * points[..., 0:1] + blended[..., 1] * points[..., 1:2]
            + blended[..., 2] * points[..., 2:3] + blended[..., 3])


def relative_skinning(rest_points: np.ndarray, weights: np.ndarray, transforms: np.ndarray) -> np.ndarray:
    """Relative skinning features ``p_i = Σ_s w_{s,i} G_s(θ) G_s(θ*)^-1 p̄_i`` (paper 000 §4.3, [LSK21]).

    Args:
        rest_points: rest positions p̄ [V, 3] (m).
        weights: skinning weights [V, J].
        transforms: ``G_s(θ) G_s(θ*)^-1`` [T, J, 4, 4] from :func:`skinning_transforms`.

    Returns:
        [T, V, 3] (m, float64); independent of the body's translation; p̄ in the rest pose.
    """
    return _apply(_blend(weights, transforms), np.asarray(rest_points, dtype=np.float64)[None])


def pose_body_rows(model: BodyModel, betas, poses, trans, rows: np.ndarray,
                   transforms: np.ndarray | None = None) -> np.ndarray:
    """Posed positions [T, R, 3] (m) of the body vertices ``rows`` only: SMPL's LBS with shape and
    pose blend shapes and ``trans``, evaluated on those rows (exactly ``model.pose(...)[0][:, rows]``,
    since blend shapes and skinning act on each vertex by itself; the joints come from all
    vertices through J(β)).

    Args:
        model: the body (e.g. subdivided).
        betas: β [S].
        poses: θ [T, J, 3] axis-angle (radians).
        trans: root translation [T, 3] (m).
        rows: vertex indices [R].
        transforms: skinning transforms from :func:`skinning_transforms` (computed if None).
    """
    poses, trans = _check_motion(model, poses, trans)
    b = _betas_row(model, betas)
    rows = np.asarray(rows, dtype=np.int64)
    if transforms is None:
        _, _, transforms = skinning_transforms(model, b, poses)
    S = b.size
    v = model.v_template[rows] + np.einsum("rcs,s->rc", model.shapedirs[rows, :, :S], b)
    v = np.broadcast_to(v[None], (poses.shape[0],) + v.shape)
    if model.posedirs is not None:
        P = model.posedirs.shape[0]
        pd = np.asarray(model.posedirs).reshape(P, model.vertex_count, 3)[:, rows].reshape(P, -1)
        rot = axis_angle_to_matrix_np(poses)
        feature = (rot[:, 1:] - np.eye(3)).reshape(poses.shape[0], -1)
        v = v + (feature @ pd).reshape(v.shape)
    return _apply(_blend(model.weights[rows], transforms), v) + trans[:, None]


def joint_distances(points: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """Euclidean distances [T, V, J] (m) from every point [T, V, 3] to every joint [T, J, 3]."""
    points = np.asarray(points, dtype=np.float64)
    joints = np.asarray(joints, dtype=np.float64)
    out = np.empty(points.shape[:2] + (joints.shape[1],))
    for s in range(joints.shape[1]):
        out[..., s] = np.linalg.norm(points - joints[:, None, s], axis=-1)
    return out


# ----------------------------------------------------------------------------- one sample

TARGET_NAMES = ("coarse", "anchor", "anchor_normal", "anchor_skin", "coarse_normal", "skin", "joint_distance",
                "joints")
"""The arrays :func:`sample_targets` returns, in order."""


def sample_targets(garment_rest: np.ndarray, faces: np.ndarray, subdivided_model: BodyModel, betas,
                   poses: np.ndarray, trans: np.ndarray, detail: np.ndarray, *, indicator: np.ndarray | None = None,
                   smoothing: SmoothingConfig = SmoothingConfig(), operator: sp.spmatrix | None = None,
                   ) -> dict[str, np.ndarray]:
    """Paper 000's per-frame targets and node features of one sample (float32 arrays).

    Args:
        garment_rest: garment rest vertices [V, 3] (m) on the body in its rest pose.
        faces: garment triangles [F, 3].
        subdivided_model: the subdivided body (``BodyModel.subdivided()``, built once by the caller;
            its joint regressor gives the base model's joints exactly).
        betas: body shape β [S].
        poses: θ [T, 24, 3] axis-angle (radians).
        trans: root translation [T, 3] (m).
        detail: simulated garment vertices [T, V, 3] (m), world frame (translation included).
        indicator: [V] from :func:`garment_indicator` (computed if None).
        smoothing: the coarse smoothing (paper: λ = 0.12, 40 iterations).
        operator: a prebuilt :func:`~datagen.targets.coarse.laplacian_operator` for ``faces``.

    Returns:
        ``coarse`` [T, V, 3] m: Laplacian-smoothed ``detail`` (M_coarse, eq. 5/9);
        ``anchor`` [T, V, 3] m: ``I M_b``, the posed subdivided body at the indicator, so that
        ``Δ_coarse = coarse - anchor`` and ``Δ_detail = detail - coarse``;
        ``anchor_normal`` [T, V, 3] unit: the posed subdivided body's vertex normals there (n^{b'});
        ``anchor_skin`` [T, V, 3] m: relative skinning features of those body vertices (p^{b'});
        ``coarse_normal`` [T, V, 3] unit: vertex normals of the coarse garment (n_i, §4.4);
        ``skin`` [T, V, 3] m: relative skinning features of the garment vertices (p_i, §4.4;
        weights of the indicator body vertex, rest position the garment rest vertex);
        ``joint_distance`` [T, V, 24] m: coarse garment vertex to posed joint distances (x_i, §4.4);
        ``joints`` [T, 24, 3] m: posed joints, translation included.
    """
    garment_rest = np.asarray(garment_rest, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    poses, trans = _check_motion(subdivided_model, poses, trans)
    detail = np.asarray(detail, dtype=np.float64)
    T, V = poses.shape[0], garment_rest.shape[0]
    if detail.shape != (T, V, 3):
        raise InputError(f"detail must be [T={T}, V={V}, 3] to match poses and the garment, got {detail.shape}")
    if not np.isfinite(detail).all():
        raise InputError("detail has non-finite values; reject the sample before computing targets")
    b = _betas_row(subdivided_model, betas)
    if indicator is None:
        indicator = garment_indicator(garment_rest, subdivided_model, b)
    indicator = np.asarray(indicator, dtype=np.int64)
    if indicator.shape != (V,):
        raise InputError(f"indicator must be [V={V}], got {indicator.shape}")

    _, posed_joints, transforms = skinning_transforms(subdivided_model, b, poses)

    # anchor and its normals: pose only the body vertices of the faces around the indicator vertices
    body_faces = np.asarray(subdivided_model.faces, dtype=np.int64)
    used, used_inverse = np.unique(indicator, return_inverse=True)
    touched = np.zeros(subdivided_model.vertex_count, dtype=bool)
    touched[used] = True
    ring_faces = body_faces[touched[body_faces].any(axis=1)]
    rows, local = np.unique(ring_faces, return_inverse=True)
    local = local.reshape(-1, 3)
    posed_rows = pose_body_rows(subdivided_model, b, poses, trans, rows, transforms)  # [T, R, 3]
    at = np.searchsorted(rows, used)[used_inverse]  # row of each garment vertex's body vertex
    anchor = posed_rows[:, at]
    anchor_normal = _unit(_face_normal_sums(posed_rows, local, len(rows))[:, at])

    weights = subdivided_model.weights[indicator]
    blended = _blend(weights, transforms)  # the garment vertices share their indicator vertex's weights
    body_rest = _rest_body(subdivided_model, b)[indicator]
    anchor_skin = _apply(blended, body_rest[None])
    skin = _apply(blended, garment_rest[None])

    coarse = coarse_from_detail(detail, faces, smoothing, operator=operator)
    joints = posed_joints + trans[:, None]
    out = {
        "coarse": coarse,
        "anchor": anchor,
        "anchor_normal": anchor_normal,
        "anchor_skin": anchor_skin,
        "coarse_normal": vertex_normals(coarse, faces),
        "skin": skin,
        "joint_distance": joint_distances(coarse, joints),
        "joints": joints,
    }
    return {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in out.items()}


def stored_targets(faces: np.ndarray, model: BodyModel, betas, poses: np.ndarray, trans: np.ndarray,
                   detail: np.ndarray, *, smoothing: SmoothingConfig = SmoothingConfig(),
                   operator: sp.spmatrix | None = None) -> dict[str, np.ndarray]:
    """What a dataset store keeps of :func:`sample_targets` (float32): ``coarse`` [T, V, 3] and
    ``joints`` [T, 24, 3]. Every other target is a cheap function of these and the static data, and
    is derived on read (:mod:`datagen.geometry.features`)."""
    poses, trans = _check_motion(model, poses, trans)
    detail = np.asarray(detail, dtype=np.float64)
    if detail.ndim != 3 or detail.shape[0] != poses.shape[0] or detail.shape[2] != 3:
        raise InputError(f"detail must be [T={poses.shape[0]}, V, 3], got {detail.shape}")
    if not np.isfinite(detail).all():
        raise InputError("detail has non-finite values; reject the sample before computing targets")
    _, posed_joints, _ = skinning_transforms(model, betas, poses)
    coarse = coarse_from_detail(detail, np.asarray(faces, dtype=np.int64), smoothing, operator=operator)
    return {"coarse": coarse.astype(np.float32), "joints": (posed_joints + trans[:, None]).astype(np.float32)}
