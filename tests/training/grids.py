"""A synthetic paper-000 frame on a triangulated grid, for the GNN's tests (no store needed)."""

from __future__ import annotations

import torch


def grid_frame(vertices: int, seed: int = 0):
    """A torch_geometric Data shaped like one FrameDataset item, on a triangulated n x n grid."""
    from torch_geometric.data import Data

    g = torch.Generator().manual_seed(seed)
    n = max(2, int(round(vertices ** 0.5)))
    V = n * n
    idx = torch.arange(V).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].flatten(), idx[:-1, 1:].flatten(), idx[1:, :-1].flatten(), idx[1:, 1:].flatten()
    faces = torch.cat([torch.stack([a, b, d], 1), torch.stack([a, d, c], 1)])
    e = torch.cat([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e = torch.unique(torch.sort(e, dim=1).values, dim=0)
    edges = torch.cat([e, e.flip(1)]).T.contiguous()
    xy = torch.stack(torch.meshgrid(torch.linspace(0, 0.6, n), torch.linspace(0, 0.6, n), indexing="ij"), -1)
    anchor = torch.cat([xy.reshape(V, 2), torch.zeros(V, 1)], 1)
    r = lambda *s: torch.randn(*s, generator=g)  # noqa: E731
    coarse = anchor + 0.02 * r(V, 3)
    return Data(x_coarse=r(V, 7), x_detail=r(V, 30), edge_index=edges, num_nodes=V, y_coarse=coarse - anchor,
                y_detail=0.003 * r(V, 3), anchor=anchor, coarse=coarse, detail=coarse + 0.003 * r(V, 3),
                skin=anchor.clone(), attributes=r(1, 85), trans=torch.zeros(1, 3), joints=r(1, 24, 3),
                face=faces.T.contiguous())
