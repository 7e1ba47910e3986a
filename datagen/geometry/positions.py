"""Garment positions as a dataset store keeps them: int32 steps of a quantum (schemas.dataset.POSITION_QUANTUM,
0.05 mm) from each frame's root joint. numpy only (torch tensors are decoded on their device when given)."""

from __future__ import annotations

import numpy as np

from datagen.errors import InputError

__all__ = ["decode_positions", "encode_positions"]


def encode_positions(positions: np.ndarray, root: np.ndarray, quantum: float) -> np.ndarray:
    """Positions [T, V, 3] (m) as int32 steps of ``quantum`` from each frame's root joint [T, 3]
    (rounded to nearest: the decoded error is at most ``quantum / 2`` plus float32 rounding)."""
    steps = np.rint((np.asarray(positions, np.float64) - np.asarray(root, np.float64)[:, None]) / quantum)
    if steps.size and np.abs(steps).max() >= 2**31:
        raise InputError(f"positions more than {quantum * 2**31:.0f} m from the root joint cannot be stored")
    return steps.astype(np.int32)


def decode_positions(steps, root, quantum: float):
    """Inverse of :func:`encode_positions`: float32 metres [T, V, 3] (numpy or torch, as given)."""
    if type(steps).__module__.startswith("torch"):  # a tensor: decoded on its device
        import torch

        return (steps.to(torch.float64) * quantum + root.to(torch.float64)[:, None]).to(torch.float32)
    return (np.asarray(steps, np.float64) * quantum + np.asarray(root, np.float64)[:, None]).astype(np.float32)
