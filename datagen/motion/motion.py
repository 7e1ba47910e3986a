"""The :class:`Motion` data type: a labelled sequence of SMPL poses and root translations.

A motion is ``T`` frames sampled at ``fps`` frames per second; frame ``k`` is at time ``k / fps``
seconds. Poses are SMPL's θ per frame, 24 axis-angle rotations in radians in the joint order of
:mod:`datagen.body.skeleton` (the root's global orientation first), with the conventions of
:mod:`datagen.geometry.rotations`. Translations are the root translation in metres, the ``transl``
that :func:`datagen.body.lbs.lbs_np` adds to every vertex.

On disk a motion is an ``.npz`` in an AMASS-like layout (see :meth:`Motion.save_npz`), read back
with ``allow_pickle=False``.
"""

from __future__ import annotations

import json
import math
import os
import zipfile
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from datagen.body.skeleton import JOINT_COUNT, POSE_DIM
from datagen.errors import InputError
from datagen.geometry.rotations import (
    axis_angle_to_quaternion_np,
    quaternion_slerp_np,
    quaternion_to_axis_angle_np,
)

__all__ = ["NPZ_KEYS", "Motion"]

NPZ_KEYS: tuple[str, ...] = ("poses", "trans", "mocap_framerate", "label", "label_name", "source")
"""Arrays in a motion ``.npz`` written by :meth:`Motion.save_npz`."""

_SNAP = 1e-6
"""Resampling: a new frame within this many source frames of a source frame copies it exactly."""


