"""Linear blend skinning with shape and pose blend shapes: paper 000 eq. (1)-(2), SMPL's model.

    M_b = W(T + B_s(β) + B_p(θ), J(β), θ, 𝒲)

Pure functions on arrays, one in numpy (float32/float64) and one in torch (differentiable,
any device). Both follow SMPL's definitions exactly as the ``smplx`` package implements them, so
a model file poses to the same vertices here and there:

- ``B_s(β) = shapedirs · β``                         shapedirs [V, 3, S]
- ``J(β) = J_regressor · (T + B_s(β))``              J_regressor [J, V]
- ``B_p(θ) = posedirs · vec(R(θ)_1.. - I)``          posedirs [P, V*3] with P = 9 (J - 1)
- global joint transforms G_j along the kinematic tree, and
  ``v' = Σ_j w_vj G_j (G_j^rest)^-1 v``               weights [V, J]

Shapes: B is the batch; poses are axis-angle [B, J, 3] or flat [B, J*3] (radians), root first.
Lengths are metres. When ``posedirs`` is ``None`` the pose blend shapes are skipped (drape's
Anny-derived body has none), which is exact, not an approximation.
"""

from __future__ import annotations

import numpy as np
import torch

from datagen.geometry.rotations import axis_angle_to_matrix, axis_angle_to_matrix_np
from datagen.geometry.skinning import blend_skinning, pose_shaped, rigid_transforms, rigid_transforms_np

__all__ = ["blend_skinning", "lbs", "lbs_np", "pose_shaped", "rigid_transforms", "rigid_transforms_np"]


# ----------------------------------------------------------------------------- numpy

def lbs_np(
    betas: np.ndarray,
    pose: np.ndarray,
    v_template: np.ndarray,
    shapedirs: np.ndarray,
    posedirs: np.ndarray | None,
    J_regressor: np.ndarray,
    parents: np.ndarray,
    weights: np.ndarray,
    transl: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Pose a batch of bodies. Returns vertices [B, V, 3] and joints [B, J, 3] in metres.

    Args:
        betas: shape coefficients [B, S] (B may be 1 and broadcast against the pose batch).
        pose: axis-angle rotations [B, J, 3] or [B, J*3], radians, root orientation first.
        v_template: rest-pose template T [V, 3].
        shapedirs: shape directions [V, 3, S'] with S' >= S (the first S are used).
        posedirs: pose directions [9 (J-1), V*3], or None for no pose blend shapes.
        J_regressor: joint regressor [J, V] (dense array or scipy sparse matrix).
        parents: parent index per joint [J], -1 for the root.
        weights: skinning weights [V, J], rows sum to 1.
        transl: optional root translation [B, 3] added to every vertex and joint.
    """
    dtype = v_template.dtype
    betas = np.asarray(betas, dtype=dtype)
    J = len(parents)
    pose = np.asarray(pose, dtype=dtype).reshape(-1, J, 3)
    batch = max(betas.shape[0], pose.shape[0])
    S = betas.shape[1]
    v_shaped = v_template[None] + np.einsum("vcs,bs->bvc", shapedirs[:, :, :S], betas, optimize=True)
    if v_shaped.shape[0] != batch:
        v_shaped = np.broadcast_to(v_shaped, (batch,) + v_shaped.shape[1:])
    joints = _regress_np(J_regressor, v_shaped)  # [B, J, 3]
    rot = axis_angle_to_matrix_np(pose)  # [Bp, J, 3, 3]
    if rot.shape[0] != batch:
        rot = np.broadcast_to(rot, (batch,) + rot.shape[1:])
    if posedirs is not None:
        feature = (rot[:, 1:] - np.eye(3, dtype=dtype)).reshape(batch, -1)
        v_posed = v_shaped + (feature @ posedirs).reshape(batch, -1, 3)
    else:
        v_posed = v_shaped
    posed_joints, rel = rigid_transforms_np(rot, joints, parents)
    verts = blend_skinning(v_posed, weights, rel)
    if transl is not None:
        transl = np.asarray(transl, dtype=dtype).reshape(-1, 1, 3)
        verts = verts + transl
        posed_joints = posed_joints + transl
    return verts, posed_joints






def _regress_np(J_regressor, vertices: np.ndarray) -> np.ndarray:
    if hasattr(J_regressor, "tocsr"):  # scipy sparse, as real SMPL files store it
        R = J_regressor.tocsr()
        return np.stack([np.asarray(R @ v) for v in vertices]).astype(vertices.dtype)
    return np.einsum("jv,bvc->bjc", J_regressor, vertices, optimize=True)


# ----------------------------------------------------------------------------- torch

def lbs(
    betas: torch.Tensor,
    pose: torch.Tensor,
    v_template: torch.Tensor,
    shapedirs: torch.Tensor,
    posedirs: torch.Tensor | None,
    J_regressor: torch.Tensor,
    parents: torch.Tensor | list[int],
    weights: torch.Tensor,
    transl: torch.Tensor | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Torch version of :func:`lbs_np` with the same arguments; differentiable in β, θ and transl."""
    parents = [int(p) for p in parents]
    J = len(parents)
    pose = pose.reshape(pose.shape[0], J, 3)
    batch = max(betas.shape[0], pose.shape[0])
    S = betas.shape[1]
    v_shaped = v_template.unsqueeze(0) + torch.einsum("vcs,bs->bvc", shapedirs[:, :, :S], betas)
    v_shaped = v_shaped.expand(batch, -1, -1)
    joints = torch.einsum("jv,bvc->bjc", J_regressor, v_shaped)
    rot = axis_angle_to_matrix(pose).expand(batch, -1, -1, -1)
    verts, posed_joints, _ = pose_shaped(rot, joints, parents, shaped=v_shaped, weights=weights, posedirs=posedirs,
                                         transl=transl)
    return verts, posed_joints
