"""Reading BVH motion capture onto SMPL's 24 joints, and writing motions as BVH.

Reading (:func:`read_bvh`)
--------------------------
The skeleton (joint names, parents, offsets, channels) is parsed with :mod:`bvhio`; the frame
block is parsed here with numpy, in float64. BVH conventions used: a joint's channels are applied
in the order listed, rotations as intrinsic Euler angles in degrees (``Zrotation Xrotation
Yrotation`` is ``R = Rz @ Rx @ Ry``, column vectors), and position channels *replace* the
matching components of the joint's ``OFFSET`` (as :mod:`bvhio` reads them). In the rest pose
(all channels zero) every joint frame is aligned with the world.

Retargeting (first order): BVH joints are mapped onto SMPL joints by name (built-in maps for
SMPL's own names, CMU mocap names and Mixamo-style names; a map file or dict overrides them).
Each mapped BVH joint's global rotation, which is its rotation relative to the BVH rest pose,
becomes the global rotation of its SMPL joint; SMPL joints that nothing maps to keep their
parent's global rotation (identity local rotation); the SMPL local rotations are then
``R_local = R_global(parent)^T R_global(joint)`` along SMPL's parents. This is exact when the BVH
rest pose and SMPL's rest pose are the same posture (both T-poses with bones pointing the same
way, the body facing +Z with its left on +X), which is the case for CMU and Mixamo BVH and
drape's body; for other rest poses the result is off by the difference of the rest poses and no
correction is attempted. BVH joints between mapped ones (CMU's ``LHipJoint``, ``Neck1``) fold
their rotation into the next mapped joint.

Unmapped joints: a BVH joint that neither the given map nor the built-in map names raises an
:class:`~datagen.errors.InputError` naming it, unless it lies below a joint mapped to an SMPL
extremity (``head``, wrists, hands, ankles, feet) and has no mapped joint below it (fingers, toes,
head tops): those are ignored silently. Map a joint to ``null`` / ``None`` to ignore it
explicitly.

Units: ``scale`` multiplies every BVH length to give metres. ``scale=None`` guesses it from the
rest skeleton's height (joints and end sites along the up axis): of metres (1), centimetres
(0.01), inches (0.0254) and CMU's ASF units as converted by cgspeed (0.0254 / 0.45 = 0.056444),
the one that makes the height 1.2 to 2.2 m; the guess is logged.

Root translation: ``trans[t] = scale * (p[t] - p_rest)`` (rotated to Y-up), where ``p`` is the
world position of the BVH joint mapped to SMPL's pelvis and ``p_rest`` its position in the rest
pose (the root's ``OFFSET`` for the usual root hips): the displacement of the root from where the
BVH's rest pose puts it, which is what drape's ``trans`` is for SMPL's pelvis. A file whose root
``OFFSET`` is zero (CMU) thus gives absolute hip positions (hips about 1 m up); one whose
``OFFSET`` is the standing hip height (Mixamo) gives near-zero vertical translation when standing.

Writing (:func:`write_bvh`)
---------------------------
The SMPL skeleton with SMPL's joint names, offsets from the body's rest joints (metres), a root
with ``Xposition Yposition Zposition Zrotation Xrotation Yrotation`` channels (position = rest
pelvis + ``trans``) and ``Zrotation Xrotation Yrotation`` for every other joint, ``Frame Time =
1 / fps``. The text is written here (float64 Euler angles from scipy, 9 significant digits)
rather than with :func:`bvhio.writeBvh`, whose float32 glm quaternions lose about 1e-4 rad near
gimbal lock; the result is read back by :mod:`bvhio` and by :func:`read_bvh` (which maps SMPL's
names onto themselves).
"""

from __future__ import annotations

import io
import json
import logging
import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from datagen.body.skeleton import JOINT_COUNT, SMPL_JOINT_NAMES, SMPL_PARENTS
from datagen.errors import InputError
from datagen.motion.amass import LabelMap, resolve_label, up_axis_rotation
from datagen.motion.motion import Motion
from datagen.geometry.rotations import axis_angle_to_matrix_np, matrix_to_axis_angle_np

__all__ = [
    "BUILTIN_JOINT_MAPS",
    "UNIT_SCALES",
    "guess_scale",
    "load_joint_map",
    "read_bvh",
    "write_bvh",
]