@dataclass(frozen=True, eq=False)
class Motion:
    """A labelled motion: SMPL poses and root translations over ``T`` frames.

    Attributes:
        poses: joint rotations [T, 24, 3], axis-angle in radians, SMPL joint order (root first).
            ``[T, 72]`` is accepted and reshaped. Stored as a float64 copy.
        trans: root translation [T, 3] in metres. Stored as a float64 copy.
        fps: frames per second (> 0); frame ``k`` is at ``k / fps`` seconds.
        label: integer class of the motion (e.g. the index of ``label_name`` in a label list).
        label_name: human-readable class, e.g. ``"walk"``.
        source: where the motion came from, JSON-serialisable, e.g.
            ``{"kind": "procedural", "generator": "walk", "params": {...}}`` or
            ``{"kind": "file", "path": "..."}``. Operations add keys: ``resampled_from_fps``,
            ``segment_start`` / ``segment_length`` (frames) and ``lead_in_frames``.

    Every field is checked on construction; mistakes raise :class:`~datagen.errors.InputError`.
    The dataclass is frozen (fields cannot be reassigned) and its arrays are owned copies.
    """

    poses: np.ndarray
    trans: np.ndarray
    fps: float
    label: int
    label_name: str
    source: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        poses = _float_array(self.poses, "poses")
        if poses.ndim == 2 and poses.shape[1] % 3 == 0 and poses.shape[1] != JOINT_COUNT:
            poses = poses.reshape(poses.shape[0], -1, 3)
        if poses.ndim != 3 or poses.shape[2] != 3:
            raise InputError(
                f"poses has shape {poses.shape}; expected [T, {JOINT_COUNT}, 3] axis-angle "
                f"rotations (or [T, {POSE_DIM}] flat), radians, in SMPL joint order"
            )
        if poses.shape[1] != JOINT_COUNT:
            raise InputError(
                f"poses: expected {JOINT_COUNT} joints per frame (SMPL order, datagen.body.skeleton), "
                f"got {poses.shape[1]}. Pass poses of shape [T, {JOINT_COUNT}, 3]; for SMPL-H/SMPL-X "
                "data take the first 22 (body) joints and append 2 zero hand joints"
            )
        frames = poses.shape[0]
        if frames == 0:
            raise InputError("poses has 0 frames; a Motion needs at least one frame")
        trans = _float_array(self.trans, "trans")
        if trans.ndim != 2 or trans.shape[1] != 3:
            raise InputError(f"trans has shape {trans.shape}; expected [T, 3] root translations in metres")
        if trans.shape[0] != frames:
            raise InputError(
                f"trans has {trans.shape[0]} frames but poses has {frames}; pass one root "
                "translation [3] per pose frame"
            )
        _check_finite(poses, "poses", "joints")
        _check_finite(trans, "trans", "axes")
        fps = _check_fps(self.fps, "fps")
        label = self.label
        if isinstance(label, (bool, np.bool_)) or not isinstance(label, (int, np.integer)):
            raise InputError(f"label must be an int (the class index), got {label!r} of type {type(label).__name__}")
        if not isinstance(self.label_name, str):
            raise InputError(f"label_name must be a str, got {type(self.label_name).__name__}")
        if not isinstance(self.source, dict):
            raise InputError(
                f"source must be a dict such as {{'kind': 'file', 'path': ...}}, got {type(self.source).__name__}"
            )
        source = json.loads(_source_json(self.source))  # a plain, JSON-safe deep copy
        object.__setattr__(self, "poses", np.ascontiguousarray(poses, dtype=np.float64).copy())
        object.__setattr__(self, "trans", np.ascontiguousarray(trans, dtype=np.float64).copy())
        object.__setattr__(self, "fps", fps)
        object.__setattr__(self, "label", int(label))
        object.__setattr__(self, "source", source)

    def __repr__(self) -> str:
        kind = self.source.get("kind", "?")
        return (f"Motion(frames={self.frame_count}, fps={self.fps:g}, duration={self.duration:.3f}s, "
                f"label={self.label} {self.label_name!r}, source kind={kind!r})")

    # ------------------------------------------------------------------------- timing

    @property
    def frame_count(self) -> int:
        """Number of frames ``T``."""
        return int(self.poses.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first frame to the last: ``(T - 1) / fps`` (0 for one frame)."""
        return (self.frame_count - 1) / self.fps

    @property
    def times(self) -> np.ndarray:
        """Time of each frame [T] in seconds: ``k / fps``."""
        return np.arange(self.frame_count) / self.fps

    # ------------------------------------------------------------------------- operations

    def resample(self, fps: float) -> Motion:
        """The motion at a new frame rate, over the same time span.

        New frames are at ``k / fps`` seconds for every ``k`` with ``k / fps <= duration`` (so
        the last new frame may fall before the last original one). Each joint's rotation is
        interpolated by quaternion slerp between the two nearest original frames and the
        translation linearly. A new frame that lands on an original frame (within 1e-6 frames)
        copies it exactly, so 30 -> 60 -> 30 fps gives back the original frames.

        Interpolated poses are returned with angles in [0, pi]; copied frames keep theirs.

        Args:
            fps: the new frame rate, frames per second (> 0).
        """
        fps = _check_fps(fps, "the new fps")
        src_count = self.frame_count
        new_count = math.floor(self.duration * fps + _SNAP) + 1
        s = np.arange(new_count) / fps * self.fps  # position in source frames
        nearest = np.rint(s)
        s = np.clip(np.where(np.abs(s - nearest) < _SNAP, nearest, s), 0.0, src_count - 1)
        i0 = np.minimum(np.floor(s).astype(np.int64), src_count - 1)
        i1 = np.minimum(i0 + 1, src_count - 1)
        alpha = s - i0  # [N]
        quats = axis_angle_to_quaternion_np(self.poses)  # [T, 24, 4]
        poses = quaternion_to_axis_angle_np(quaternion_slerp_np(quats[i0], quats[i1], alpha[:, None]))
        exact = alpha == 0.0
        poses[exact] = self.poses[i0[exact]]
        trans = (1.0 - alpha)[:, None] * self.trans[i0] + alpha[:, None] * self.trans[i1]
        trans[exact] = self.trans[i0[exact]]
        return self._derive(poses, trans, fps=fps, resampled_from_fps=self.fps)

    def segments(self, length: int = 60, stride: int | None = None) -> list[Motion]:
        """Cut the motion into segments of ``length`` frames, starting every ``stride`` frames.

        Segments start at frames ``0, stride, 2 * stride, ...``; an incomplete tail is dropped, so
        a motion shorter than ``length`` gives an empty list. Translations are kept as they are
        (not re-centred). Each segment's ``source`` records ``segment_start`` (frames, relative to
        the motion this one was itself cut from, if any) and ``segment_length``.

        Args:
            length: frames per segment (>= 1).
            stride: frames between segment starts (>= 1); ``None`` means ``length``
                (back-to-back segments); less than ``length`` makes them overlap.
        """
        length = _check_positive_int(length, "length")
        stride = length if stride is None else _check_positive_int(stride, "stride")
        offset = int(self.source.get("segment_start", 0))
        out = []
        for start in range(0, self.frame_count - length + 1, stride):
            stop = start + length
            out.append(self._derive(self.poses[start:stop], self.trans[start:stop],
                                    segment_start=offset + start, segment_length=length))
        return out

    def with_lead_in(self, seconds: float, rest_pose: np.ndarray | None = None) -> tuple[Motion, int]:
        """Prepend frames that move the body from the rest pose into the first frame.

        drape's cloth simulator starts every garment draped on the body in the rest pose; a
        motion that starts in any other pose would tear the garment through the body in its first
        step. The lead-in gives the cloth time to follow: ``n = round(seconds * fps)`` frames
        whose joint rotations are slerped, per joint, from ``rest_pose`` to the first frame with a
        smoothstep ease ``w = 3u^2 - 2u^3``, ``u = i / n`` for lead-in frame ``i``. Frame 0 is
        exactly the rest pose, and frame ``n`` is the original first frame unchanged. The
        translation of every lead-in frame is the first frame's, so the body turns in place and
        does not slide horizontally into the motion. Drop the first ``n`` frames of the
        simulated result to get back to the original motion.

        Args:
            seconds: lead-in duration in seconds (>= 0; 0 returns this motion and 0).
            rest_pose: [24, 3] axis-angle rest pose (radians), or ``None`` for zeros, the SMPL
                T-pose.

        Returns:
            The new motion (``T + n`` frames; its source records ``lead_in_frames``) and ``n``.
        """
        try:
            seconds = float(seconds)
        except (TypeError, ValueError):
            raise InputError(f"lead-in seconds must be a number, got {seconds!r}") from None
        if not math.isfinite(seconds) or seconds < 0:
            raise InputError(f"lead-in seconds must be finite and >= 0, got {seconds}")
        if rest_pose is None:
            rest = np.zeros((JOINT_COUNT, 3))
        else:
            rest = _float_array(rest_pose, "rest_pose")
            if rest.shape == (POSE_DIM,):
                rest = rest.reshape(JOINT_COUNT, 3)
            if rest.shape != (JOINT_COUNT, 3):
                raise InputError(
                    f"rest_pose has shape {rest.shape}; expected [{JOINT_COUNT}, 3] axis-angle "
                    "(radians), or None for the SMPL T-pose"
                )
            _check_finite(rest[None], "rest_pose", "joints")
        n = round(seconds * self.fps)
        if n == 0:
            return self, 0
        u = np.arange(n) / n
        ease = u * u * (3.0 - 2.0 * u)  # [n]
        q_rest = axis_angle_to_quaternion_np(rest)[None]  # [1, 24, 4]
        q_first = axis_angle_to_quaternion_np(self.poses[0])[None]
        lead = quaternion_to_axis_angle_np(quaternion_slerp_np(q_rest, q_first, ease[:, None]))
        lead[0] = rest
        poses = np.concatenate([lead, self.poses], axis=0)
        trans = np.concatenate([np.repeat(self.trans[:1], n, axis=0), self.trans], axis=0)
        lead_total = n + int(self.source.get("lead_in_frames", 0))
        return self._derive(poses, trans, lead_in_frames=lead_total), n

    # ------------------------------------------------------------------------- files

    def save_npz(self, path: str | os.PathLike) -> None:
        """Write the motion to ``path`` (exactly that name) as an uncompressed ``.npz``.

        Layout (AMASS-like; no pickled objects):

        - ``poses`` [T, 72] float64, axis-angle radians, SMPL joint order;
        - ``trans`` [T, 3] float64, metres;
        - ``mocap_framerate`` scalar float64, frames per second;
        - ``label`` scalar int64; ``label_name`` scalar str;
        - ``source`` scalar str, the source dict as JSON.
        """
        arrays = {
            "poses": self.poses.reshape(self.frame_count, POSE_DIM),
            "trans": self.trans,
            "mocap_framerate": np.float64(self.fps),
            "label": np.int64(self.label),
            "label_name": np.str_(self.label_name),
            "source": np.str_(_source_json(self.source)),
        }
        with open(path, "wb") as f:
            np.savez(f, **arrays)

    @classmethod
    def load_npz(cls, path: str | os.PathLike) -> Motion:
        """Read a motion written by :meth:`save_npz` (loaded with ``allow_pickle=False``)."""
        if not os.path.isfile(path):
            raise InputError(f"motion file {os.fspath(path)!r} does not exist; pass the path of an .npz "
                             "written by Motion.save_npz")
        if not zipfile.is_zipfile(path):
            raise InputError(f"{os.fspath(path)!r} is not a readable .npz file (not a zip archive); pass "
                             "an .npz written by Motion.save_npz")
        try:
            with np.load(path, allow_pickle=False) as data:
                missing = [k for k in NPZ_KEYS if k not in data.files]
                if missing:
                    raise InputError(
                        f"{os.fspath(path)!r} lacks {missing} (it has {sorted(data.files)}); a drape "
                        f"motion .npz has {list(NPZ_KEYS)}. Raw AMASS files go through drape's AMASS "
                        "reader, not Motion.load_npz"
                    )
                arrays = {k: data[k] for k in NPZ_KEYS}
        except (zipfile.BadZipFile, OSError) as exc:
            raise InputError(f"{os.fspath(path)!r} is not a readable .npz file ({exc})") from exc
        except ValueError as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"{os.fspath(path)!r} holds pickled objects, which drape does not load; "
                             f"write motion files with Motion.save_npz ({exc})") from exc
        try:
            source = json.loads(str(arrays["source"]))
        except json.JSONDecodeError as exc:
            raise InputError(f"'source' in {os.fspath(path)!r} is not valid JSON ({exc})") from exc
        for key in ("mocap_framerate", "label", "label_name", "source"):
            if arrays[key].shape != ():
                raise InputError(f"'{key}' in {os.fspath(path)!r} has shape {arrays[key].shape}; expected a scalar")
        if not np.issubdtype(arrays["label"].dtype, np.integer):
            raise InputError(f"'label' in {os.fspath(path)!r} is {arrays['label'].dtype}; expected an integer")
        return cls(
            poses=arrays["poses"],
            trans=arrays["trans"],
            fps=float(arrays["mocap_framerate"]),
            label=int(arrays["label"]),
            label_name=str(arrays["label_name"]),
            source=source,
        )

    # ------------------------------------------------------------------------- helpers

    def _derive(self, poses: np.ndarray, trans: np.ndarray, fps: float | None = None, **source_updates) -> Motion:
        """A new motion with this one's label and its source updated by ``source_updates``."""
        return Motion(poses=poses, trans=trans, fps=self.fps if fps is None else fps, label=self.label,
                      label_name=self.label_name, source={**self.source, **source_updates})


