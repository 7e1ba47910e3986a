"""Reading AMASS motions (``.npz``) as drape :class:`~datagen.motion.motion.Motion` objects, and label maps.

AMASS (Mahmood et al. 2019) stores each sequence as an ``.npz`` with

- ``poses`` [T, 156] axis-angle radians for SMPL-H's 52 joints (22 body joints, then 30 finger
  joints), [T, 165] for SMPL-X's 55 (22 body, jaw, two eyes, 30 finger joints) or [T, 72] for
  SMPL's 24; newer SMPL-X releases may instead hold ``root_orient`` [T, 3] and ``pose_body``
  [T, 63], which are read as well;
- ``trans`` [T, 3] root translation in metres;
- ``mocap_framerate`` (SMPL-H releases) or ``mocap_frame_rate`` (SMPL-X releases), frames per
  second;
- ``betas`` (the subject's shape in AMASS's body model; kept in ``Motion.source`` for reference,
  drape poses its own body), ``gender``, ``dmpls`` (ignored).

Joint conversion: the first 22 joints of SMPL, SMPL-H and SMPL-X are the same body joints in the
same order, so they are copied. SMPL's ``left_hand`` / ``right_hand`` (joints 22, 23) get the
identity rotation for SMPL-H and SMPL-X data (the finger joints are dropped; the hand then
continues the wrist, which is what a mitten-like SMPL hand can show). ``[T, 72]`` SMPL data is
kept as it is, hands included.

Up axis: AMASS's world is Z-up; the root orientation of every frame contains the +90 degree
rotation about X that stands the Y-up body model up. drape is Y-up, so with ``up_axis="z"`` (the
default) the root orientation ``R`` and the translation ``t`` of every frame become ``C @ R`` and
``C @ t`` with ``C`` the -90 degree rotation about X (``(x, y, z) -> (x, z, -y)``). A standing
AMASS frame then has a near-identity root orientation. The rotation turns the body about the
world origin, not about its pelvis joint ``J0``, so the whole motion sits ``(C - I) @ J0`` (a
constant of about 0.1 m for an adult) from where a rotation about the pelvis would put it; the
motion itself is unchanged. Pass ``up_axis="y"`` for data that is already Y-up.

Labels come from a label map file (:func:`load_label_map`): glob patterns on the motion's path,
first match wins. A motion that no pattern matches is an error unless ``label_name`` is given or
``allow_unlabelled=True`` (label ``-1``, name ``"unlabelled"``): a dataset must not take in
unlabelled data by accident.
"""

from __future__ import annotations

import fnmatch
import json
import logging
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import Any

import numpy as np

from datagen.errors import InputError
from datagen.motion.labels import label_index, label_vocabulary
from datagen.motion.motion import Motion
from datagen.geometry.rotations import axis_angle_to_matrix_np, matrix_to_axis_angle_np

__all__ = [
    "AMASS_POSE_WIDTHS",
    "UNLABELLED",
    "LabelMap",
    "load_label_map",
    "read_amass",
    "resolve_label",
    "up_axis_rotation",
]

logger = logging.getLogger(__name__)

AMASS_POSE_WIDTHS: dict[int, str] = {72: "smpl", 156: "smplh", 165: "smplx"}
"""Accepted widths of AMASS ``poses`` (3 x joints) and the body model each belongs to."""

UNLABELLED: tuple[int, str] = (-1, "unlabelled")
"""Label and label name of a motion read with ``allow_unlabelled=True`` that no pattern matched."""

_DISPLAY = {"smpl": "SMPL, 24 joints", "smplh": "SMPL-H, 52 joints", "smplx": "SMPL-X, 55 joints"}

_BODY_JOINTS = 22
"""Joints shared by SMPL, SMPL-H and SMPL-X (pelvis ... right_wrist)."""

_FRAMERATE_KEYS = ("mocap_framerate", "mocap_frame_rate")


