"""The store's SMPL-format body as a differentiable torch layer (paper 001's vertex losses and metrics)."""

from __future__ import annotations

import torch

from datagen.geometry.skinning import pose_shaped


class BodyLayer(torch.nn.Module):
    """The store's SMPL-format body as a differentiable layer: rotation matrices [N, 24, 3, 3],
    translations [N, 3] and β [N, S] -> vertices [N, V', 3] (every ``stride``-th vertex)."""

    def __init__(self, body: dict, stride: int = 1):
        super().__init__()
        f32 = torch.float32
        self.parents = [int(p) for p in body["parents"]]
        self.register_buffer("parent_index", torch.as_tensor(self.parents[1:], dtype=torch.long), persistent=False)
        self.register_buffer("v_template", torch.as_tensor(body["v_template"], dtype=f32), persistent=False)
        self.register_buffer("shapedirs", torch.as_tensor(body["shapedirs"], dtype=f32), persistent=False)
        self.register_buffer("J_regressor", torch.as_tensor(body["J_regressor"], dtype=f32), persistent=False)
        keep = torch.arange(0, len(body["v_template"]), stride)
        self.register_buffer("keep", keep, persistent=False)
        self.register_buffer("weights", torch.as_tensor(body["weights"], dtype=f32)[keep], persistent=False)

    def forward(self, rot: torch.Tensor, trans: torch.Tensor, betas: torch.Tensor) -> torch.Tensor:
        S = betas.shape[-1]
        shaped = self.v_template[None] + torch.einsum("vcs,bs->bvc", self.shapedirs[:, :, :S], betas)
        joints = torch.einsum("jv,bvc->bjc", self.J_regressor, shaped)
        return pose_shaped(rot, joints, self.parents, shaped=shaped[:, self.keep], weights=self.weights,
                           transl=trans, parent_index=self.parent_index)[0]
