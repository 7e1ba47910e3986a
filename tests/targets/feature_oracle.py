"""The numpy oracle of paper 000's per-frame targets and node features (§4.1-4.4), for the tests.

:func:`sample_targets` computes, for one sample, every array the schema-3 store kept, the
straightforward way (numpy, float64, the whole subdivided ``BodyModel``): the torch
implementation that drape uses (:func:`datagen.features.derive`, from what a store keeps) is
checked equal to it (``tests/targets/test_targets.py``). Nothing in drape imports this module.

- the anchor ``I M_b`` (eq. 5) with its vertex normals n^{b'} (§4.3), posing only the body rows
  that are needed (:func:`pose_body_rows`; LBS is per vertex, so this is exact);
- relative skinning features ``p = Σ_s w_s G_s(θ) G_s(θ*)^-1 p̄`` (§4.3, [LSK21]) of the anchor
  body vertices and of the garment vertices (:func:`relative_skinning`);
- the coarse target, its vertex normals and the distances from every coarse garment vertex to
  every posed joint (§4.4, :func:`joint_distances`).

G_s is SMPL's world transform of joint s (a 4x4 rigid transform: the rotations composed along
the kinematic chain and the joint positions J(β)), as in SMPL's ``G'_k = G_k(θ, J) G_k(θ*, J)^-1``
which the paper's formula copies; it does not include the root translation ``trans``. So
``G_s(θ) G_s(θ*)^-1`` is exactly the skinning transform of :func:`datagen.body.lbs.rigid_transforms_np`,
and the feature is the linearly skinned rest position without the translation: unchanged when the
body is moved, equal to p̄ in the rest pose. p̄ is the shaped rest position ``T + B_s(β)`` (no pose
blend shapes), so for a body without pose blend shapes (drape's default) ``anchor_skin = anchor -
trans`` exactly.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from datagen.body.model import BodyModel
from datagen.errors import InputError
from datagen.geometry.rotations import axis_angle_to_matrix_np
from datagen.geometry.topology import vertex_normals_np
from datagen.targets.coarse import SmoothingConfig, coarse_from_detail
from datagen.targets.correspondence import betas_row, garment_indicator, rest_body
from datagen.targets.stored import motion_arrays, skinning_transforms

__all__ = ["TARGET_NAMES", "joint_distances", "pose_body_rows", "relative_skinning", "sample_targets"]


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
    poses, trans = motion_arrays(model, poses, trans)
    b = betas_row(model, betas)
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
    poses, trans = motion_arrays(subdivided_model, poses, trans)
    detail = np.asarray(detail, dtype=np.float64)
    T, V = poses.shape[0], garment_rest.shape[0]
    if detail.shape != (T, V, 3):
        raise InputError(f"detail must be [T={T}, V={V}, 3] to match poses and the garment, got {detail.shape}")
    if not np.isfinite(detail).all():
        raise InputError("detail has non-finite values; reject the sample before computing targets")
    b = betas_row(subdivided_model, betas)
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
    anchor_normal = vertex_normals_np(posed_rows, local)[:, at]

    weights = subdivided_model.weights[indicator]
    blended = _blend(weights, transforms)  # the garment vertices share their indicator vertex's weights
    body_rest = rest_body(subdivided_model, b)[indicator]
    anchor_skin = _apply(blended, body_rest[None])
    skin = _apply(blended, garment_rest[None])

    coarse = coarse_from_detail(detail, faces, smoothing, operator=operator)
    joints = posed_joints + trans[:, None]
    out = {
        "coarse": coarse,
        "anchor": anchor,
        "anchor_normal": anchor_normal,
        "anchor_skin": anchor_skin,
        "coarse_normal": vertex_normals_np(coarse, faces),
        "skin": skin,
        "joint_distance": joint_distances(coarse, joints),
        "joints": joints,
    }
    return {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in out.items()}