def up_axis_rotation(up_axis: str) -> np.ndarray:
    """The rotation [3, 3] that takes a world with ``up_axis`` up ('y' or 'z') to drape's Y-up world.

    'y' gives the identity; 'z' gives -90 degrees about X, ``(x, y, z) -> (x, z, -y)``, which takes
    +Z (up) to +Y and -Y (the forward direction of a Z-up body whose left is +X) to +Z.
    """
    axis = str(up_axis).lower() if isinstance(up_axis, str) else up_axis
    if axis == "y":
        return np.eye(3)
    if axis == "z":
        return np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
    raise InputError(f"up_axis must be 'y' or 'z' (the axis that points up in the file), got {up_axis!r}")


# ----------------------------------------------------------------------------- labels

@dataclass(frozen=True)
class LabelMap:
    """Glob patterns on motion file paths and the label name each one gives.

    Attributes:
        patterns: ``(pattern, label_name)`` pairs in file order; the first pattern that matches
            wins. Patterns use :mod:`fnmatch` syntax (``*`` also matches ``/``) and are matched,
            case-insensitively, against the motion's path in POSIX form (as passed to the
            reader) and against its basename.
        vocabulary: label names in class order: drape's :data:`~datagen.motion.labels.LABELS`
            followed by the map's other names in file order (:func:`label_vocabulary`).
        path: the file the map was read from, or ``None``.
    """

    patterns: tuple[tuple[str, str], ...]
    vocabulary: tuple[str, ...]
    path: str | None = None

    @classmethod
    def from_patterns(cls, patterns: dict[str, str], path: str | None = None) -> LabelMap:
        """A map from ``{pattern: label_name}`` (insertion order is the match order)."""
        where = f"label map {path!r}" if path else "label map"
        if not isinstance(patterns, dict) or not patterns:
            raise InputError(f"{where}: 'patterns' must be a non-empty mapping "
                             "{\"glob pattern\": \"label_name\", ...}")
        pairs = []
        for pattern, name in patterns.items():
            if not isinstance(pattern, str) or not pattern:
                raise InputError(f"{where}: pattern {pattern!r} must be a non-empty string")
            if not isinstance(name, str) or not name:
                raise InputError(f"{where}: pattern {pattern!r} maps to {name!r}; a label name must be "
                                 "a non-empty string such as \"walk\"")
            pairs.append((pattern, name))
        vocabulary = label_vocabulary([name for _, name in pairs])
        return cls(patterns=tuple(pairs), vocabulary=vocabulary, path=path)

    def match(self, path: str | os.PathLike) -> str | None:
        """The label name of the first pattern matching ``path`` (or its basename), else ``None``."""
        posix = PurePath(os.fspath(path)).as_posix().lower()
        base = posix.rsplit("/", 1)[-1]
        for pattern, name in self.patterns:
            p = pattern.lower()
            if fnmatch.fnmatchcase(posix, p) or fnmatch.fnmatchcase(base, p):
                return name
        return None