logger = logging.getLogger(__name__)

UNIT_SCALES: dict[str, float] = {"m": 1.0, "cm": 0.01, "in": 0.0254, "cmu": 0.0254 / 0.45}
"""Candidate BVH length units (metres per unit) for :func:`guess_scale`; ``cmu`` is CMU's ASF unit."""

HEIGHT_RANGE_M: tuple[float, float] = (1.2, 2.2)
"""A guessed scale must put the rest skeleton's height (metres) in this range."""

_EXTREMITIES = frozenset({"head", "left_wrist", "right_wrist", "left_hand", "right_hand",
                          "left_ankle", "right_ankle", "left_foot", "right_foot"})
"""SMPL joints below whose mapped BVH joint unknown leaf joints (fingers, toes) are ignored."""


LIMB_JOINTS = ("left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle", "left_shoulder",
               "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist")
"""SMPL joints a BVH must drive: without them an arm or leg would hang stiffly from its parent."""


def _sided(pairs: dict[str, str | None]) -> dict[str, str | None]:
    """Expand ``{"{S}Arm": "{s}_shoulder"}`` to the Left/left and Right/right entries."""
    out: dict[str, str | None] = {}
    for key, value in pairs.items():
        for S, s, L in (("Left", "left", "L"), ("Right", "right", "R")):
            out[key.format(S=S, L=L)] = None if value is None else value.format(s=s)
    return out


_CMU_MAP: dict[str, str | None] = {
    "Hips": "pelvis", "LowerBack": "spine1", "Spine": "spine2", "Spine1": "spine3",
    "Neck": "neck", "Neck1": None, "Head": "head",
    **_sided({
        "{L}HipJoint": None, "{S}UpLeg": "{s}_hip", "{S}Leg": "{s}_knee", "{S}Foot": "{s}_ankle",
        "{S}ToeBase": "{s}_foot", "{S}Shoulder": "{s}_collar", "{S}Arm": "{s}_shoulder",
        "{S}ForeArm": "{s}_elbow", "{S}Hand": "{s}_wrist", "{S}FingerBase": "{s}_hand",
        "{S}HandIndex1": None, "{L}Thumb": None,
    }),
}

_MIXAMO_MAP: dict[str, str | None] = {
    "Hips": "pelvis", "Spine": "spine1", "Spine1": "spine2", "Spine2": "spine3",
    "Neck": "neck", "Head": "head", "HeadTop_End": None,
    **_sided({
        "{S}UpLeg": "{s}_hip", "{S}Leg": "{s}_knee", "{S}Foot": "{s}_ankle", "{S}ToeBase": "{s}_foot",
        "{S}Toe_End": None, "{S}Shoulder": "{s}_collar", "{S}Arm": "{s}_shoulder",
        "{S}ForeArm": "{s}_elbow", "{S}Hand": "{s}_wrist",
    }),
}

BUILTIN_JOINT_MAPS: dict[str, dict[str, str | None]] = {
    "smpl": {name: name for name in SMPL_JOINT_NAMES},
    "cmu": _CMU_MAP,
    "mixamo": _MIXAMO_MAP,
}
"""BVH joint name -> SMPL joint name (``None``: ignored) for known skeletons. :func:`read_bvh`
picks the one naming most of the file's joints (a namespace such as ``mixamorig:`` is stripped
before looking names up here)."""


# ----------------------------------------------------------------------------- parsing

@dataclass(frozen=True)
class _Skeleton:
    names: list[str]
    parents: np.ndarray          # [B], -1 for the root
    offsets: np.ndarray          # [B, 3] file units
    channels: list[list[str]]
    end_sites: np.ndarray        # [B, 3] end-site offset of leaves (NaN where none)
    frame_time: float
    frames: np.ndarray           # [T, C] float64


def _import_bvhio():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PendingDeprecationWarning)  # bvhio's "import glm"
        import bvhio
    return bvhio


