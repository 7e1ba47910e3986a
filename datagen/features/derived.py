"""Paper 000's per-frame node features of a stored sample, derived from what the store keeps.

A dataset store keeps what was simulated and what cannot be recomputed cheaply (garment positions,
the coarse target, pose, translation, joints, labels, metrics) and the static data that the rest is
a function of: the body model with its subdivision recipe, each body's β, each garment instance's
rest mesh and indicator. :func:`derive` is the one home of that function. The store's reader, the
exporters and the trainers call it; nothing else recomputes these arrays.

=================  =============  ================================================================
name               shape          definition (paper 000)
=================  =============  ================================================================
``joints``         [T, J, 3] m    posed joints, translation included (SMPL's forward kinematics)
``anchor``         [T, V, 3] m    ``I M_b`` (eq. 5): the posed subdivided body vertex each garment
                                  vertex is attached to (indicator I, §4.1)
``anchor_normal``  [T, V, 3]      unit vertex normal of the posed subdivided body there (n^{b'}, §4.3)
``anchor_skin``    [T, V, 3] m    relative skinning feature of that body vertex (p^{b'}, §4.3):
                                  ``Σ_s w_s G_s(θ) G_s(θ*)^-1 p̄`` = ``anchor - trans`` (no pose
                                  blend shapes)
``skin``           [T, V, 3] m    relative skinning feature of the garment vertex (p_i, §4.4): the
                                  same blend of transforms applied to the garment's rest vertex
``coarse_normal``  [T, V, 3]      unit vertex normal of the coarse garment (n_i, §4.4)
``joint_distance`` [T, V, J] m    coarse garment vertex to posed joint distances (x_i, §4.4)
``body_vertices``  [T, B, 3] m    the posed body (SMPL LBS, no pose blend shapes)
=================  =============  ================================================================

Which stored arrays each name is computed from is :data:`schemas.dataset.DERIVED` (the store's
layout says what its reader derives). One implementation in torch serves both worlds:
:func:`derive` takes numpy arrays (computed in float64 on the CPU, returned as float32 numpy) or
torch tensors (computed in the tensors' dtype on their device, returned as tensors), batched over
the frames of one sample. The body is posed by :func:`datagen.geometry.skinning.pose_shaped`, the normals
are :func:`datagen.geometry.topology.vertex_normals`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

from datagen.errors import InputError
from datagen.features.binding import GarmentBinding
from datagen.geometry.rotations import axis_angle_to_matrix
from datagen.geometry.skinning import blend_skinning, pose_shaped
from datagen.geometry.topology import vertex_normals
from schemas.dataset import DERIVED

__all__ = ["DERIVED", "derive", "joint_distances"]


def joint_distances(points: torch.Tensor, joints: torch.Tensor) -> torch.Tensor:
    """Distances [..., V, J] (m) from points [..., V, 3] to joints [..., J, 3] (x_i of paper 000 §4.4)."""
    return torch.linalg.vector_norm(points[..., :, None, :] - joints[..., None, :, :], dim=-1)


def _apply(blended: torch.Tensor, points: torch.Tensor) -> torch.Tensor:
    """``blended [T, V, 3, 4] @ (points [V, 3], 1)`` -> [T, V, 3]."""
    return (blended[..., 0] * points[..., 0:1] + blended[..., 1] * points[..., 1:2]
            + blended[..., 2] * points[..., 2:3] + blended[..., 3])


def derive(binding: GarmentBinding, names: Sequence[str], *, pose=None, trans=None, coarse=None, joints=None
           ) -> dict:
    """The derived arrays ``names`` (see :data:`DERIVED` and the module docstring) of one sample's frames.

    Args:
        binding: the garment instance on its body (:func:`~datagen.features.binding.bind_garment`).
        names: which arrays to compute.
        pose: θ [T, J, 3] axis-angle (rad); needed by every name except ``coarse_normal``.
        trans: root translation [T, 3] (m).
        coarse: coarse garment positions [T, V, 3] (m).
        joints: posed joints [T, J, 3] (m), as stored; computed from pose and trans when None.

    Returns:
        name -> array: numpy float32 when the inputs are numpy (computed in float64), tensors of
        the inputs' float dtype on their device otherwise.
    """
    unknown = [n for n in names if n not in DERIVED]
    if unknown:
        raise InputError(f"unknown derived array(s) {unknown}; derived arrays are {list(DERIVED)}")
    given = {"pose": pose, "trans": trans, "coarse": coarse}
    need = {k for n in names for k in DERIVED[n] if k != "joints"} | (
        {"pose", "trans"} if "joint_distance" in names and joints is None else set())
    missing = sorted(k for k in need if given[k] is None)
    if missing:
        raise InputError(f"deriving {list(names)} needs {missing}")
    tensors = [x for x in (pose, trans, coarse, joints) if isinstance(x, torch.Tensor)]
    numpy_out = not tensors
    if numpy_out:
        device, dtype = torch.device("cpu"), torch.float64
    else:
        device = tensors[0].device
        dtype = next((t.dtype for t in tensors if t.is_floating_point()), torch.float32)
    as_t = lambda x: None if x is None else torch.as_tensor(x, dtype=dtype, device=device)  # noqa: E731
    pose, trans, coarse, joints = as_t(pose), as_t(trans), as_t(coarse), as_t(joints)
    g = binding.tensors(device, dtype)
    out: dict[str, torch.Tensor] = {}
    if pose is not None and need & {"pose"}:
        T = pose.shape[0]
        J = len(binding.body.parents)
        if pose.shape != (T, J, 3):
            raise InputError(f"pose must be [T, {J}, 3] axis-angle, got {tuple(pose.shape)}")
        if trans is not None and trans.shape != (T, 3):
            raise InputError(f"trans must be [T={T}, 3], got {tuple(trans.shape)}")
        body = binding.body.tensors(device, dtype)
        shaped = body["shaped"].expand(T, -1, -1) if "body_vertices" in names else None
        body_vertices, posed_joints, rel = pose_shaped(
            axis_angle_to_matrix(pose), body["rest_joints"].expand(T, -1, -1), list(binding.body.parents),
            shaped=shaped, weights=body["weights"], transl=trans)  # joints with trans when it is given
        if joints is None and trans is not None:
            joints = posed_joints
        if "joints" in names:
            out["joints"] = posed_joints
        if {"anchor", "anchor_skin", "skin"} & set(names):
            blended = (g["weights"] @ rel[:, :, :3, :].reshape(T, J, 12)).reshape(T, -1, 3, 4)
            if {"anchor", "anchor_skin"} & set(names):
                anchor_skin = _apply(blended, g["anchor_rest"])
                if "anchor_skin" in names:
                    out["anchor_skin"] = anchor_skin
                if "anchor" in names:
                    out["anchor"] = anchor_skin + trans[:, None]
            if "skin" in names:
                out["skin"] = _apply(blended, g["rest"])
        if "anchor_normal" in names:
            ring = blend_skinning(g["ring_rest"].expand(T, -1, -1), g["ring_weights"], rel)
            out["anchor_normal"] = vertex_normals(ring, g["ring_faces"])[:, g["ring_at"]]
        if "body_vertices" in names:
            out["body_vertices"] = body_vertices
    if coarse is not None:
        V = binding.vertex_count
        if coarse.ndim != 3 or coarse.shape[1:] != (V, 3):
            raise InputError(f"coarse must be [T, V={V}, 3], got {tuple(coarse.shape)}")
        if "coarse_normal" in names:
            out["coarse_normal"] = vertex_normals(coarse, g["faces"])
        if "joint_distance" in names:
            out["joint_distance"] = joint_distances(coarse, joints)
    out = {n: out[n] for n in names}
    if numpy_out:
        return {n: v.numpy().astype(np.float32) for n, v in out.items()}
    return out