def _float_array(value, name: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a numeric array, got {type(value).__name__} ({exc})") from None
    return arr


def _check_finite(arr: np.ndarray, name: str, inner: str) -> None:
    """Raise if ``arr`` [T, K, ...] has NaN/inf, saying how many and in which frames and columns."""
    bad = ~np.isfinite(arr)
    count = int(bad.sum())
    if count == 0:
        return
    where = np.argwhere(bad)
    frames = np.unique(where[:, 0])
    cols = np.unique(where[:, 1])

    def listed(values: np.ndarray) -> str:
        shown = ", ".join(str(int(v)) for v in values[:10])
        return f"[{shown}{', ...' if len(values) > 10 else ''}]"

    raise InputError(
        f"{name} has {count} non-finite value{'s' if count != 1 else ''} (NaN or inf) in "
        f"{len(frames)} frame{'s' if len(frames) != 1 else ''} {listed(frames)}, {inner} {listed(cols)}; "
        "fix or drop those frames before building a Motion"
    )


def _check_fps(fps, name: str) -> float:
    try:
        value = float(fps)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number of frames per second, got {fps!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise InputError(f"{name} must be finite and > 0 frames per second, got {fps!r}; pass e.g. 30.0")
    return value


def _check_positive_int(value, name: str) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 1:
        raise InputError(f"{name} must be an int >= 1 (frames), got {value!r}")
    return int(value)


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} is not JSON-serialisable")


def _source_json(source: dict) -> str:
    try:
        return json.dumps(source, default=_json_default, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"source must be JSON-serialisable (str/int/float/bool/None, lists and dicts with str "
            f"keys; numpy values are converted), got {source!r}: {exc}"
        ) from None