def _parse_bvh(path: str) -> _Skeleton:
    bvhio = _import_bvhio()

    if not os.path.isfile(path):
        raise InputError(f"BVH file {path!r} does not exist; pass the path of a .bvh file")
    with open(path, "rb") as f:
        magic = f.read(4)
    if magic == b"PK\x03\x04":  # a zip archive: numpy's .npz (an AMASS motion, or drape's own)
        raise InputError(f"{path!r} is named .bvh but is a NumPy .npz archive (a zip file), not BVH text: if it is "
                         "an AMASS motion, give it the .npz suffix and import it again")
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.read().splitlines()
    stripped = [ln.strip() for ln in lines]
    if not stripped or "HIERARCHY" not in stripped[:5]:
        raise InputError(f"{path!r} is not a BVH file: it must start with a 'HIERARCHY' line")
    try:
        motion_at = stripped.index("MOTION")
    except ValueError:
        raise InputError(f"BVH file {path!r} has no 'MOTION' line; the file is truncated or not a BVH") from None
    header = [(i, s) for i, s in enumerate(stripped[motion_at + 1:], start=motion_at + 1) if s][:2]
    if (len(header) < 2 or not header[0][1].startswith("Frames:") or len(header[0][1].split()) != 2
            or not header[1][1].startswith("Frame Time:") or len(header[1][1].split()) != 3):
        raise InputError(f"BVH file {path!r}: 'MOTION' must be followed by 'Frames: N' and 'Frame Time: seconds'")
    try:
        declared = int(header[0][1].split()[1])
        frame_time = float(header[1][1].split()[2])
    except ValueError:
        raise InputError(f"BVH file {path!r}: cannot read the frame count or frame time from "
                         f"{header[0][1]!r} / {header[1][1]!r}") from None
    if not math.isfinite(frame_time) or frame_time <= 0:
        raise InputError(f"BVH file {path!r}: Frame Time is {frame_time}; it must be > 0 seconds per frame")
    try:
        container = bvhio.readAsBvh(path, loadKeyFrames=False)
    except (SyntaxError, ValueError, IndexError) as exc:
        msg = exc.msg if isinstance(exc, SyntaxError) else str(exc)  # bvhio's line numbers are unreliable
        raise InputError(f"BVH file {path!r} has a malformed HIERARCHY ({msg})") from None

    names, parents, offsets, channels, ends = [], [], [], [], []

    def walk(joint, parent: int) -> None:
        index = len(names)
        names.append(str(joint.Name))
        parents.append(parent)
        offsets.append([joint.Offset.x, joint.Offset.y, joint.Offset.z])
        channels.append(list(joint.Channels))
        ends.append([joint.EndSite.x, joint.EndSite.y, joint.EndSite.z] if not joint.Children else [np.nan] * 3)
        for child in joint.Children:
            walk(child, index)

    walk(container.Root, -1)
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise InputError(f"BVH file {path!r} names joints {dupes} more than once; joint names must be unique")
    width = sum(len(c) for c in channels)
    rows = [s for s in stripped[header[1][0] + 1:] if s]
    counts = [len(r.split()) for r in rows]
    bad = [i for i, c in enumerate(counts) if c != width]
    if bad:
        raise InputError(f"BVH file {path!r}: frame {bad[0]} has {counts[bad[0]]} values but the HIERARCHY declares "
                         f"{width} channels ({len(bad)} frame line(s) are wrong); the file is damaged")
    if not rows:
        raise InputError(f"BVH file {path!r} has no frames")
    try:
        frames = np.array(" ".join(rows).split(), dtype=np.float64).reshape(len(rows), width)
    except ValueError as exc:
        raise InputError(f"BVH file {path!r}: the MOTION block holds a value that is not a number ({exc})") from None
    if not np.all(np.isfinite(frames)):
        bad_frames = np.unique(np.argwhere(~np.isfinite(frames))[:, 0])
        raise InputError(f"BVH file {path!r} has non-finite values in {len(bad_frames)} frame(s), first "
                         f"{bad_frames[:10].tolist()}; fix or drop those frames")
    if len(rows) != declared:
        logger.warning("BVH file %s declares %d frames but holds %d; reading %d", path, declared, len(rows), len(rows))
    return _Skeleton(names, np.array(parents, dtype=np.int64), np.array(offsets, dtype=np.float64), channels,
                     np.array(ends, dtype=np.float64), frame_time, frames)


