"""What a dataset store keeps of paper 000's per-frame targets: the coarse garment (Laplacian-smoothed
simulation, §5.1) and the posed joints. Every other target and node feature is a function of these
and the static arrays, derived on read by :mod:`datagen.features`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from datagen.body.lbs import rigid_transforms_np
from datagen.body.model import BodyModel
from datagen.errors import InputError
from datagen.geometry.rotations import axis_angle_to_matrix_np
from datagen.targets.coarse import SmoothingConfig, coarse_from_detail
from datagen.targets.correspondence import rest_body

__all__ = ["motion_arrays", "skinning_transforms", "stored_targets"]


def motion_arrays(model: BodyModel, poses, trans) -> tuple[np.ndarray, np.ndarray]:
    """Checked float64 poses θ [T, J, 3] (axis-angle, rad; [T, J*3] accepted) and translations
    [T, 3] (m; zeros when ``trans`` is None), or an InputError."""
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
    poses, _ = motion_arrays(model, poses, None)
    shaped = rest_body(model, betas)
    rest_joints = np.asarray(model.J_regressor @ shaped)  # dense or scipy-sparse regressor
    T = poses.shape[0]
    rot = axis_angle_to_matrix_np(poses)
    posed_joints, rel = rigid_transforms_np(rot, np.repeat(rest_joints[None], T, axis=0), model.parents)
    return rest_joints, posed_joints, rel


def stored_targets(faces: np.ndarray, model: BodyModel, betas, poses: np.ndarray, trans: np.ndarray,
                   detail: np.ndarray, *, smoothing: SmoothingConfig = SmoothingConfig(),
                   operator: sp.spmatrix | None = None) -> dict[str, np.ndarray]:
    """What a dataset store keeps of paper 000's per-frame targets (float32): ``coarse`` [T, V, 3] (m,
    Laplacian-smoothed ``detail`` [T, V, 3], M_coarse of eq. 5/9) and ``joints`` [T, 24, 3] (m, posed,
    translation included). Every other target is a cheap function of these and the static data, and
    is derived on read (:mod:`datagen.features`)."""
    poses, trans = motion_arrays(model, poses, trans)
    detail = np.asarray(detail, dtype=np.float64)
    if detail.ndim != 3 or detail.shape[0] != poses.shape[0] or detail.shape[2] != 3:
        raise InputError(f"detail must be [T={poses.shape[0]}, V, 3], got {detail.shape}")
    if not np.isfinite(detail).all():
        raise InputError("detail has non-finite values; reject the sample before computing targets")
    _, posed_joints, _ = skinning_transforms(model, betas, poses)
    coarse = coarse_from_detail(detail, np.asarray(faces, dtype=np.int64), smoothing, operator=operator)
    return {"coarse": coarse.astype(np.float32), "joints": (posed_joints + trans[:, None]).astype(np.float32)}
