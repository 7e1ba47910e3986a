"""Paper 000's node features, assembled in one place for training and inference.

- :func:`body_node_features`: the body graph's [n^{b'}, p^{b'}, α₁] (R^7, §4.3) from the store's
  derived anchor normals and skinning features.
- :func:`node_features`: the garment graph's [n, p, x] (R^30, §4.4) at coarse positions: the
  coarse mesh's vertex normals, the skinning feature, the distances to the posed joints. The
  dataset (:class:`training.gnn.data.FrameDataset`) calls it on the ground-truth coarse mesh, as the
  paper trains; the module (:class:`training.gnn.module.GNNModule`) on the predicted one, as
  inference runs: the same function, so the two cannot disagree.
"""

from __future__ import annotations

import torch

from datagen.features import joint_distances
from datagen.geometry.topology import vertex_normals


def body_node_features(anchor_normal: torch.Tensor, anchor_skin: torch.Tensor, alpha: torch.Tensor) -> torch.Tensor:
    """[V, 7] of one frame: anchor normals [V, 3], anchor skinning features [V, 3] (m) and the fit
    attribute's first component α₁ (``alpha`` [A], its first entry) on every node."""
    return torch.cat([anchor_normal, anchor_skin, alpha[:1].expand(len(anchor_normal), 1)], dim=1)


def node_features(coarse: torch.Tensor, face: torch.Tensor, skin: torch.Tensor, joints: torch.Tensor,
                  batch: torch.Tensor | None = None) -> torch.Tensor:
    """[N, 30] garment node features at coarse positions ``coarse`` [N, 3] (m) of one or more
    garments: ``face`` [3, F] their triangles (node indices of the batch), ``skin`` [N, 3] the
    skinning feature (m), ``joints`` [G, J, 3] each graph's posed joints (m) and ``batch`` [N] each
    node's graph (None: one graph)."""
    normals = vertex_normals(coarse[None], face.T)[0]
    per_node = joints[0].expand(len(coarse), -1, -1) if batch is None else joints[batch]
    x = joint_distances(coarse[:, None, :], per_node)[:, 0]  # [N, J]
    return torch.cat([normals, skin, x], dim=1)