def _local_transforms(skel: _Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations [T, B, 3, 3] and translations [T, B, 3] (file units) of every joint."""
    T, B = skel.frames.shape[0], len(skel.names)
    rot = np.broadcast_to(np.eye(3), (T, B, 3, 3)).copy()
    pos = np.broadcast_to(skel.offsets, (T, B, 3)).copy()
    column = 0
    for b, chans in enumerate(skel.channels):
        order, angle_cols = "", []
        for k, ch in enumerate(chans):
            axis, kind = ch[:1].upper(), ch[1:].lower()
            if axis not in "XYZ" or kind not in ("rotation", "position"):
                raise InputError(f"BVH joint {skel.names[b]!r} has an unknown channel {ch!r}; channels are "
                                 "Xposition/Yposition/Zposition/Xrotation/Yrotation/Zrotation")
            if kind == "position":
                pos[:, b, "XYZ".index(axis)] = skel.frames[:, column + k]
            else:
                order += axis
                angle_cols.append(column + k)
        if order:
            if len(set(order)) != len(order):
                raise InputError(f"BVH joint {skel.names[b]!r} repeats a rotation channel ({chans})")
            rot[:, b] = Rotation.from_euler(order, skel.frames[:, angle_cols], degrees=True).as_matrix()
        column += len(chans)
    return rot, pos


def _rest_positions(skel: _Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Rest-pose world positions [B, 3] of the joints and [E, 3] of the end sites (file units)."""
    P = np.zeros_like(skel.offsets)
    for b, p in enumerate(skel.parents):
        P[b] = skel.offsets[b] + (P[p] if p >= 0 else 0.0)
    has_end = np.all(np.isfinite(skel.end_sites), axis=1)
    return P, P[has_end] + skel.end_sites[has_end]


def guess_scale(height: float) -> float:
    """Metres per unit, among :data:`UNIT_SCALES`, that make a skeleton ``height`` units tall 1.2-2.2 m.

    Raises :class:`~datagen.errors.InputError` when none does (pass ``scale=`` instead).
    """
    lo, hi = HEIGHT_RANGE_M
    fits = [(unit, s) for unit, s in UNIT_SCALES.items() if lo <= height * s <= hi]
    if not fits:
        tried = ", ".join(f"{unit}: {height * s:.3g} m" for unit, s in UNIT_SCALES.items())
        raise InputError(f"cannot guess the BVH's length unit: its rest skeleton is {height:.4g} units tall, and no "
                         f"unit makes that {lo}-{hi} m ({tried}); pass scale= (metres per file unit)")
    unit, s = fits[0]
    logger.info("BVH rest skeleton is %.4g units tall: guessed unit %r (scale %g m/unit, height %.3f m)",
                height, unit, s, height * s)
    return s


# ----------------------------------------------------------------------------- joint maps

def load_joint_map(path: str | os.PathLike) -> dict[str, str | None]:
    """A joint map ``{"bvh_joint_name": "smpl_joint_name" | null, ...}`` from a JSON or YAML file."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"joint map file {os.fspath(path)!r} does not exist; pass a .json or .yaml file holding "
                         "{\"BvhJointName\": \"smpl_joint_name\", ...}")
    text = p.read_text(encoding="utf-8")
    suffix = p.suffix.lower()
    if suffix == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputError(f"joint map file {os.fspath(path)!r} is not valid JSON: {exc}") from None
    elif suffix in (".yaml", ".yml"):
        import yaml

        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            raise InputError(f"joint map file {os.fspath(path)!r} is not valid YAML: {exc}") from None
    else:
        raise InputError(f"joint map file {os.fspath(path)!r} must end in .json, .yaml or .yml")
    return _check_joint_map(data, os.fspath(path))


def _check_joint_map(data: Any, where: str) -> dict[str, str | None]:
    if not isinstance(data, dict):
        raise InputError(f"joint map {where} must be a mapping {{\"BvhJointName\": \"smpl_joint_name\" or null}}, "
                         f"got {type(data).__name__}")
    for key, value in data.items():
        if not isinstance(key, str) or not key:
            raise InputError(f"joint map {where}: key {key!r} must be a BVH joint name")
        if value is not None and value not in SMPL_JOINT_NAMES:
            raise InputError(f"joint map {where}: {key!r} maps to {value!r}, which is not an SMPL joint; use one of "
                             f"{', '.join(SMPL_JOINT_NAMES)}, or null to ignore the joint")
    return dict(data)


def _strip_namespace(name: str) -> str:
    return name.rsplit(":", 1)[-1]


def _resolve_joint_map(skel: _Skeleton, joint_map: dict[str, str | None] | str | os.PathLike | None,
                       path: str) -> tuple[dict[int, int], list[str], str]:
    """SMPL joint index -> BVH joint index, the ignored BVH joints and the built-in map used."""
    if joint_map is None:
        user: dict[str, str | None] = {}
    elif isinstance(joint_map, dict):
        user = _check_joint_map(joint_map, "(dict)")
    elif isinstance(joint_map, (str, os.PathLike)):
        user = load_joint_map(joint_map)
    else:
        raise InputError(f"joint_map must be a dict, the path of a joint map file or None, got {type(joint_map).__name__}")
    names = skel.names
    builtin_name, builtin = max(BUILTIN_JOINT_MAPS.items(),
                                key=lambda kv: sum(_strip_namespace(n) in kv[1] for n in names))
    unused = sorted(set(user) - set(names))
    if unused:
        logger.warning("joint map names %s, which %s does not have", unused, path)
    target: dict[int, str | None] = {}
    unknown: list[int] = []
    for b, name in enumerate(names):
        if name in user:
            target[b] = user[name]
        elif _strip_namespace(name) in builtin:
            target[b] = builtin[_strip_namespace(name)]
        else:
            unknown.append(b)
    smpl_to_bvh: dict[int, int] = {}
    for b, smpl in target.items():
        if smpl is None:
            continue
        k = SMPL_JOINT_NAMES.index(smpl)
        if k in smpl_to_bvh:
            raise InputError(f"BVH joints {names[smpl_to_bvh[k]]!r} and {names[b]!r} of {path!r} both map to SMPL "
                             f"joint {smpl!r}; map one of them to another joint or to null in the joint map")
        smpl_to_bvh[k] = b
    children: dict[int, list[int]] = {}
    for b, p in enumerate(skel.parents):
        children.setdefault(int(p), []).append(b)

    def ancestors(b: int):
        p = int(skel.parents[b])
        while p >= 0:
            yield p
            p = int(skel.parents[p])

    def has_mapped_below(b: int) -> bool:
        return any(target.get(c) is not None or has_mapped_below(c) for c in children.get(b, []))

    errors, ignored = [], [names[b] for b, s in target.items() if s is None]
    for b in unknown:
        under_extremity = any(target.get(a) in _EXTREMITIES for a in ancestors(b))
        if under_extremity and not has_mapped_below(b):
            ignored.append(names[b])
        else:
            errors.append(names[b])
    if errors:
        raise InputError(
            f"BVH file {path!r} has joints that no joint map names: {errors} (the built-in {builtin_name!r} map was "
            "used). Pass joint_map= a dict or a JSON/YAML file mapping each to an SMPL joint or to null to ignore it, "
            f"e.g. {{\"{errors[0]}\": \"spine2\"}} or {{\"{errors[0]}\": null}}; SMPL joints: {', '.join(SMPL_JOINT_NAMES)}"
        )
    if 0 not in smpl_to_bvh:
        raise InputError(f"no joint of BVH file {path!r} maps to SMPL's 'pelvis' (the root); map the hips joint to "
                         "\"pelvis\" in the joint map")
    missing = [n for n in LIMB_JOINTS if SMPL_JOINT_NAMES.index(n) not in smpl_to_bvh]
    if missing:  # a limb without its joints would be carried stiffly by its parent: refuse, do not guess
        raise InputError(f"BVH file {path!r} has no joint for SMPL's {', '.join(missing)}: every hip, knee, ankle, "
                         "shoulder, elbow and wrist must come from the file (feet, hands, collars and extra spine "
                         "joints may be missing). If they are there under other names, map them with a joint map")
    # Each mapped joint must lie below the BVH joint of its nearest mapped SMPL ancestor.
    for k, b in smpl_to_bvh.items():
        a = SMPL_PARENTS[k]
        while a >= 0 and a not in smpl_to_bvh:
            a = SMPL_PARENTS[a]
        if a >= 0 and smpl_to_bvh[a] not in set(ancestors(b)):
            raise InputError(f"BVH joint {names[b]!r} maps to SMPL {SMPL_JOINT_NAMES[k]!r} but is not below "
                             f"{names[smpl_to_bvh[a]]!r}, which maps to its SMPL ancestor {SMPL_JOINT_NAMES[a]!r}; "
                             "check the joint map (left/right swapped?)")
    return smpl_to_bvh, ignored, builtin_name


# ----------------------------------------------------------------------------- reading

def read_bvh(path: str | os.PathLike, joint_map: dict[str, str | None] | str | os.PathLike | None = None, *,
             scale: float | None = None, up_axis: str = "y", label_name: str | None = None,
             label: int | None = None, fps: float | None = None,
             label_map: LabelMap | str | os.PathLike | None = None, allow_unlabelled: bool = False) -> Motion:
    """Read a BVH file and retarget it onto SMPL's 24 joints (see the module docstring).

    Args:
        path: the ``.bvh`` file.
        joint_map: ``{"BvhJointName": "smpl_joint_name" | None}`` as a dict or a JSON/YAML file;
            its entries override the built-in map (:data:`BUILTIN_JOINT_MAPS`).
        scale: metres per file unit; ``None`` guesses it (:func:`guess_scale`).
        up_axis: the file's up axis, ``'y'`` (default) or ``'z'`` (rotated to drape's Y up).
        label_name, label, label_map, allow_unlabelled: the motion's label, as in
            :func:`datagen.motion.amass.resolve_label`.
        fps: resample to this rate; ``None`` keeps the file's ``1 / Frame Time`` (rounded to an
            integer when within 1e-4 of one, relatively: 0.0083333 s gives 120 fps).

    Returns:
        The motion; ``source`` holds ``kind="file"``, ``format="bvh"``, ``path``, ``scale``,
        ``up_axis``, ``joint_map`` (the BVH -> SMPL names used), ``ignored_joints``,
        ``builtin_map`` and ``fps_original``.
    """
    name = os.fspath(path)
    C = up_axis_rotation(up_axis)
    skel = _parse_bvh(name)
    smpl_to_bvh, ignored, builtin_name = _resolve_joint_map(skel, joint_map, name)
    label, label_name = resolve_label(path, label_map, label_name=label_name, label=label,
                                      allow_unlabelled=allow_unlabelled)
    rest, ends = _rest_positions(skel)
    if scale is None:
        up = 1 if up_axis.lower() == "y" else 2
        heights = np.concatenate([rest[:, up], ends[:, up]])
        scale = guess_scale(float(heights.max() - heights.min()))
    else:
        try:
            scale = float(scale)
        except (TypeError, ValueError):
            raise InputError(f"scale must be a number of metres per BVH unit, got {scale!r}") from None
        if not math.isfinite(scale) or scale <= 0:
            raise InputError(f"scale must be finite and > 0 metres per BVH unit, got {scale}")

    local_rot, local_pos = _local_transforms(skel)
    T = local_rot.shape[0]
    G = np.empty_like(local_rot)
    P = np.empty_like(local_pos)
    for b, p in enumerate(skel.parents):
        if p < 0:
            G[:, b], P[:, b] = local_rot[:, b], local_pos[:, b]
        else:
            G[:, b] = G[:, p] @ local_rot[:, b]
            P[:, b] = P[:, p] + np.einsum("tij,tj->ti", G[:, p], local_pos[:, b])
    G = C @ G @ C.T  # rotations relative to the (rest-aligned) world, in Y-up coordinates

    smpl_global = np.empty((T, JOINT_COUNT, 3, 3))
    poses = np.empty((T, JOINT_COUNT, 3, 3))
    for k in range(JOINT_COUNT):
        parent = SMPL_PARENTS[k]
        smpl_global[:, k] = G[:, smpl_to_bvh[k]] if k in smpl_to_bvh else smpl_global[:, parent]
        poses[:, k] = smpl_global[:, k] if parent < 0 else smpl_global[:, parent].swapaxes(-1, -2) @ smpl_global[:, k]
    root = smpl_to_bvh[0]
    trans = scale * (P[:, root] - rest[root]) @ C.T

    rate = 1.0 / skel.frame_time
    if abs(rate - round(rate)) <= 1e-4 * rate:
        rate = float(round(rate))
    used = {skel.names[b]: SMPL_JOINT_NAMES[k] for k, b in sorted(smpl_to_bvh.items())}
    source = {"kind": "file", "format": "bvh", "path": name, "scale": scale, "up_axis": up_axis.lower(),
              "joint_map": used, "ignored_joints": ignored, "builtin_map": builtin_name, "fps_original": rate}
    motion = Motion(poses=matrix_to_axis_angle_np(poses), trans=trans, fps=rate, label=label,
                    label_name=label_name, source=source)
    logger.info("read BVH %s: %d frames at %g fps, %d joints mapped, %d ignored", name, T, rate, len(used), len(ignored))
    if fps is not None:
        motion = motion.resample(fps)
    return motion


# ----------------------------------------------------------------------------- writing

def write_bvh(motion: Motion, path: str | os.PathLike, rest_joints: np.ndarray) -> Path:
    """Write ``motion`` as a BVH of SMPL's skeleton (see the module docstring).

    Args:
        motion: the motion to write.
        path: the ``.bvh`` file to write (its directory must exist).
        rest_joints: the body's rest-pose joint positions [24, 3] (or [1, 24, 3]) in metres, e.g.
            ``body_model.rest_joints(betas)[0]``; they give the bone offsets.

    Returns:
        The path written. The file is in metres; leaf joints (head, feet, hands) get an end site
        half their bone's length further along the bone.
    """
    if not isinstance(motion, Motion):
        raise InputError(f"motion must be a datagen Motion, got {type(motion).__name__}")
    joints = np.asarray(rest_joints, dtype=np.float64)
    if joints.shape == (1, JOINT_COUNT, 3):
        joints = joints[0]
    if joints.shape != (JOINT_COUNT, 3) or not np.all(np.isfinite(joints)):
        raise InputError(f"rest_joints must be finite [{JOINT_COUNT}, 3] rest joint positions in metres "
                         f"(body_model.rest_joints(betas)[0]), got shape {joints.shape}")
    path = Path(path)
    if not path.parent.is_dir():
        raise InputError(f"directory {path.parent} does not exist; create it first")
    children: dict[int, list[int]] = {k: [] for k in range(JOINT_COUNT)}
    for k, p in enumerate(SMPL_PARENTS):
        if p >= 0:
            children[p].append(k)
    order: list[int] = []
    out = io.StringIO()
    out.write("HIERARCHY\n")

    def vec(v) -> str:
        return " ".join(f"{x:.9g}" for x in v)

    def joint(k: int, depth: int) -> None:
        pad = "  " * depth
        order.append(k)
        parent = SMPL_PARENTS[k]
        offset = joints[k] if parent < 0 else joints[k] - joints[parent]
        out.write(f"{pad}{'ROOT' if parent < 0 else 'JOINT'} {SMPL_JOINT_NAMES[k]}\n{pad}{{\n")
        out.write(f"{pad}  OFFSET {vec(offset)}\n")
        if parent < 0:
            out.write(f"{pad}  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n")
        else:
            out.write(f"{pad}  CHANNELS 3 Zrotation Xrotation Yrotation\n")
        for c in children[k]:
            joint(c, depth + 1)
        if not children[k]:
            out.write(f"{pad}  End Site\n{pad}  {{\n{pad}    OFFSET {vec(0.5 * offset)}\n{pad}  }}\n")
        out.write(f"{pad}}}\n")

    joint(0, 0)
    T = motion.frame_count
    local = axis_angle_to_matrix_np(motion.poses[:, order])  # [T, 24, 3, 3] in hierarchy order
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # gimbal lock: the angles still give the rotation
        euler = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_euler("ZXY", degrees=True).reshape(T, -1)
    root_pos = joints[0] + motion.trans
    table = np.concatenate([root_pos, euler], axis=1)
    out.write(f"MOTION\nFrames: {T}\nFrame Time: {1.0 / motion.fps:.12g}\n")
    np.savetxt(out, table, fmt="%.9g")
    path.write_text(out.getvalue(), encoding="utf-8")
    logger.info("wrote BVH %s: %d frames at %g fps", path, T, motion.fps)
    return path
