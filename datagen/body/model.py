"""The SMPL-format body model: arrays plus the functions that pose them.

A :class:`BodyModel` holds what an SMPL file holds (``v_template, shapedirs, posedirs,
J_regressor, weights, kintree_table, f``) in SMPL's conventions: metres, Y up, the body facing
+Z, SMPL's 24 joints in SMPL's order. It poses in numpy (:meth:`BodyModel.pose`) or in torch
(:class:`BodyModelTorch`, differentiable). Inputs are checked; mistakes raise
:class:`~datagen.errors.InputError` with a message saying what to pass instead.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch

from datagen.body import lbs as _lbs
from datagen.body.skeleton import JOINT_COUNT, SMPL_JOINT_NAMES
from datagen.errors import InputError


@dataclass(frozen=True, eq=False)
class BodyModel:
    """An SMPL-format body model. Arrays are float64 in memory; files keep what they hold.

    Attributes:
        v_template: rest-pose template T [m], shape [V, 3].
        shapedirs: shape blend-shape directions [m per unit β], shape [V, 3, S].
        posedirs: pose blend-shape directions [m], shape [9 (J - 1), V * 3], or None when the
            model has no pose correctives (posing then skips B_p exactly).
        J_regressor: joint regressor, shape [J, V], rows sum to 1.
        weights: skinning weights, shape [V, J], rows sum to 1.
        parents: parent joint index, shape [J], -1 for the root.
        faces: triangle vertex indices, shape [F, 3], int64.
        meta: provenance (source, licence, rest pose, build key, shape statistics, presets).
    """

    v_template: np.ndarray
    shapedirs: np.ndarray
    posedirs: np.ndarray | None
    J_regressor: np.ndarray
    weights: np.ndarray
    parents: np.ndarray
    faces: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        V = self.v_template.shape[0]
        J = len(self.parents)
        checks = [
            (self.v_template.ndim == 2 and self.v_template.shape[1] == 3, f"v_template must be [V, 3], got {self.v_template.shape}"),
            (self.shapedirs.ndim == 3 and self.shapedirs.shape[:2] == (V, 3), f"shapedirs must be [V={V}, 3, S], got {self.shapedirs.shape}"),
            (self.J_regressor.shape == (J, V), f"J_regressor must be [J={J}, V={V}], got {self.J_regressor.shape}"),
            (self.weights.shape == (V, J), f"weights must be [V={V}, J={J}], got {self.weights.shape}"),
            (self.faces.ndim == 2 and self.faces.shape[1] == 3, f"faces must be [F, 3], got {self.faces.shape}"),
            (self.faces.size == 0 or (self.faces.min() >= 0 and self.faces.max() < V), f"faces index vertices outside 0..{V - 1}"),
            (self.posedirs is None or self.posedirs.shape == (9 * (J - 1), V * 3), f"posedirs must be [{9 * (J - 1)}, {V * 3}], got {None if self.posedirs is None else self.posedirs.shape}"),
        ]
        for ok, message in checks:
            if not ok:
                raise InputError(f"invalid body model: {message}")

    # ------------------------------------------------------------------ sizes
    @property
    def vertex_count(self) -> int:
        return int(self.v_template.shape[0])

    @property
    def face_count(self) -> int:
        return int(self.faces.shape[0])

    @property
    def joint_count(self) -> int:
        return int(len(self.parents))

    @property
    def shape_dim(self) -> int:
        return int(self.shapedirs.shape[2])

    @property
    def joint_names(self) -> tuple[str, ...]:
        return SMPL_JOINT_NAMES if self.joint_count == JOINT_COUNT else tuple(f"joint{j}" for j in range(self.joint_count))

    @property
    def has_pose_blendshapes(self) -> bool:
        return self.posedirs is not None

    def replace(self, **changes) -> "BodyModel":
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ posing
    def check_inputs(self, betas=None, pose=None, transl=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Validate and normalise β [B, S'] (S' <= S), θ [B, J, 3] or [B, J*3], transl [B, 3].

        ``None`` means zeros (mean shape, rest pose). A single unbatched vector is accepted.
        """
        J = self.joint_count
        betas = np.zeros((1, self.shape_dim)) if betas is None else np.asarray(betas, dtype=np.float64)
        if betas.ndim == 1:
            betas = betas[None]
        if betas.ndim != 2 or betas.shape[1] > self.shape_dim or betas.shape[1] == 0:
            raise InputError(
                f"betas must have shape [batch, S] with 1 <= S <= {self.shape_dim}, got {betas.shape}; "
                f"pass e.g. np.zeros((1, {self.shape_dim}))"
            )
        pose = np.zeros((1, J, 3)) if pose is None else np.asarray(pose, dtype=np.float64)
        if pose.ndim == 1:
            pose = pose[None]
        if pose.ndim == 2 and pose.shape[1] == 3 * J:
            pose = pose.reshape(-1, J, 3)
        if pose.ndim != 3 or pose.shape[1:] != (J, 3):
            raise InputError(
                f"pose θ must have shape [batch, {J}, 3] or [batch, {3 * J}] (axis-angle, radians, root first), "
                f"got {pose.shape}"
            )
        if betas.shape[0] not in (1, pose.shape[0]) and pose.shape[0] != 1:
            raise InputError(f"betas batch {betas.shape[0]} and pose batch {pose.shape[0]} differ; make them equal or one of them 1")
        batch = max(betas.shape[0], pose.shape[0])
        if transl is not None:
            transl = np.asarray(transl, dtype=np.float64)
            if transl.ndim == 1:
                transl = transl[None]
            if transl.ndim != 2 or transl.shape[1] != 3 or transl.shape[0] not in (1, batch):
                raise InputError(f"transl must have shape [batch, 3] with batch 1 or {batch}, got {transl.shape}")
        for name, arr in (("betas", betas), ("pose", pose), ("transl", transl)):
            if arr is not None and not np.all(np.isfinite(arr)):
                bad = int(np.size(arr) - np.isfinite(arr).sum())
                raise InputError(f"{name} has {bad} non-finite value(s) (NaN or inf); pass finite numbers")
        return betas, pose, transl

    def pose(self, betas=None, pose=None, transl=None, dtype=np.float64) -> tuple[np.ndarray, np.ndarray]:
        """Posed vertices [B, V, 3] and joints [B, J, 3] in metres (numpy)."""
        betas, pose, transl = self.check_inputs(betas, pose, transl)
        cast = lambda a: None if a is None else a.astype(dtype, copy=False)  # noqa: E731
        return _lbs.lbs_np(
            betas.astype(dtype), pose.astype(dtype), cast(self.v_template), cast(self.shapedirs),
            cast(self.posedirs), cast(self.J_regressor), self.parents, cast(self.weights),
            None if transl is None else transl.astype(dtype),
        )

    def shaped(self, betas=None) -> np.ndarray:
        """Rest-pose vertices T + B_s(β), shape [B, V, 3]."""
        betas, _, _ = self.check_inputs(betas, None, None)
        S = betas.shape[1]
        return self.v_template[None] + np.einsum("vcs,bs->bvc", self.shapedirs[:, :, :S], betas)

    def rest_joints(self, betas=None) -> np.ndarray:
        """Rest-pose joint positions J(β), shape [B, J, 3]."""
        return np.einsum("jv,bvc->bjc", self.J_regressor, self.shaped(betas))

    def torch(self, dtype: torch.dtype = torch.float32, device: str | torch.device = "cpu") -> "BodyModelTorch":
        """A differentiable torch module over the same arrays."""
        return BodyModelTorch(self, dtype=dtype, device=device)

    def subdivided(self) -> "BodyModel":
        """The model with every triangle split 4-to-1 at edge midpoints (see :mod:`datagen.body.subdivide`)."""
        from datagen.body.subdivide import subdivide_body

        return subdivide_body(self)


