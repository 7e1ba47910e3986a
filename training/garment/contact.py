"""Garment-body contact for paper 001's collision handling (§3.4, eq. 4).

- :func:`body_contact`: for every garment vertex the closest vertex of the posed body and that
  vertex's unit normal; the signed distance ``n · (x - b)`` is negative inside the body.
- :func:`collision_loss`: eq. 4, ``max(-n · (x - b), 0)`` (averaged here), with an optional margin.
- :func:`push_out`: the post-process: vertices inside (or nearer than ``margin``) move out along
  the body normal to ``margin``.
"""

from __future__ import annotations

import torch


def body_contact(garment: torch.Tensor, body: torch.Tensor, body_faces: torch.Tensor
                 ) -> tuple[torch.Tensor, torch.Tensor]:
    """(closest body vertex [T, V, 3], its unit normal [T, V, 3]) for garment vertices [T, V, 3]
    on posed bodies [T, B, 3]."""
    from datagen.geometry.topology import vertex_normals

    from training.metrics import nearest

    normals = vertex_normals(body, body_faces)
    idx = nearest(garment, body)  # [T, V], in blocks
    gather = idx[..., None].expand(-1, -1, 3)
    return torch.gather(body, 1, gather), torch.gather(normals, 1, gather)


def signed_distance(garment: torch.Tensor, closest: torch.Tensor, normal: torch.Tensor) -> torch.Tensor:
    return ((garment - closest) * normal).sum(-1)


def collision_loss(garment: torch.Tensor, closest: torch.Tensor, normal: torch.Tensor, margin: float = 0.0
                   ) -> torch.Tensor:
    """Eq. 4, averaged: ``max(margin - n · (x - b), 0)``."""
    return torch.relu(margin - signed_distance(garment, closest, normal)).mean()


def push_out(garment: torch.Tensor, closest: torch.Tensor, normal: torch.Tensor, margin: float = 0.002
             ) -> torch.Tensor:
    """Vertices inside the body or nearer than ``margin`` moved out along the body normal to ``margin``."""
    d = signed_distance(garment, closest, normal)
    return garment + torch.relu(margin - d)[..., None] * normal


def inside_share(garment: torch.Tensor, closest: torch.Tensor, normal: torch.Tensor) -> float:
    return float((signed_distance(garment, closest, normal) < 0).float().mean())