def load_label_map(path: str | os.PathLike) -> LabelMap:
    """Read a label map from a JSON (``.json``) or YAML (``.yaml``/``.yml``) file.

    The file holds ``{"patterns": {"glob pattern": "label_name", ...}}``, e.g.::

        patterns:
          "*/CMU/*walk*": walk
          "*_jog*": run

    Patterns are tried in file order and the first match wins (see :class:`LabelMap`). The
    integer label of a name is its index in :attr:`LabelMap.vocabulary`.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"label map file {os.fspath(path)!r} does not exist; pass a .json or .yaml file "
                         "holding {\"patterns\": {\"glob pattern\": \"label_name\", ...}}")
    suffix = p.suffix.lower()
    text = p.read_text(encoding="utf-8")
    try:
        if suffix == ".json":
            data = json.loads(text)
        elif suffix in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
        else:
            raise InputError(f"label map file {os.fspath(path)!r} must end in .json, .yaml or .yml")
    except (json.JSONDecodeError, ValueError) as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(f"label map file {os.fspath(path)!r} is not valid JSON: {exc}") from exc
    except Exception as exc:  # yaml.YAMLError (pyyaml is imported lazily)
        raise InputError(f"label map file {os.fspath(path)!r} is not valid YAML: {exc}") from exc
    if not isinstance(data, dict) or "patterns" not in data:
        raise InputError(f"label map file {os.fspath(path)!r} must hold a mapping with a 'patterns' key: "
                         "{\"patterns\": {\"glob pattern\": \"label_name\", ...}}")
    unknown = sorted(set(data) - {"patterns"})
    if unknown:
        raise InputError(f"label map file {os.fspath(path)!r} has unknown keys {unknown}; only 'patterns' is read")
    return LabelMap.from_patterns(data["patterns"], path=os.fspath(path))


def _as_label_map(label_map: LabelMap | str | os.PathLike | None) -> LabelMap | None:
    if label_map is None or isinstance(label_map, LabelMap):
        return label_map
    if isinstance(label_map, (str, os.PathLike)):
        return load_label_map(label_map)
    raise InputError(f"label_map must be a LabelMap, the path of a label map file or None, got "
                     f"{type(label_map).__name__}")


def resolve_label(path: str | os.PathLike, label_map: LabelMap | str | os.PathLike | None = None, *,
                  label_name: str | None = None, label: int | None = None,
                  allow_unlabelled: bool = False) -> tuple[int, str]:
    """The ``(label, label_name)`` of the motion file at ``path``.

    In order of precedence:

    1. ``label_name`` given: that name, with ``label`` if given, else its index in the map's
       vocabulary (or in :func:`label_vocabulary` ``((label_name,))`` without a map: drape's
       labels, then the new name);
    2. the first pattern of ``label_map`` that matches ``path``;
    3. ``allow_unlabelled=True``: :data:`UNLABELLED` ``(-1, "unlabelled")``;
    4. otherwise :class:`~datagen.errors.InputError`, naming the file and the map.
    """
    label_map = _as_label_map(label_map)
    if label is not None and label_name is None:
        raise InputError(f"label={label!r} was given without label_name; pass both (or only label_name)")
    if label_name is not None:
        if not isinstance(label_name, str) or not label_name:
            raise InputError(f"label_name must be a non-empty string, got {label_name!r}")
        if label is not None:
            if isinstance(label, (bool, np.bool_)) or not isinstance(label, (int, np.integer)):
                raise InputError(f"label must be an int, got {label!r}")
            return int(label), label_name
        vocabulary = label_vocabulary((label_map.vocabulary if label_map else ()) + (label_name,))
        return label_index(label_name, vocabulary), label_name
    if label_map is not None:
        name = label_map.match(path)
        if name is not None:
            return label_index(name, label_map.vocabulary), name
    if allow_unlabelled:
        return UNLABELLED
    if label_map is None:
        raise InputError(f"no label for {os.fspath(path)!r}: pass label_map (a pattern file), label_name=..., "
                         "or allow_unlabelled=True to read it as label -1 'unlabelled'")
    shown = ", ".join(repr(p) for p, _ in label_map.patterns[:8]) + (", ..." if len(label_map.patterns) > 8 else "")
    raise InputError(f"no pattern of label map {label_map.path or '(in memory)'} matches {os.fspath(path)!r} "
                     f"(patterns: {shown}); add a pattern for it, pass label_name=..., or pass "
                     "allow_unlabelled=True to read it as label -1 'unlabelled'")


# ----------------------------------------------------------------------------- AMASS

def read_amass(path: str | os.PathLike, label_map: LabelMap | str | os.PathLike | None = None, *,
               label_name: str | None = None, fps: float | None = None, up_axis: str = "z",
               allow_unlabelled: bool = False) -> Motion:
    """Read an AMASS ``.npz`` as a drape motion (SMPL's 24 joints, Y up).

    Args:
        path: the AMASS ``.npz`` (see the module docstring for the layout).
        label_map: a :class:`LabelMap` or the path of a label map file (:func:`load_label_map`).
        label_name: the label, overriding the map (see :func:`resolve_label`).
        fps: resample to this many frames per second (:meth:`Motion.resample`); ``None`` keeps
            the file's rate.
        up_axis: the file's up axis: ``'z'`` (AMASS, default) or ``'y'``.
        allow_unlabelled: read a file without a label as label -1 ``"unlabelled"`` instead of
            raising.

    Returns:
        The motion; ``source`` holds ``kind="file"``, ``format="amass"``, ``path``, ``body_model``
        (``"smpl"``, ``"smplh"`` or ``"smplx"``), ``betas`` (a list, or ``None`` when the file
        has none), ``gender`` (when readable), ``up_axis`` and ``fps_original``.
    """
    C = up_axis_rotation(up_axis)
    name = os.fspath(path)
    arrays = _load_amass_arrays(name)
    label, label_name = resolve_label(path, label_map, label_name=label_name, allow_unlabelled=allow_unlabelled)
    poses, body_model = _amass_poses(arrays, name)
    trans = _float_field(arrays, "trans", name)
    if trans.ndim != 2 or trans.shape[1] != 3 or trans.shape[0] != poses.shape[0]:
        raise InputError(f"AMASS file {name!r}: 'trans' has shape {trans.shape}; expected [T={poses.shape[0]}, 3] "
                         "root translations in metres, one per pose frame")
    rate = _framerate(arrays, name)
    for key, arr in (("poses", poses), ("trans", trans)):
        if not np.all(np.isfinite(arr)):
            frames = np.unique(np.argwhere(~np.isfinite(arr.reshape(arr.shape[0], -1)))[:, 0])
            raise InputError(f"AMASS file {name!r}: '{key}' has non-finite values (NaN or inf) in "
                             f"{len(frames)} frame(s), first {frames[:10].tolist()}; the file is damaged, "
                             "re-download it or drop those frames")
    if body_model != "smpl":
        hands = np.zeros((poses.shape[0], 2, 3))
        poses = np.concatenate([poses[:, :_BODY_JOINTS], hands], axis=1)
    if up_axis.lower() == "z":
        root = C @ axis_angle_to_matrix_np(poses[:, 0])
        poses = poses.copy()
        poses[:, 0] = matrix_to_axis_angle_np(root)
        trans = trans @ C.T
    betas = None
    if "betas" in arrays:
        b = np.asarray(arrays["betas"], dtype=np.float64).reshape(-1)
        betas = [float(x) for x in b] if np.all(np.isfinite(b)) else None
    source: dict[str, Any] = {
        "kind": "file", "format": "amass", "path": name, "body_model": body_model, "betas": betas,
        "up_axis": up_axis.lower(), "fps_original": rate,
    }
    if "gender" in arrays:
        source["gender"] = arrays["gender"]
    motion = Motion(poses=poses, trans=trans, fps=rate, label=label, label_name=label_name, source=source)
    logger.info("read AMASS %s: %d frames at %g fps (%s), label %d %r", name, motion.frame_count, rate,
                body_model, label, label_name)
    if fps is not None:
        motion = motion.resample(fps)
    return motion


def _load_amass_arrays(name: str) -> dict[str, Any]:
    """The arrays of an AMASS npz (``gender`` as a str when readable), loaded without pickles."""
    if not os.path.isfile(name):
        raise InputError(f"AMASS file {name!r} does not exist; pass the path of an AMASS .npz "
                         "(e.g. CMU/01/01_01_poses.npz)")
    if not zipfile.is_zipfile(name):
        with open(name, "rb") as fh:
            head = fh.read(64).lstrip()
        if head.startswith(b"HIERARCHY"):
            raise InputError(f"{name!r} is named .npz but is BVH text, not a NumPy .npz archive: give it the .bvh "
                             "suffix and import it again")
        raise InputError(f"{name!r} is not a NumPy .npz file (an .npz is a zip archive; this file is not one); pass "
                         "an AMASS .npz")
    out: dict[str, Any] = {}
    try:
        with np.load(name, allow_pickle=False) as data:
            files = list(data.files)
            for key in files:
                if key == "gender":
                    try:
                        g = data[key]
                        out[key] = g.item().decode() if isinstance(g.item(), bytes) else str(g.item())
                    except ValueError:  # stored as a pickled object: not needed, skip it
                        pass
                elif key in ("poses", "trans", "betas", "root_orient", "pose_body", *_FRAMERATE_KEYS):
                    out[key] = data[key]
    except (zipfile.BadZipFile, OSError) as exc:
        raise InputError(f"{name!r} is not a readable .npz file ({exc})") from exc
    except ValueError as exc:
        raise InputError(f"AMASS file {name!r} holds a needed array as a pickled object, which drape does "
                         f"not load ({exc}); re-save it with plain numeric arrays") from exc
    out["__files__"] = files
    return out


def _float_field(arrays: dict, key: str, name: str) -> np.ndarray:
    if key not in arrays:
        raise InputError(f"AMASS file {name!r} has no '{key}' array (it has {sorted(arrays['__files__'])}); an "
                         "AMASS motion has 'poses' [T, 156], 'trans' [T, 3], 'mocap_framerate' and 'betas'")
    try:
        return np.asarray(arrays[key], dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"AMASS file {name!r}: '{key}' is not numeric ({exc})") from None


def _amass_poses(arrays: dict, name: str) -> tuple[np.ndarray, str]:
    """Poses [T, J, 3] and the body model name from ``poses`` or ``root_orient`` + ``pose_body``."""
    if "poses" not in arrays and "root_orient" in arrays and "pose_body" in arrays:
        root = _float_field(arrays, "root_orient", name)
        body = _float_field(arrays, "pose_body", name)
        if root.ndim != 2 or root.shape[1] != 3 or body.ndim != 2 or body.shape[1] != 63 or len(root) != len(body):
            raise InputError(f"AMASS file {name!r}: 'root_orient' {root.shape} and 'pose_body' {body.shape} must be "
                             "[T, 3] and [T, 63] with the same T")
        poses = np.concatenate([root, body], axis=1)
        kind = "smplx"
    else:
        poses = _float_field(arrays, "poses", name)
        if poses.ndim != 2 or poses.shape[1] not in AMASS_POSE_WIDTHS:
            widths = ", ".join(f"{w} ({_DISPLAY[m]})" for w, m in AMASS_POSE_WIDTHS.items())
            raise InputError(f"AMASS file {name!r}: 'poses' has shape {poses.shape}; expected [T, W] with W one of "
                             f"{widths}: axis-angle radians, 3 per joint, body joints first")
        kind = AMASS_POSE_WIDTHS[poses.shape[1]]
    if poses.shape[0] == 0:
        raise InputError(f"AMASS file {name!r} has 0 frames")
    return poses.reshape(poses.shape[0], -1, 3), kind


def _framerate(arrays: dict, name: str) -> float:
    for key in _FRAMERATE_KEYS:
        if key in arrays:
            try:
                rate = float(np.asarray(arrays[key]).reshape(-1)[0])
            except (TypeError, ValueError, IndexError):
                rate = float("nan")
            if not np.isfinite(rate) or rate <= 0:
                raise InputError(f"AMASS file {name!r}: '{key}' is {arrays[key]!r}; expected frames per second > 0")
            return rate
    raise InputError(f"AMASS file {name!r} has no frame rate: neither 'mocap_framerate' (SMPL-H AMASS) nor "
                     f"'mocap_frame_rate' (SMPL-X AMASS); it has {sorted(arrays['__files__'])}")
