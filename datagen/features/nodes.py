"""Paper 000's node features: the input vectors of its two graphs, assembled in one place so that a
trainer's dataset (from the store's derived arrays) and its model at inference (from a predicted
coarse mesh) build them the same way.

- body graph (W_coarse, §4.3): ``[n^{b'}, p^{b'}, α₁]`` ∈ R⁷ per garment vertex,
  :func:`coarse_node_features`;
- garment graph (W_detail, §4.4): ``[n, p, x]`` ∈ R^(6 + J) per garment vertex (R³⁰ for SMPL's 24
  joints), :func:`detail_node_features`: the coarse mesh's vertex normals, the garment's relative
  skinning feature and the distances from the coarse vertex to every posed joint.
"""

from __future__ import annotations

import torch

from datagen.features.derived import joint_distances
from datagen.geometry.topology import vertex_normals

__all__ = ["coarse_node_features", "detail_node_features"]


def coarse_node_features(anchor_normal: torch.Tensor, anchor_skin: torch.Tensor, alpha: torch.Tensor
                         ) -> torch.Tensor:
    """The body graph's node features ``[n^{b'}, p^{b'}, α₁]`` [..., V, 7].

    Args:
        anchor_normal: unit body normals at the anchors [..., V, 3].
        anchor_skin: relative skinning features of the anchors [..., V, 3] (m).
        alpha: the garment's fit attribute [A] (its first value is used) or one value per vertex
            [..., V, 1].
    """
    a = alpha if alpha.dim() == anchor_skin.dim() else alpha[:1]
    return torch.cat([anchor_normal, anchor_skin, a.expand(*anchor_skin.shape[:-1], 1)], dim=-1)


def detail_node_features(coarse: torch.Tensor, faces: torch.Tensor, skin: torch.Tensor, joints: torch.Tensor
                         ) -> torch.Tensor:
    """The garment graph's node features ``[n, p, x]`` [..., V, 6 + J] at coarse positions ``coarse``.

    Args:
        coarse: coarse garment positions [..., V, 3] (m): the store's coarse target, or a prediction.
        faces: garment triangles [F, 3] (long; several garments batched as one mesh with offset
            indices work as well).
        skin: relative skinning features of the garment vertices [..., V, 3] (m).
        joints: posed joints [..., J, 3] (m) of the frame, or per vertex [..., V, J, 3] (a batch of
            graphs of different frames).
    """
    normals = vertex_normals(coarse, faces)
    if joints.dim() == coarse.dim() + 1:  # per vertex
        x = torch.linalg.vector_norm(coarse[..., :, None, :] - joints, dim=-1)
    else:
        x = joint_distances(coarse, joints)
    return torch.cat([normals, skin, x], dim=-1)
