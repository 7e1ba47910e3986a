"""STED, the spatio-temporal edge difference of two animated meshes with one topology (Vasa and
Skala 2011, "A perception correlated comparison method for dynamic meshes"), as paper 001 Table 3
uses it for body sequences.

- Spatial part: every edge's relative length change ``(|ẽ| - |e|) / |e|``; at each vertex and frame
  the standard deviation of those changes over the vertex's one-ring edges, weighted by their true
  lengths; STED_s is its mean over vertices and frames. A rigid motion or a uniform scaling of the
  neighbourhood costs nothing; local stretching does.
- Temporal part: each vertex's displacement from one frame to the next (its "temporal edge"),
  predicted against true, divided by the mean true length of the vertex's one-ring edges;
  STED_t is the root mean square of that over vertices and frame pairs.
- STED = sqrt(STED_s² + STED_t²) (the two parts weighted equally; Vasa and Skala tune a weight
  on perceptual data, which is not reproduced here).
"""

from __future__ import annotations

import numpy as np
import torch

from datagen.geometry.topology import unique_edges


def mesh_edges(faces: np.ndarray) -> np.ndarray:
    """The unique undirected edges [E, 2] of triangles ``faces`` [F, 3]."""
    return unique_edges(faces)


def sted(pred: torch.Tensor, true: torch.Tensor, edges: torch.Tensor) -> dict[str, torch.Tensor]:
    """STED of sequences ``pred`` and ``true`` [N, T, V, 3] over ``edges`` [E, 2]: per sequence [N]
    ``spatial``, ``temporal`` and ``sted``."""
    a, b = edges[:, 0], edges[:, 1]
    N, T, V, _ = true.shape
    l_true = (true[:, :, a] - true[:, :, b]).norm(dim=-1)  # [N, T, E]
    l_pred = (pred[:, :, a] - pred[:, :, b]).norm(dim=-1)
    rel = (l_pred - l_true) / l_true.clamp(min=1e-9)

    def to_vertices(values: torch.Tensor) -> torch.Tensor:  # sum over each vertex's incident edges
        out = torch.zeros(N, T, V, dtype=values.dtype, device=values.device)
        return out.index_add(2, a, values).index_add(2, b, values)

    weight = to_vertices(l_true).clamp(min=1e-12)
    mean = to_vertices(l_true * rel) / weight
    dev_a, dev_b = rel - mean[:, :, a], rel - mean[:, :, b]
    var = (torch.zeros_like(weight).index_add(2, a, l_true * dev_a ** 2).index_add(2, b, l_true * dev_b ** 2)) / weight
    spatial = var.clamp(min=0).sqrt().mean(dim=(1, 2))
    degree = to_vertices(torch.ones_like(l_true)).clamp(min=1)
    ring = (weight / degree)[:, :-1]  # mean true one-ring edge length, frames 0 .. T-2
    step_true = (true[:, 1:] - true[:, :-1]).norm(dim=-1)
    step_pred = (pred[:, 1:] - pred[:, :-1]).norm(dim=-1)
    temporal = (((step_pred - step_true) / ring) ** 2).mean(dim=(1, 2)).sqrt()
    return {"spatial": spatial, "temporal": temporal, "sted": (spatial ** 2 + temporal ** 2).sqrt()}
