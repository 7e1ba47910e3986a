"""A frame of paper 001's models as numbers, and the Transformer's positions.

A frame is its 24 joint rotations in the 6D representation (``datagen.geometry.rotations``'s
convention: the first two columns of the rotation matrix) and the root translation relative to the
sequence's first frame: 24 x 6 + 3 = 147 numbers (:data:`FRAME_FEATURES`). The motion generator
reconstructs them; the garment regressor's pose encoder reads them.
"""

from __future__ import annotations

import math

import torch

from datagen.geometry.rotations import matrix_to_rotation_6d, rotation_6d_to_matrix

JOINTS = 24
FRAME_FEATURES = JOINTS * 6 + 3


def sinusoidal_positions(length: int, width: int, device=None) -> torch.Tensor:
    """The Transformer's sinusoidal position code [length, width]."""
    position = torch.arange(length, dtype=torch.float32, device=device)[:, None]
    rate = torch.exp(torch.arange(0, width, 2, dtype=torch.float32, device=device) * (-math.log(10000.0) / width))
    out = torch.zeros(length, width, device=device)
    out[:, 0::2] = torch.sin(position * rate)
    out[:, 1::2] = torch.cos(position * rate[: width // 2])
    return out


def frames_to_features(rotations: torch.Tensor, trans: torch.Tensor) -> torch.Tensor:
    """[B, T, 24, 3, 3] rotation matrices and [B, T, 3] translations -> [B, T, 147] (translation
    relative to each sequence's first frame)."""
    B, T = rotations.shape[:2]
    six = matrix_to_rotation_6d(rotations).reshape(B, T, JOINTS * 6)
    return torch.cat([six, trans - trans[:, :1]], dim=-1)


def features_to_frames(x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """[B, T, 147] -> rotation matrices [B, T, 24, 3, 3] (Gram-Schmidt of the 6D part) and the
    translation [B, T, 3] (from the first frame)."""
    B, T = x.shape[:2]
    rot = rotation_6d_to_matrix(x[..., : JOINTS * 6].reshape(B, T, JOINTS, 6))
    return rot, x[..., JOINTS * 6:]


def pose_features(batch: dict) -> tuple[torch.Tensor, torch.Tensor]:
    """(features [B, T, 147], rotation matrices [B, T, 24, 3, 3]) of a batch's true poses (axis-angle
    ``pose`` [B, T, 24, 3], ``trans`` [B, T, 3] m)."""
    from datagen.geometry.rotations import axis_angle_to_matrix

    rot = axis_angle_to_matrix(batch["pose"].float())
    return frames_to_features(rot, batch["trans"].float()), rot