class BodyModelTorch(torch.nn.Module):
    """Torch posing of a :class:`BodyModel`; gradients flow to β, θ and the translation.

    ``forward(betas [B, S], pose [B, J, 3] | [B, J*3], transl [B, 3] | None)`` returns
    ``(vertices [B, V, 3], joints [B, J, 3])`` in metres.
    """

    def __init__(self, model: BodyModel, dtype: torch.dtype = torch.float32, device: str | torch.device = "cpu"):
        super().__init__()
        self.joint_count = model.joint_count
        self.shape_dim = model.shape_dim
        self.parents = [int(p) for p in model.parents]
        as_t = lambda a: torch.as_tensor(np.ascontiguousarray(a), dtype=dtype, device=device)  # noqa: E731
        self.register_buffer("v_template", as_t(model.v_template))
        self.register_buffer("shapedirs", as_t(model.shapedirs))
        self.register_buffer("J_regressor", as_t(model.J_regressor))
        self.register_buffer("weights", as_t(model.weights))
        self.register_buffer("posedirs", None if model.posedirs is None else as_t(model.posedirs))
        self.register_buffer("faces", torch.as_tensor(model.faces, dtype=torch.long, device=device))

    def forward(self, betas: torch.Tensor, pose: torch.Tensor, transl: torch.Tensor | None = None):
        J = self.joint_count
        if betas.ndim != 2 or betas.shape[1] > self.shape_dim:
            raise InputError(f"betas must be [batch, S<= {self.shape_dim}], got {tuple(betas.shape)}")
        if pose.ndim == 2 and pose.shape[1] == 3 * J:
            pose = pose.reshape(pose.shape[0], J, 3)
        if pose.ndim != 3 or tuple(pose.shape[1:]) != (J, 3):
            raise InputError(f"pose must be [batch, {J}, 3] or [batch, {3 * J}], got {tuple(pose.shape)}")
        return _lbs.lbs(betas, pose, self.v_template, self.shapedirs, self.posedirs, self.J_regressor,
                        self.parents, self.weights, transl)

