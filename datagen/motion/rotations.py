"""Rotation conversions, batched, in numpy and torch.

One convention everywhere: right-handed, column vectors, ``R @ v`` rotates ``v``; axis-angle
``r = angle * axis`` with the angle in radians; a rotation matrix has shape ``[..., 3, 3]``.
"""

from __future__ import annotations

import numpy as np
import torch


def axis_angle_to_matrix_np(axis_angle: np.ndarray) -> np.ndarray:
    """Rodrigues' formula. ``axis_angle`` [..., 3] (radians) -> rotation matrices [..., 3, 3].

    Stable at zero angle: sin(t)/t and (1 - cos t)/t^2 use their Taylor series below 1e-4.
    """
    r = np.asarray(axis_angle, dtype=np.float64 if np.asarray(axis_angle).dtype == np.float64 else np.float32)
    theta2 = np.sum(r * r, axis=-1, keepdims=True)[..., None]  # [..., 1, 1]
    theta = np.sqrt(theta2)
    small = theta < 1e-4
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta2 / 24.0, (1.0 - np.cos(safe)) / (safe * safe))
    K = _skew_np(r)
    eye = np.broadcast_to(np.eye(3, dtype=r.dtype), K.shape)
    return (eye + a * K + b * (K @ K)).astype(r.dtype)


def axis_angle_to_matrix(axis_angle: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`axis_angle_to_matrix_np`; differentiable everywhere, zero included."""
    r = axis_angle
    theta2 = (r * r).sum(-1, keepdim=True)[..., None]
    small = theta2 < 1e-8
    safe2 = torch.where(small, torch.ones_like(theta2), theta2)
    safe = safe2.sqrt()
    a = torch.where(small, 1.0 - theta2 / 6.0, torch.sin(safe) / safe)
    b = torch.where(small, 0.5 - theta2 / 24.0, (1.0 - torch.cos(safe)) / safe2)
    K = _skew(r)
    eye = torch.eye(3, dtype=r.dtype, device=r.device).expand(K.shape)
    return eye + a * K + b * (K @ K)


def _skew_np(v: np.ndarray) -> np.ndarray:
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    o = np.zeros_like(x)
    return np.stack([o, -z, y, z, o, -x, -y, x, o], axis=-1).reshape(v.shape[:-1] + (3, 3))


def _skew(v: torch.Tensor) -> torch.Tensor:
    x, y, z = v.unbind(-1)
    o = torch.zeros_like(x)
    return torch.stack([o, -z, y, z, o, -x, -y, x, o], dim=-1).reshape(v.shape[:-1] + (3, 3))
