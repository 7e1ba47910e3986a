"""Point-set queries the trainers' evaluation and collision handling share, chunked so that a
frame of the whole body (13,348 vertices) never makes a [frames, V, W] distance tensor at once
(a batch of 480 frames would be hundreds of GB)."""

from __future__ import annotations

import torch

ROWS = 2048
"""Points of ``a`` against all of ``b`` per distance block."""


def _blocks(a: torch.Tensor, b: torch.Tensor):
    """(frame, row slice, distances [rows, W]) over the frames of a [N, V, 3] and b [N, W, 3]."""
    for n in range(a.shape[0]):
        for r in range(0, a.shape[1], ROWS):
            yield n, slice(r, r + ROWS), torch.cdist(a[n, r:r + ROWS], b[n])


def nearest(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """For every point of a [N, V, 3] the index [N, V] of the nearest point of b [N, W, 3] (same frame)."""
    out = torch.empty(a.shape[:2], dtype=torch.long, device=a.device)
    for n, rows, d in _blocks(a, b):
        out[n, rows] = d.argmin(dim=1)
    return out


def hausdorff(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Symmetric Hausdorff distance between point sets a [N, V, 3] and b [N, W, 3], per frame [N]."""
    a_to_b = torch.zeros(a.shape[0], dtype=a.dtype, device=a.device)
    b_to_a = torch.full(b.shape[:2], float("inf"), dtype=a.dtype, device=a.device)
    for n, _, d in _blocks(a, b):
        a_to_b[n] = torch.maximum(a_to_b[n], d.min(dim=1).values.max())
        b_to_a[n] = torch.minimum(b_to_a[n], d.min(dim=0).values)
    return torch.maximum(a_to_b, b_to_a.max(dim=1).values)


def rmse(squared_sum: float, points: int, what: str, point: str) -> dict[str, float]:
    """Both RMSEs of ``points`` 3-vectors (joints' axis-angles, vertices) whose squared errors sum to
    ``squared_sum``, named: ``{what}_rmse_per_coordinate`` (the root of the mean squared coordinate
    error) and ``{what}_rmse_per_{point}`` (the root of the mean squared Euclidean distance, √3
    times the first). Papers rarely say which they report; drape prints both."""
    if points <= 0:
        return {f"{what}_rmse_per_coordinate": float("nan"), f"{what}_rmse_per_{point}": float("nan")}
    return {f"{what}_rmse_per_coordinate": (squared_sum / (3 * points)) ** 0.5,
            f"{what}_rmse_per_{point}": (squared_sum / points) ** 0.5}
