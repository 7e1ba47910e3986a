"""Rotation conversions, batched over any leading dims, in numpy (``*_np``) and torch.

One convention everywhere:

- right-handed, **column vectors**: ``R @ v`` rotates ``v``; a rotation matrix has shape
  ``[..., 3, 3]``;
- **axis-angle** ``r = angle * axis`` [..., 3], the angle in radians (SMPL's θ);
- **quaternions** [..., 4] stored **(w, x, y, z), scalar first**, unit norm, canonicalised to
  ``w >= 0`` (so ``q`` and ``-q``, the same rotation, map to one value). Every function that
  returns a quaternion returns it canonical; every function that takes one normalises it first.
  Note that scipy's ``Rotation.as_quat`` uses (x, y, z, w);
- **6D** [..., 6] = the first two **columns** of the matrix, concatenated:
  ``[R[..., :, 0], R[..., :, 1]]`` (Zhou et al. 2019, "On the Continuity of Rotation
  Representations in Neural Networks"); converted back by Gram-Schmidt, so any 6D input with
  two non-parallel halves gives a proper rotation.

Axis-angle returned by these functions has its angle in [0, pi]. Conversions are stable near
angle 0 (Taylor series below a threshold) and near pi (matrix -> axis-angle goes through a
quaternion found by Shepperd's method, which branches on the largest diagonal term, so the axis
is recovered up to sign at exactly pi).

numpy functions keep float32 input as float32 and compute everything else in float64. torch
functions keep the input's dtype and device and are differentiable, with finite gradients at zero
angle.
"""

from __future__ import annotations

import numpy as np
import torch

__all__ = [
    "axis_angle_to_matrix",
    "axis_angle_to_matrix_np",
    "axis_angle_to_quaternion",
    "axis_angle_to_quaternion_np",
    "matrix_to_axis_angle",
    "matrix_to_axis_angle_np",
    "matrix_to_quaternion",
    "matrix_to_quaternion_np",
    "matrix_to_rotation_6d",
    "matrix_to_rotation_6d_np",
    "quaternion_slerp",
    "quaternion_slerp_np",
    "quaternion_to_axis_angle",
    "quaternion_to_axis_angle_np",
    "quaternion_to_matrix",
    "quaternion_to_matrix_np",
    "rotation_6d_to_matrix",
    "rotation_6d_to_matrix_np",
]

_SMALL_ANGLE = 1e-4
"""Below this angle (radians) the axis-angle <-> quaternion factors use their Taylor series."""

_SLERP_LINEAR_CHORD = 1e-6
"""Below this chord |q0 - q1| (about the angle between them) slerp uses normalised linear
interpolation, which then differs from slerp by less than 1e-18."""


def _float_np(x) -> np.ndarray:
    """``x`` as a float array: float32 stays float32, anything else becomes float64."""
    x = np.asarray(x)
    return x.astype(np.float32 if x.dtype == np.float32 else np.float64, copy=False)


# ----------------------------------------------------------------------------- axis-angle <-> matrix

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


def matrix_to_axis_angle_np(matrix: np.ndarray) -> np.ndarray:
    """Rotation matrices [..., 3, 3] -> axis-angle [..., 3] (radians, angle in [0, pi]).

    Goes through :func:`matrix_to_quaternion_np`, so it is stable near 0 and at pi, where the
    axis is recovered up to sign (both signs are the same rotation).
    """
    return quaternion_to_axis_angle_np(matrix_to_quaternion_np(matrix))


