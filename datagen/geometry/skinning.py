"""Forward kinematics and linear blend skinning on arrays (numpy and torch): the skinning
transforms ``G_j(θ) G_j(θ*)^-1`` of a kinematic tree and their per-vertex blend. The body model
(:mod:`datagen.body.lbs`) and the derived features of a stored sample (:mod:`datagen.features`)
both pose with these (in torch through :func:`pose_shaped`, the one torch SMPL posing), so a body
posed for the simulator and one rebuilt from a store agree to rounding."""

from __future__ import annotations

import numpy as np
import torch

__all__ = ["blend_skinning", "pose_shaped", "rigid_transforms", "rigid_transforms_np"]


def rigid_transforms_np(rot: np.ndarray, joints: np.ndarray, parents) -> tuple[np.ndarray, np.ndarray]:
    """Forward kinematics. rot [B, J, 3, 3] local rotations, joints [B, J, 3] rest positions.

    Returns posed joint positions [B, J, 3] and the skinning transforms [B, J, 4, 4] that take a
    rest-pose point to its posed position (G_j with the rest joint position removed).
    """
    batch, J = rot.shape[:2]
    dtype = rot.dtype
    rel_joints = joints.copy()
    rel_joints[:, 1:] -= joints[:, np.asarray(parents[1:])]
    local = np.zeros((batch, J, 4, 4), dtype=dtype)
    local[:, :, :3, :3] = rot
    local[:, :, :3, 3] = rel_joints
    local[:, :, 3, 3] = 1.0
    world = np.empty_like(local)
    world[:, 0] = local[:, 0]
    for j in range(1, J):
        world[:, j] = world[:, parents[j]] @ local[:, j]
    posed_joints = world[:, :, :3, 3].copy()
    rel = world.copy()
    rel[:, :, :3, 3] -= np.einsum("bjik,bjk->bji", world[:, :, :3, :3], joints)
    return posed_joints, rel


def blend_skinning(vertices, weights, transforms):
    """Linear blend skinning of points [B, V, 3] with weights [V, J] and per-joint transforms
    [B, J, 4, 4] (numpy or torch): ``v' = Σ_j w_vj T_j v``.

    The [3, 4] transforms are blended by one matmul, then applied as four scaled column sums: a
    batched 3x3 matmul per vertex is several times slower.
    """
    batch, J = transforms.shape[:2]
    blended = (weights @ transforms[:, :, :3, :].reshape(batch, J, 12)).reshape(batch, -1, 3, 4)
    v = vertices
    return (blended[..., 0] * v[..., 0:1] + blended[..., 1] * v[..., 1:2]
            + blended[..., 2] * v[..., 2:3] + blended[..., 3])


def rigid_transforms(rot: torch.Tensor, joints: torch.Tensor, parents: list[int],
                     parent_index: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """Torch version of :func:`rigid_transforms_np` (no in-place writes, so autograd works).
    ``parent_index``: ``parents[1:]`` as a long tensor on ``joints``' device, where the caller keeps
    one (indexing with the list copies it from the host each call, which a CUDA graph cannot hold)."""
    idx = parents[1:] if parent_index is None else parent_index
    rel_joints = torch.cat([joints[:, :1], joints[:, 1:] - joints[:, idx]], dim=1)
    top = torch.cat([rot, rel_joints.unsqueeze(-1)], dim=-1)  # [B, J, 3, 4]
    bottom = torch.zeros_like(top[..., :1, :])
    bottom[..., 0, 3] = 1.0
    local = torch.cat([top, bottom], dim=-2)
    chain = [local[:, 0]]
    for j in range(1, len(parents)):
        chain.append(chain[parents[j]] @ local[:, j])
    world = torch.stack(chain, dim=1)
    posed_joints = world[:, :, :3, 3]
    offset = torch.einsum("bjik,bjk->bji", world[:, :, :3, :3], joints)
    rel = torch.cat([world[:, :, :3, :3], (world[:, :, :3, 3] - offset).unsqueeze(-1)], dim=-1)
    rel = torch.cat([rel, world[:, :, 3:, :]], dim=-2)
    return posed_joints, rel


def pose_shaped(
    rot: torch.Tensor,
    rest_joints: torch.Tensor,
    parents: list[int],
    *,
    shaped: torch.Tensor | None = None,
    weights: torch.Tensor | None = None,
    posedirs: torch.Tensor | None = None,
    transl: torch.Tensor | None = None,
    parent_index: torch.Tensor | None = None,
) -> tuple[torch.Tensor | None, torch.Tensor, torch.Tensor]:
    """SMPL's posing of a shaped body, in torch: the one torch implementation that
    :func:`datagen.body.lbs.lbs` (so :class:`~datagen.body.model.BodyModelTorch`), the derived
    features of a store (:mod:`datagen.features`) and the trainers' body layers call.

    ``W(shaped + B_p(θ), J(β), θ, 𝒲) + transl``: forward kinematics of the rest joints, the pose
    blend shapes (when ``posedirs`` is given) and linear blend skinning of ``shaped``.

    Args:
        rot: local joint rotations R(θ) [B, J, 3, 3], root first.
        rest_joints: rest joint positions J(β) [B, J, 3] (m).
        parents: parent of each joint [J] (-1 for the root).
        shaped: shaped rest vertices ``T + B_s(β)`` [B, V, 3] (m), or None to pose the joints only.
            A subset of the body's vertices may be given (with their ``weights``) when ``posedirs``
            is None.
        weights: skinning weights [V, J] of ``shaped``'s vertices.
        posedirs: pose directions [9 (J-1), V*3], or None for no pose blend shapes.
        transl: root translation [B, 3] (m), added to vertices and joints; None adds nothing.
        parent_index: ``parents[1:]`` as a long tensor on the device (see
            :func:`~datagen.geometry.skinning.rigid_transforms`).

    Returns:
        (vertices [B, V, 3] or None, posed joints [B, J, 3], skinning transforms
        ``G_j(θ) G_j(θ*)^-1`` [B, J, 4, 4] (without ``transl``)), in metres.
    """
    posed_joints, rel = rigid_transforms(rot, rest_joints, parents, parent_index)
    verts = None
    if shaped is not None:
        if posedirs is not None:
            eye = torch.eye(3, dtype=rot.dtype, device=rot.device)
            feature = (rot[:, 1:] - eye).reshape(rot.shape[0], -1)
            shaped = shaped + (feature @ posedirs).reshape(rot.shape[0], -1, 3)
        verts = blend_skinning(shaped, weights, rel)
    if transl is not None:
        transl = transl.reshape(-1, 1, 3)
        if verts is not None:
            verts = verts + transl
        posed_joints = posed_joints + transl
    return verts, posed_joints, rel
