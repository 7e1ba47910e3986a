"""Writing a motion on a body: an animated USD mesh, or a BVH of the body's skeleton.

USD (:func:`write_motion_usd`): one ``UsdGeom.Mesh`` at ``/Body/Skin`` whose ``points`` (float32,
metres) and ``extent`` are time-sampled, one sample per frame at time code ``k`` for frame ``k``;
``timeCodesPerSecond = framesPerSecond = motion.fps``, start/end time codes ``0`` and ``T - 1``,
``upAxis = Y``, ``metersPerUnit = 1``, ``/Body`` the default prim. ``with_skeleton=True`` adds
``/Body/Bones``, a linear ``UsdGeom.BasisCurves`` with one two-point segment per SMPL bone (parent
joint to joint), time-sampled: a visual aid for checking the motion, not a UsdSkel rig.

The stage set-up, the atomic write and :func:`usd_validation_errors` are shared with
:mod:`datagen.export.usd` (and re-exported here). USD needs the optional ``usd-core`` package
(``pip install 'drape[usd]'``).
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np

from datagen.body.skeleton import SMPL_PARENTS
from datagen.errors import InputError, require
from datagen.files import check_output_path
from datagen.export.usd import BODY_COLOR, USD_SUFFIXES, define_mesh, new_stage, save_stage, usd_validation_errors
from datagen.motion.bvh import write_bvh
from datagen.motion.motion import Motion

__all__ = ["USD_SUFFIXES", "usd_validation_errors", "write_motion_bvh", "write_motion_usd"]

logger = logging.getLogger(__name__)

POSE_CHUNK_FRAMES = 64
"""Frames posed per call of ``body_model.pose`` (bounds memory to about 64 x V x 3 float64)."""


def _check_betas(body_model, betas) -> np.ndarray | None:
    if betas is None:
        return None
    b = np.asarray(betas, dtype=np.float64)
    if b.ndim == 2 and b.shape[0] == 1:
        b = b[0]
    if b.ndim != 1:
        raise InputError(f"betas must be one shape vector [S] (or [1, S]), got shape {b.shape}")
    return b[None]


def posed_frames(motion: Motion, body_model, betas=None, chunk: int = POSE_CHUNK_FRAMES):
    """Yield ``(start, vertices [n, V, 3], joints [n, J, 3])`` in metres for chunks of ``motion``'s frames."""
    b = _check_betas(body_model, betas)
    for start in range(0, motion.frame_count, chunk):
        stop = min(start + chunk, motion.frame_count)
        verts, joints = body_model.pose(b, motion.poses[start:stop], motion.trans[start:stop])
        yield start, verts, joints


def write_motion_usd(motion: Motion, path: str | os.PathLike, body_model, betas=None, *,
                     with_skeleton: bool = False) -> Path:
    """Write ``motion`` posed on ``body_model`` as an animated USD mesh (see the module docstring).

    Args:
        motion: the motion; frame ``k`` is written at time code ``k``.
        path: a ``.usd`` (crate), ``.usda`` (text) or ``.usdc`` file; its directory must exist.
        body_model: a :class:`~datagen.body.model.BodyModel` (e.g. ``default_body()``).
        betas: shape coefficients [S] (S <= the model's), or ``None`` for the mean shape.
        with_skeleton: also write the SMPL bones as time-sampled line segments.

    Returns:
        The path written.
    """
    require("pxr", "USD export", extra="usd")
    from pxr import Gf, Usd, UsdGeom, Vt

    if not isinstance(motion, Motion):
        raise InputError(f"motion must be a datagen Motion, got {type(motion).__name__}")
    path = check_output_path(path, USD_SUFFIXES, "USD file")
    stage, root = new_stage(motion.fps, motion.frame_count, "/Body",
                            documentation=f"drape motion {motion.label_name!r}: {motion.frame_count} frames at "
                            f"{motion.fps:g} fps")
    root.GetPrim().SetCustomDataByKey("drape:label_name", motion.label_name)
    root.GetPrim().SetCustomDataByKey("drape:label", motion.label)

    mesh = define_mesh(stage, "/Body/Skin", np.asarray(body_model.faces), color=BODY_COLOR)
    points = mesh.CreatePointsAttr()
    extent = mesh.CreateExtentAttr()
    bones = None
    if with_skeleton:
        child = np.array([k for k, p in enumerate(SMPL_PARENTS) if p >= 0])
        parent = np.array([SMPL_PARENTS[k] for k in child])
        bones = UsdGeom.BasisCurves.Define(stage, "/Body/Bones")
        bones.CreateTypeAttr(UsdGeom.Tokens.linear)
        bones.CreateCurveVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(child), 2, dtype=np.int32)))
        bones.CreateWidthsAttr(Vt.FloatArray([0.01]))
        bones.GetWidthsAttr().SetMetadata("interpolation", UsdGeom.Tokens.constant)
        bones.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(0.9, 0.2, 0.2)]))
        bone_points = bones.CreatePointsAttr()
        bone_extent = bones.CreateExtentAttr()

    for start, verts, joints in posed_frames(motion, body_model, betas):
        verts32 = verts.astype(np.float32)
        for i in range(len(verts32)):
            t = Usd.TimeCode(start + i)
            v = verts32[i]
            points.Set(Vt.Vec3fArray.FromNumpy(v), t)
            extent.Set(Vt.Vec3fArray.FromNumpy(np.stack([v.min(0), v.max(0)])), t)
            if bones is not None:
                seg = np.stack([joints[i, parent], joints[i, child]], axis=1).reshape(-1, 3).astype(np.float32)
                bone_points.Set(Vt.Vec3fArray.FromNumpy(seg), t)
                bone_extent.Set(Vt.Vec3fArray.FromNumpy(np.stack([seg.min(0), seg.max(0)])), t)
    save_stage(stage, path)
    logger.info("wrote USD %s: %d frames at %g fps, %d vertices", path, motion.frame_count, motion.fps,
                body_model.vertex_count)
    return path


def write_motion_bvh(motion: Motion, path: str | os.PathLike, body_model, betas=None) -> Path:
    """Write ``motion`` as a BVH of ``body_model``'s skeleton: :func:`write_bvh` with its rest joints.

    Args:
        motion: the motion.
        path: the ``.bvh`` file (its directory must exist).
        body_model: a :class:`~datagen.body.model.BodyModel`; its rest joints for ``betas`` give
            the bone offsets (metres).
        betas: shape coefficients [S], or ``None`` for the mean shape.
    """
    b = _check_betas(body_model, betas)
    return write_bvh(motion, path, body_model.rest_joints(b)[0])
