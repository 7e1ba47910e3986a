"""Writing a posed or rest body mesh: npz, obj, ply (trimesh) or usd (usd-core)."""

from __future__ import annotations

import logging
import zipfile
from pathlib import Path

import numpy as np

from datagen.body.skeleton import JOINT_COUNT, SMPL_JOINT_NAMES
from datagen.errors import InputError, require

logger = logging.getLogger(__name__)

MESH_FORMATS = ("npz", "obj", "ply", "usd")

NAMED_POSES = ("t-pose", "a-pose")


def named_pose(name: str) -> np.ndarray:
    """θ [24, 3] of a named pose: the T-pose (all zeros, the rest pose) or an A-pose (arms 45° down)."""
    pose = np.zeros((JOINT_COUNT, 3))
    if name == "t-pose":
        return pose
    if name == "a-pose":
        pose[SMPL_JOINT_NAMES.index("left_shoulder")] = [0.0, 0.0, -np.pi / 4]
        pose[SMPL_JOINT_NAMES.index("right_shoulder")] = [0.0, 0.0, np.pi / 4]
        return pose
    raise InputError(f"unknown pose '{name}'; use one of {', '.join(NAMED_POSES)} or a .npy/.npz file")


def read_pose(source: str, frame: int = 0) -> tuple[np.ndarray, np.ndarray | None]:
    """θ [24, 3] and optional root translation [3] from a named pose or a file.

    Files: ``.npy`` with 72 numbers ([72] or [24, 3]); ``.npz`` with ``poses`` [T, >=72] (AMASS
    style; the first 72 columns are SMPL's 24 joints) and optional ``trans`` [T, 3], of which
    ``frame`` is taken.
    """
    if source in NAMED_POSES:
        return named_pose(source), None
    path = Path(source)
    if not path.is_file():
        raise InputError(f"pose '{source}' is neither a named pose ({', '.join(NAMED_POSES)}) nor an existing file")
    try:
        if path.suffix == ".npy":
            arr, trans = np.load(path, allow_pickle=False), None
        elif path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as npz:
                if "poses" not in npz.files:
                    raise InputError(f"pose file {path} has no 'poses' array (it has: {', '.join(npz.files)})")
                poses = npz["poses"]
                if poses.ndim != 2 or poses.shape[1] < 72:
                    raise InputError(f"pose file {path}: 'poses' must be [T, >=72], got {poses.shape}")
                if not 0 <= frame < len(poses):
                    raise InputError(f"pose file {path} has frames 0..{len(poses) - 1}; frame {frame} does not exist")
                arr = poses[frame, :72]
                trans = npz["trans"][frame] if "trans" in npz.files else None
        else:
            raise InputError(f"pose file {path} must be .npy or .npz")
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        if isinstance(exc, zipfile.BadZipFile) or "pickled" in str(exc):
            raise InputError(f"pose file {path} is not a NumPy {path.suffix} file (it could not be read as one); "
                             "give a .npy of 72 numbers or an .npz with a 'poses' array") from None
        raise InputError(f"pose file {path} could not be read: {exc}") from None
    arr = np.asarray(arr, dtype=np.float64)
    if arr.size != 72:
        raise InputError(f"pose file {path} holds {arr.size} numbers; θ needs 72 (24 joints x 3, axis-angle)")
    return arr.reshape(JOINT_COUNT, 3), trans


def write_mesh(path: str | Path, vertices: np.ndarray, faces: np.ndarray, fmt: str | None = None,
               joints: np.ndarray | None = None, extra: dict | None = None) -> Path:
    """Write one mesh (vertices [V, 3] in metres, faces [F, 3]) in ``fmt`` (default: from the suffix)."""
    path = Path(path)
    fmt = (fmt or path.suffix.lstrip(".")).lower()
    if fmt == "usda" or fmt == "usdc":
        fmt = "usd"
    if fmt not in MESH_FORMATS:
        raise InputError(f"unknown mesh format '{fmt}'; choose one of {', '.join(MESH_FORMATS)}")
    if not path.parent.exists():
        raise InputError(f"directory {path.parent} does not exist; create it first")
    if fmt == "npz":
        data = {"vertices": vertices.astype(np.float32), "faces": faces.astype(np.int32)}
        if joints is not None:
            data["joints"] = joints.astype(np.float32)
        data.update(extra or {})
        np.savez_compressed(path, **data)
    elif fmt in ("obj", "ply"):
        import trimesh

        trimesh.Trimesh(vertices, faces, process=False).export(path, file_type=fmt)
    else:
        _write_usd(path, vertices, faces)
    logger.info("wrote %s (%d vertices)", path, len(vertices))
    return path


def _write_usd(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    require("pxr", "USD export", extra="usd")
    from pxr import Gf, Usd, UsdGeom, Vt
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    root = UsdGeom.Xform.Define(stage, "/Body")
    stage.SetDefaultPrim(root.GetPrim())
    mesh = UsdGeom.Mesh.Define(stage, "/Body/Skin")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(vertices.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, dtype=np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(faces.reshape(-1).astype(np.int32)))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    lo, hi = vertices.min(0), vertices.max(0)
    mesh.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]))
    mesh.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(0.80, 0.65, 0.55)]))
    stage.GetRootLayer().Save()