def matrix_to_axis_angle(matrix: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`matrix_to_axis_angle_np`; differentiable, finite at identity."""
    return quaternion_to_axis_angle(matrix_to_quaternion(matrix))


# ----------------------------------------------------------------------------- axis-angle <-> quaternion

def axis_angle_to_quaternion_np(axis_angle: np.ndarray) -> np.ndarray:
    """Axis-angle [..., 3] (radians) -> unit quaternions [..., 4] (w, x, y, z), ``w >= 0``.

    ``q = (cos(t/2), sin(t/2) * axis)`` with ``t = |r|``; sin(t/2)/t uses its Taylor series
    below 1e-4. Angles above pi give the canonical (negated) quaternion of the same rotation.
    """
    r = _float_np(axis_angle)
    theta2 = np.sum(r * r, axis=-1, keepdims=True)
    theta = np.sqrt(theta2)
    small = theta < _SMALL_ANGLE
    safe = np.where(small, 1.0, theta)
    k = np.where(small, 0.5 - theta2 / 48.0, np.sin(0.5 * safe) / safe)
    w = np.where(small, 1.0 - theta2 / 8.0, np.cos(0.5 * safe))
    q = np.concatenate([w, k * r], axis=-1)
    return _canonical_np(q).astype(r.dtype, copy=False)


def axis_angle_to_quaternion(axis_angle: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`axis_angle_to_quaternion_np`; differentiable, finite at zero."""
    r = axis_angle
    theta2 = (r * r).sum(-1, keepdim=True)
    small = theta2 < _SMALL_ANGLE**2
    safe = torch.where(small, torch.ones_like(theta2), theta2).sqrt()
    k = torch.where(small, 0.5 - theta2 / 48.0, torch.sin(0.5 * safe) / safe)
    w = torch.where(small, 1.0 - theta2 / 8.0, torch.cos(0.5 * safe))
    return _canonical(torch.cat([w, k * r], dim=-1))


def quaternion_to_axis_angle_np(quaternion: np.ndarray) -> np.ndarray:
    """Quaternions [..., 4] (w, x, y, z), any norm > 0 -> axis-angle [..., 3], angle in [0, pi].

    ``angle = 2 atan2(|xyz|, w)`` after canonicalising to ``w >= 0``; the factor angle/|xyz|
    uses its Taylor series when |xyz| < 1e-4, so it is exact near 0 and well defined at pi.
    """
    q = _canonical_np(_normalize_np(_float_np(quaternion)))
    w, xyz = q[..., :1], q[..., 1:]
    n2 = np.sum(xyz * xyz, axis=-1, keepdims=True)
    n = np.sqrt(n2)
    small = n < _SMALL_ANGLE
    safe_n = np.where(small, 1.0, n)
    safe_w = np.where(small, w, 1.0)  # w ~ 1 wherever small is true (unit quaternion)
    factor = np.where(small, 2.0 / safe_w - (2.0 / 3.0) * n2 / safe_w**3,
                      2.0 * np.arctan2(n, w) / safe_n)
    return (factor * xyz).astype(q.dtype, copy=False)


def quaternion_to_axis_angle(quaternion: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`quaternion_to_axis_angle_np`; differentiable, finite at identity."""
    q = _canonical(_normalize(quaternion))
    w, xyz = q[..., :1], q[..., 1:]
    n2 = (xyz * xyz).sum(-1, keepdim=True)
    small = n2 < _SMALL_ANGLE**2
    safe_n = torch.where(small, torch.ones_like(n2), n2).sqrt()
    safe_w = torch.where(small, w, torch.ones_like(w))
    factor = torch.where(small, 2.0 / safe_w - (2.0 / 3.0) * n2 / safe_w**3,
                         2.0 * torch.atan2(safe_n, w) / safe_n)
    return factor * xyz


# ----------------------------------------------------------------------------- quaternion <-> matrix

def _quaternion_matrix_entries(w, x, y, z) -> list:
    """The nine entries of a unit quaternion's rotation matrix, row by row (numpy or torch)."""
    return [
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    ]


def quaternion_to_matrix_np(quaternion: np.ndarray) -> np.ndarray:
    """Quaternions [..., 4] (w, x, y, z), normalised here -> rotation matrices [..., 3, 3]."""
    q = _normalize_np(_float_np(quaternion))
    m = np.stack(_quaternion_matrix_entries(*np.moveaxis(q, -1, 0)), axis=-1)
    return m.reshape(q.shape[:-1] + (3, 3))


def quaternion_to_matrix(quaternion: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`quaternion_to_matrix_np`; differentiable."""
    q = _normalize(quaternion)
    m = torch.stack(_quaternion_matrix_entries(*q.unbind(-1)), dim=-1)
    return m.reshape(q.shape[:-1] + (3, 3))


def matrix_to_quaternion_np(matrix: np.ndarray) -> np.ndarray:
    """Rotation matrices [..., 3, 3] -> unit quaternions [..., 4] (w, x, y, z), ``w >= 0``.

    Shepperd's method: of the four algebraically equivalent formulas, each use the square root
    of one of ``1 + tr``, ``1 + 2 R00 - tr``, ``1 + 2 R11 - tr``, ``1 + 2 R22 - tr`` (= 4 w^2,
    4 x^2, 4 y^2, 4 z^2) and divides the off-diagonal terms by it; the largest is picked per
    matrix, so the divisor is never below 1 and the result is accurate for every rotation.
    """
    m = _float_np(matrix)
    if m.shape[-2:] != (3, 3):
        raise ValueError(f"matrix must have shape [..., 3, 3], got {m.shape}")
    m00, m01, m02 = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    m10, m11, m12 = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    four_sq = np.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22,
                        1 - m00 + m11 - m22, 1 - m00 - m11 + m22], axis=-1)  # 4 w^2, 4 x^2, ...
    # Row i: 4 q_i * q, using the formula whose diagonal term is 4 q_i^2.
    cand = np.stack([
        np.stack([four_sq[..., 0], m21 - m12, m02 - m20, m10 - m01], axis=-1),
        np.stack([m21 - m12, four_sq[..., 1], m10 + m01, m02 + m20], axis=-1),
        np.stack([m02 - m20, m10 + m01, four_sq[..., 2], m12 + m21], axis=-1),
        np.stack([m10 - m01, m20 + m02, m21 + m12, four_sq[..., 3]], axis=-1),
    ], axis=-2)  # [..., 4, 4]
    best = np.argmax(four_sq, axis=-1)
    q = np.take_along_axis(cand, best[..., None, None], axis=-2)[..., 0, :]
    return _canonical_np(_normalize_np(q)).astype(m.dtype, copy=False)


def matrix_to_quaternion(matrix: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`matrix_to_quaternion_np` (Shepperd's method); differentiable."""
    if matrix.shape[-2:] != (3, 3):
        raise ValueError(f"matrix must have shape [..., 3, 3], got {tuple(matrix.shape)}")
    m00, m01, m02 = matrix[..., 0, 0], matrix[..., 0, 1], matrix[..., 0, 2]
    m10, m11, m12 = matrix[..., 1, 0], matrix[..., 1, 1], matrix[..., 1, 2]
    m20, m21, m22 = matrix[..., 2, 0], matrix[..., 2, 1], matrix[..., 2, 2]
    four_sq = torch.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22,
                           1 - m00 + m11 - m22, 1 - m00 - m11 + m22], dim=-1)
    cand = torch.stack([
        torch.stack([four_sq[..., 0], m21 - m12, m02 - m20, m10 - m01], dim=-1),
        torch.stack([m21 - m12, four_sq[..., 1], m10 + m01, m02 + m20], dim=-1),
        torch.stack([m02 - m20, m10 + m01, four_sq[..., 2], m12 + m21], dim=-1),
        torch.stack([m10 - m01, m20 + m02, m21 + m12, four_sq[..., 3]], dim=-1),
    ], dim=-2)
    best = four_sq.argmax(dim=-1)
    index = best[..., None, None].expand(best.shape + (1, 4))
    q = torch.gather(cand, -2, index)[..., 0, :]
    return _canonical(_normalize(q))


# ----------------------------------------------------------------------------- 6D

def matrix_to_rotation_6d_np(matrix: np.ndarray) -> np.ndarray:
    """Rotation matrices [..., 3, 3] -> 6D [..., 6] = ``[R[..., :, 0], R[..., :, 1]]`` (columns)."""
    m = _float_np(matrix)
    return np.concatenate([m[..., :, 0], m[..., :, 1]], axis=-1)


def matrix_to_rotation_6d(matrix: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`matrix_to_rotation_6d_np`."""
    return torch.cat([matrix[..., :, 0], matrix[..., :, 1]], dim=-1)


def rotation_6d_to_matrix_np(rot6d: np.ndarray) -> np.ndarray:
    """6D [..., 6] -> rotation matrices [..., 3, 3] by Gram-Schmidt (Zhou et al. 2019).

    Column 0 is the first half normalised; column 1 is the second half minus its component
    along column 0, normalised; column 2 is their cross product. The input need not be
    orthonormal (e.g. a network's output), only its halves non-parallel and non-zero.
    """
    d = _float_np(rot6d)
    a1, a2 = d[..., :3], d[..., 3:]
    b1 = _normalize_np(a1)
    b2 = _normalize_np(a2 - np.sum(b1 * a2, axis=-1, keepdims=True) * b1)
    b3 = np.cross(b1, b2)
    return np.stack([b1, b2, b3], axis=-1)


def rotation_6d_to_matrix(rot6d: torch.Tensor) -> torch.Tensor:
    """Torch version of :func:`rotation_6d_to_matrix_np`; differentiable."""
    a1, a2 = rot6d[..., :3], rot6d[..., 3:]
    b1 = _normalize(a1)
    b2 = _normalize(a2 - (b1 * a2).sum(-1, keepdim=True) * b1)
    b3 = torch.cross(b1, b2, dim=-1)
    return torch.stack([b1, b2, b3], dim=-1)


# ----------------------------------------------------------------------------- slerp

def quaternion_slerp_np(q0: np.ndarray, q1: np.ndarray, t) -> np.ndarray:
    """Spherical linear interpolation along the shortest arc, canonical (w >= 0) result.

    Args:
        q0, q1: quaternions [..., 4] (w, x, y, z), normalised here; broadcast against each other.
        t: interpolation parameter, a scalar or an array broadcastable against ``q0.shape[:-1]``;
            0 gives ``q0`` and 1 gives ``q1`` (canonicalised); values outside [0, 1] extrapolate.

    Returns:
        Unit quaternions [..., 4]. ``q1`` is negated first when ``q0 . q1 < 0`` so the path is
        the shorter of the two; quaternions less than 1e-6 apart (chord length) use normalised
        linear interpolation, identical to slerp to round-off.
    """
    q0 = _normalize_np(_float_np(q0))
    q1 = _normalize_np(_float_np(q1))
    t = np.asarray(t, dtype=q0.dtype)[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    # The half-angle between q0 and q1 from chord lengths: accurate at every angle (acos of the
    # dot product loses half the digits near 0).
    chord2 = np.sum((q0 - q1) ** 2, axis=-1, keepdims=True)
    linear = chord2 < _SLERP_LINEAR_CHORD**2
    chord = np.sqrt(np.where(linear, 1.0, chord2))
    omega = 2.0 * np.arctan2(chord, np.linalg.norm(q0 + q1, axis=-1, keepdims=True))
    sin_omega = np.sin(omega)
    s0 = np.where(linear, 1.0 - t, np.sin((1.0 - t) * omega) / sin_omega)
    s1 = np.where(linear, t, np.sin(t * omega) / sin_omega)
    return _canonical_np(_normalize_np(s0 * q0 + s1 * q1)).astype(q0.dtype, copy=False)


def quaternion_slerp(q0: torch.Tensor, q1: torch.Tensor, t) -> torch.Tensor:
    """Torch version of :func:`quaternion_slerp_np`; differentiable in ``q0``, ``q1`` and ``t``.

    ``t`` is a float or a tensor broadcastable against ``q0.shape[:-1]``.
    """
    q0 = _normalize(q0)
    q1 = _normalize(q1)
    t = torch.as_tensor(t, dtype=q0.dtype, device=q0.device)[..., None]
    dot = (q0 * q1).sum(-1, keepdim=True)
    q1 = torch.where(dot < 0, -q1, q1)
    chord2 = ((q0 - q1) ** 2).sum(-1, keepdim=True)
    linear = chord2 < _SLERP_LINEAR_CHORD**2
    chord = torch.where(linear, torch.ones_like(chord2), chord2).sqrt()
    omega = 2.0 * torch.atan2(chord, (q0 + q1).norm(dim=-1, keepdim=True))
    sin_omega = torch.sin(omega)
    s0 = torch.where(linear, 1.0 - t, torch.sin((1.0 - t) * omega) / sin_omega)
    s1 = torch.where(linear, t, torch.sin(t * omega) / sin_omega)
    return _canonical(_normalize(s0 * q0 + s1 * q1))


# ----------------------------------------------------------------------------- helpers

def _normalize_np(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _normalize(v: torch.Tensor) -> torch.Tensor:
    return v / v.norm(dim=-1, keepdim=True)


def _canonical_np(q: np.ndarray) -> np.ndarray:
    """Negate quaternions with w < 0 so that w >= 0 (same rotation)."""
    return np.where(q[..., :1] < 0, -q, q)


def _canonical(q: torch.Tensor) -> torch.Tensor:
    return torch.where(q[..., :1] < 0, -q, q)


def _skew_np(v: np.ndarray) -> np.ndarray:
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    o = np.zeros_like(x)
    return np.stack([o, -z, y, z, o, -x, -y, x, o], axis=-1).reshape(v.shape[:-1] + (3, 3))


def _skew(v: torch.Tensor) -> torch.Tensor:
    x, y, z = v.unbind(-1)
    o = torch.zeros_like(x)
    return torch.stack([o, -z, y, z, o, -x, -y, x, o], dim=-1).reshape(v.shape[:-1] + (3, 3))
