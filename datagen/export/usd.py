"""Animated USD files of a body and a garment, and the stage conventions every drape USD file shares.

:func:`write_animation_usd` takes plain arrays (so the store exporter, ``drape simulate`` results
and model predictions all go through it) and writes one layer, ``.usd`` (binary crate), ``.usdc``
or ``.usda`` (text)::

    /Drape                  Xform, the default prim; customData["drape"] = what the arrays are
                            (source, sample, split, garment type, body, motion, ... as given)
      Body                  Mesh: faces, time-sampled points, normals (vertex) and extent,
                            constant displayColor; without a skeleton (or without skin weights)
      Garment               Mesh: the same, doubleSided; primvars:drape:region (int, vertex) with
                            customData["drape"]["region_names"]; displayColor per vertex by region;
                            primvars:st (texCoord2f[], metres: a pattern garment's flat panel
                            coordinates, faceVarying; a shell's material uv, vertex) and
                            primvars:drape:panel (int, uniform: the pattern panel of each triangle)
      Skel                  SkelRoot, only with a skeleton:
        Skeleton            joints (SMPL names as paths), bindTransforms, restTransforms,
                            skel:animationSource -> Animation
        Animation           SkelAnimation: time-sampled translations (root: rest joint + trans)
                            and rotations (quatf, the pose's local rotations), constant scales
        Body                the body Mesh bound to the Skeleton (with skin weights): points are
                            the shaped rest pose, primvars:skel:jointIndices / jointWeights,
                            geomBindTransform identity; UsdSkel's linear blend skinning gives the
                            posed body, the same as drape's LBS

Frame ``k`` is time code ``k``; ``timeCodesPerSecond = framesPerSecond = fps``, start and end time
codes ``0`` and ``T - 1``, ``upAxis = Y``, ``metersPerUnit = 1``. Points are float32 metres,
written as given, so reading them back gives the input's float32 values exactly.

:func:`new_stage` and :func:`save_stage` set up and write every drape USD layer (the motion
exporter of :mod:`datagen.export.motion` uses them too); :func:`usd_validation_errors` runs
usd-core's own validators on a written file. Files are written to a temporary name next to the
target and renamed, so a failed export leaves nothing half written. USD needs the optional
``usd-core`` package (``pip install 'drape[usd]'``).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from datagen.errors import InputError, require
from datagen.files import atomic_output, check_output_path
from datagen.geometry.topology import vertex_normals_np

__all__ = [
    "BODY_COLOR",
    "GARMENT_COLOR",
    "REGION_COLORS",
    "ROOT",
    "USD_SUFFIXES",
    "SkeletonAnimation",
    "define_mesh",
    "joint_paths",
    "new_stage",
    "save_stage",
    "usd_validation_errors",
    "vertex_normals",
    "write_animation_usd",
]

logger = logging.getLogger(__name__)

USD_SUFFIXES = (".usd", ".usda", ".usdc")
"""File name endings the USD writers take (``.usd`` is binary crate)."""

ROOT = "/Drape"
"""The default prim of :func:`write_animation_usd`'s files."""

BODY_COLOR = (0.80, 0.65, 0.55)
GARMENT_COLOR = (0.25, 0.45, 0.75)
REGION_COLORS = ((0.25, 0.45, 0.75), (0.90, 0.55, 0.20), (0.30, 0.65, 0.35), (0.60, 0.40, 0.75), (0.80, 0.30, 0.30),
                 (0.20, 0.65, 0.70), (0.85, 0.75, 0.25), (0.85, 0.50, 0.70))
"""Display colour of garment region code ``r``: ``REGION_COLORS[r % len(REGION_COLORS)]``."""

FRAME_CHUNK = 32
"""Frames whose normals are computed in one go (bounds memory to about 32 x V x 3 float32 x 4)."""


@dataclass(frozen=True, kw_only=True)
class SkeletonAnimation:
    """An SMPL-format skeleton and its motion, as plain arrays, for a UsdSkel rig.

    Attributes:
        poses: local joint rotations [T, J, 3], axis-angle (radians), root first.
        trans: root translation [T, 3] (m), added to every joint (SMPL's ``transl``).
        rest_joints: joint positions of the shaped body in its rest pose [J, 3] (m).
        parents: parent of each joint [J], -1 for the root; parents come before their children.
        joint_names: a name per joint (SMPL's by default).
        rest_vertices: the shaped body in its rest pose [B, 3] (m), or None.
        weights: skinning weights [B, J] (rows sum to 1), or None. With ``rest_vertices`` they
            bind the body mesh to the skeleton; without them the skeleton is written unbound next
            to the time-sampled body.
    """

    poses: np.ndarray
    trans: np.ndarray
    rest_joints: np.ndarray
    parents: Sequence[int]
    joint_names: Sequence[str] | None = None
    rest_vertices: np.ndarray | None = None
    weights: np.ndarray | None = None

    @property
    def bindable(self) -> bool:
        return self.rest_vertices is not None and self.weights is not None


# ------------------------------------------------------------------------------------- stages


def new_stage(fps: float, frame_count: int, root_path: str, *, documentation: str = ""):
    """An in-memory stage with drape's conventions and an ``Xform`` at ``root_path`` as default prim.

    ``upAxis = Y``, ``metersPerUnit = 1``, ``timeCodesPerSecond = framesPerSecond = fps``, time
    codes ``0 .. frame_count - 1``. Returns ``(stage, root_xform)``.
    """
    require("pxr", "USD export", extra="usd")
    from pxr import Usd, UsdGeom

    if not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be a positive number, got {fps!r}")
    if frame_count < 1:
        raise InputError(f"an animation needs at least one frame, got {frame_count}")
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetTimeCodesPerSecond(float(fps))
    stage.SetFramesPerSecond(float(fps))
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(frame_count - 1)
    root = UsdGeom.Xform.Define(stage, root_path)
    stage.SetDefaultPrim(root.GetPrim())
    if documentation:
        stage.GetRootLayer().documentation = documentation
    return stage, root


def save_stage(stage, path: str | os.PathLike) -> Path:
    """Write ``stage``'s root layer to ``path`` (format by suffix) through a temporary file."""
    path = check_output_path(path, USD_SUFFIXES, "USD file")
    with atomic_output(path) as tmp:
        if not stage.GetRootLayer().Export(str(tmp)):
            raise InputError(f"usd-core could not write {path}")
    return path


def define_mesh(stage, prim_path: str, faces: np.ndarray, *, color=None, double_sided: bool = False):
    """A triangle ``UsdGeom.Mesh`` at ``prim_path`` with ``faces`` [F, 3], no subdivision.

    ``color``: one RGB (constant ``displayColor``), per-vertex RGBs [V, 3], or None.
    """
    from pxr import Gf, Sdf, UsdGeom, Vt

    faces = np.asarray(faces)
    mesh = UsdGeom.Mesh.Define(stage, prim_path)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, dtype=np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(faces.reshape(-1), dtype=np.int32)))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    if double_sided:
        mesh.CreateDoubleSidedAttr(True)
    if color is not None:
        c = np.asarray(color, dtype=np.float32)
        if c.ndim == 1:
            mesh.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, c))]))
        else:
            primvar = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("displayColor", Sdf.ValueTypeNames.Color3fArray,
                                                              UsdGeom.Tokens.vertex)
            primvar.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(c)))
    return mesh


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit area-weighted vertex normals [T, V, 3] (float32, as USD keeps them) of ``vertices``
    [T, V, 3] (or [V, 3]): :func:`datagen.geometry.topology.vertex_normals_np` in float32. A vertex
    in no triangle (or only in degenerate ones) gets a zero normal."""
    return vertex_normals_np(np.asarray(vertices, dtype=np.float32), faces)


def _normals_vt(vt: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """:func:`vertex_normals` of vertices laid out [V, T, 3] (as the writer keeps a chunk of frames
    for its bounds), returned [V, T, 3]; no copy is made to change the layout."""
    return np.moveaxis(vertex_normals_np(np.moveaxis(vt, 0, 1), faces), 0, 1)


def joint_paths(parents: Sequence[int], names: Sequence[str]) -> list[str]:
    """UsdSkel joint paths (``pelvis/left_hip/left_knee``) from parents (parents first) and names."""
    paths: list[str] = []
    for j, p in enumerate(parents):
        p = int(p)
        if p >= j:
            raise InputError(f"joint {j}'s parent {p} comes after it; UsdSkel needs parents before children")
        paths.append(names[j] if p < 0 else f"{paths[p]}/{names[j]}")
    return paths


# ------------------------------------------------------------------------------------- checks


def _frames(name: str, a, T: int | None = None) -> np.ndarray:
    a = np.asarray(a)
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] < 1 or a.shape[1] < 1:
        raise InputError(f"{name} must be [T, V, 3] with T, V >= 1, got shape {a.shape}")
    if T is not None and a.shape[0] != T:
        raise InputError(f"{name} has {a.shape[0]} frames; the garment has {T}")
    if not np.issubdtype(a.dtype, np.floating):
        raise InputError(f"{name} must be floats (metres), got {a.dtype}")
    a = np.ascontiguousarray(a, dtype=np.float32)
    bad = ~np.isfinite(a).all(axis=(1, 2))
    if bad.any():
        raise InputError(f"{name} has non-finite values (NaN or inf) in frame(s) {np.flatnonzero(bad)[:10].tolist()}")
    return a


def _faces(name: str, f, V: int) -> np.ndarray:
    f = np.asarray(f)
    if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
        raise InputError(f"{name} must be integer triangles [F, 3], got shape {f.shape} of {f.dtype}")
    if f.size and (f.min() < 0 or f.max() >= V):
        raise InputError(f"{name} index vertices outside 0 .. {V - 1}")
    return f


def check_animation(anim) -> None:
    """Refuse (:class:`InputError`) an animation whose positions are not finite [T, V, 3] floats or whose
    faces index vertices it has not: the checks the USD writer runs, for readers that draw it too."""
    _faces("garment_faces", anim.garment_faces, _frames("garment_vertices", anim.garment_vertices).shape[1])
    if anim.body_vertices is not None:
        _faces("body_faces", anim.body_faces, _frames("body_vertices", anim.body_vertices).shape[1])


def _custom_value(value):
    from pxr import Vt

    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        if all(isinstance(x, str) for x in value):
            return Vt.StringArray([str(x) for x in value])
        if all(isinstance(x, (bool, int, np.integer)) for x in value):
            return Vt.IntArray([int(x) for x in value])
        return Vt.DoubleArray([float(x) for x in value])
    if isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


def _check_skeleton(sk: SkeletonAnimation, T: int, B: int) -> tuple[np.ndarray, ...]:
    poses = np.asarray(sk.poses, dtype=np.float64)
    J = len(sk.parents)
    if poses.ndim == 2 and poses.shape[1] == 3 * J:
        poses = poses.reshape(len(poses), J, 3)
    if poses.shape != (T, J, 3):
        raise InputError(f"skeleton poses must be [T={T}, J={J}, 3] (axis-angle), got {poses.shape}")
    trans = np.asarray(sk.trans, dtype=np.float64)
    if trans.shape != (T, 3):
        raise InputError(f"skeleton trans must be [T={T}, 3], got {trans.shape}")
    rest = np.asarray(sk.rest_joints, dtype=np.float64)
    if rest.shape != (J, 3):
        raise InputError(f"skeleton rest_joints must be [J={J}, 3], got {rest.shape}")
    for name, a in (("poses", poses), ("trans", trans), ("rest_joints", rest)):
        if not np.isfinite(a).all():
            raise InputError(f"skeleton {name} has non-finite values")
    if sk.bindable:
        rv, w = np.asarray(sk.rest_vertices), np.asarray(sk.weights)
        if rv.shape != (B, 3) or w.shape != (B, J):
            raise InputError(f"skeleton rest_vertices [{B}, 3] and weights [{B}, {J}] must match the body's {B} "
                             f"vertices, got {rv.shape} and {w.shape}")
    return poses, trans, rest


# ------------------------------------------------------------------------------------- writer


def write_animation_usd(path: str | os.PathLike, body_vertices: np.ndarray, body_faces: np.ndarray,
                        garment_vertices: np.ndarray, garment_faces: np.ndarray, fps: float, *,
                        region: np.ndarray | None = None, region_names: Sequence[str] | None = None,
                        skeleton: SkeletonAnimation | None = None, metadata: Mapping[str, Any] | None = None,
                        normals: bool = True, garment_colors: np.ndarray | None = None,
                        garment_values: tuple[str, np.ndarray] | None = None, garment_st: np.ndarray | None = None,
                        garment_panel: np.ndarray | None = None, panel_names: Sequence[str] | None = None) -> Path:
    """Write a body and a garment moving together as one USD layer (see the module docstring).

    Args:
        path: a ``.usd`` (crate), ``.usdc`` or ``.usda`` file; its directory must exist. An
            existing file is replaced only once the new one is complete.
        body_vertices: posed body [T, B, 3] (m).
        body_faces: body triangles [Fb, 3].
        garment_vertices: garment [T, V, 3] (m), the same T frames.
        garment_faces: garment triangles [F, 3].
        fps: frames per second; frame ``k`` is time code ``k``.
        region: region (panel) code per garment vertex [V] (int), or None.
        region_names: name of each region code (``region_names[region[v]]``), or None.
        skeleton: also write the body as a UsdSkel rig (:class:`SkeletonAnimation`).
        metadata: JSON-like values (str, int, float, bool, lists of them) for the root prim's
            ``customData["drape"]``.
        normals: write time-sampled vertex normals.
        garment_colors: time-sampled per-vertex RGB [T, V, 3] in 0..1 for the garment's
            ``displayColor`` (e.g. a prediction coloured by its error); replaces the region colours.
        garment_values: (name, [T, V] floats): a time-sampled per-vertex primvar ``drape:<name>``
            (e.g. ``error_mm``), so the values behind the colours travel with the file.
        garment_st: texture coordinates (m) of the garment: per triangle corner [F, 3, 2] (a pattern
            garment's flat panel coordinates: a welded seam vertex has one per panel), written as the
            ``st`` primvar (``texCoord2f[]``, ``faceVarying``, in ``faceVertexIndices`` order), or
            per vertex [V, 2] (``vertex`` interpolation).
        garment_panel: panel of every garment triangle [F] (int), the ``drape:panel`` primvar
            (``uniform``), with ``panel_names`` (one per panel) in its customData.

    Returns:
        The path written.

    Raises:
        InputError: arrays of the wrong shape, non-finite values, a bad path.
        MissingDependencyError: usd-core is not installed.
    """
    require("pxr", "USD export", extra="usd")
    from pxr import Sdf, Usd, UsdGeom, Vt

    path = check_output_path(path, USD_SUFFIXES, "USD file")
    gv = _frames("garment_vertices", garment_vertices)
    T, V = gv.shape[:2]
    bv = _frames("body_vertices", body_vertices, T)
    B = bv.shape[1]
    gf = _faces("garment_faces", garment_faces, V)
    bf = _faces("body_faces", body_faces, B)
    if region is not None:
        region = np.asarray(region)
        if region.shape != (V,) or not np.issubdtype(region.dtype, np.integer):
            raise InputError(f"region must be an integer code per garment vertex [{V}], got {region.shape} of "
                             f"{region.dtype}")
        if region_names is not None and region.size and region.max() >= len(region_names):
            raise InputError(f"region code {int(region.max())} has no name; {len(region_names)} region names given")
    if skeleton is not None:
        poses, trans, rest = _check_skeleton(skeleton, T, B)
    skinned = skeleton is not None and skeleton.bindable

    doc = f"drape: body ({B} vertices) and garment ({V} vertices), {T} frames at {fps:g} fps"
    stage, root = new_stage(fps, T, ROOT, documentation=doc)
    for key, value in (metadata or {}).items():
        root.GetPrim().SetCustomDataByKey(f"drape:{key}", _custom_value(value))

    if garment_colors is not None:
        garment_colors = np.asarray(garment_colors, np.float32)
        if garment_colors.shape != (T, V, 3):
            raise InputError(f"garment_colors must be [T={T}, V={V}, 3], got {garment_colors.shape}")
    garment = define_mesh(stage, f"{ROOT}/Garment", gf, double_sided=True,
                          color=None if garment_colors is not None else GARMENT_COLOR if region is None else
                          np.asarray(REGION_COLORS, np.float32)[region % len(REGION_COLORS)])
    if garment_colors is not None:
        colour = UsdGeom.PrimvarsAPI(garment).CreatePrimvar("displayColor", Sdf.ValueTypeNames.Color3fArray,
                                                            UsdGeom.Tokens.vertex)
        for k in range(T):
            colour.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(garment_colors[k])), Usd.TimeCode(k))
    if garment_values is not None:
        name, values = garment_values[0], np.asarray(garment_values[1], np.float32)
        if values.shape != (T, V):
            raise InputError(f"garment_values must be [T={T}, V={V}], got {values.shape}")
        pv = UsdGeom.PrimvarsAPI(garment).CreatePrimvar(f"drape:{name}", Sdf.ValueTypeNames.FloatArray,
                                                        UsdGeom.Tokens.vertex)
        for k in range(T):
            pv.Set(Vt.FloatArray.FromNumpy(np.ascontiguousarray(values[k])), Usd.TimeCode(k))
    if region is not None:
        pv = UsdGeom.PrimvarsAPI(garment).CreatePrimvar("drape:region", Sdf.ValueTypeNames.IntArray,
                                                        UsdGeom.Tokens.vertex)
        pv.Set(Vt.IntArray.FromNumpy(np.ascontiguousarray(region, dtype=np.int32)))
        if region_names is not None:
            names = Vt.StringArray([str(n) for n in region_names])
            pv.GetAttr().SetCustomDataByKey("drape:region_names", names)
            garment.GetPrim().SetCustomDataByKey("drape:region_names", names)
    if garment_st is not None:
        _write_st(garment, np.asarray(garment_st), len(gf), V)
    if garment_panel is not None:
        panel = np.asarray(garment_panel)
        if panel.shape != (len(gf),) or not np.issubdtype(panel.dtype, np.integer):
            raise InputError(f"garment_panel must be an integer panel per garment triangle [{len(gf)}], got "
                             f"{panel.shape} of {panel.dtype}")
        pv = UsdGeom.PrimvarsAPI(garment).CreatePrimvar("drape:panel", Sdf.ValueTypeNames.IntArray,
                                                        UsdGeom.Tokens.uniform)
        pv.Set(Vt.IntArray.FromNumpy(np.ascontiguousarray(panel, dtype=np.int32)))
        if panel_names is not None:
            pv.GetAttr().SetCustomDataByKey("drape:panel_names", Vt.StringArray([str(n) for n in panel_names]))
    meshes = [(garment, gv, gf)]
    if not skinned:
        body = define_mesh(stage, f"{ROOT}/Body", bf, color=BODY_COLOR)
        meshes.append((body, bv, bf))
    attrs = []
    for mesh, frames, faces in meshes:
        faces = np.asarray(faces, dtype=np.int64)
        n_attr = None
        if normals:
            n_attr = mesh.CreateNormalsAttr()
            mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        attrs.append((mesh.CreatePointsAttr(), mesh.CreateExtentAttr(), n_attr, frames, faces))
    for start in range(0, T, FRAME_CHUNK):
        stop = min(T, start + FRAME_CHUNK)
        for points, extent, n_attr, frames, faces in attrs:
            chunk = frames[start:stop]
            vt = np.ascontiguousarray(chunk.transpose(1, 0, 2))  # [V, n, 3]: fast reductions over vertices
            flat = vt.reshape(len(vt), -1)
            lo, hi = flat.min(axis=0).reshape(-1, 3), flat.max(axis=0).reshape(-1, 3)
            nrm = _normals_vt(vt, faces).transpose(1, 0, 2) if n_attr is not None else None
            for k in range(stop - start):
                t = Usd.TimeCode(start + k)
                points.Set(Vt.Vec3fArray.FromNumpy(chunk[k]), t)
                extent.Set(Vt.Vec3fArray.FromNumpy(np.stack([lo[k], hi[k]])), t)
                if nrm is not None:
                    n_attr.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(nrm[k])), t)

    if skeleton is not None:
        _write_skeleton(stage, skeleton, poses, trans, rest, bf, normals)
    path = save_stage(stage, path)
    logger.debug("wrote USD %s: %d frames at %g fps, body %d vertices%s, garment %d vertices", path, T, fps, B,
                " (UsdSkel-skinned)" if skinned else "", V)
    return path


def _write_st(mesh, st: np.ndarray, F: int, V: int) -> None:
    """The ``st`` primvar (texCoord2f[]) of ``mesh``: faceVarying from per-corner [F, 3, 2] values,
    vertex from per-vertex [V, 2] ones."""
    from pxr import Sdf, UsdGeom, Vt

    if st.shape == (F, 3, 2):
        values, interpolation = st.reshape(-1, 2), UsdGeom.Tokens.faceVarying
    elif st.shape == (V, 2):
        values, interpolation = st, UsdGeom.Tokens.vertex
    else:
        raise InputError(f"garment_st must be per triangle corner [{F}, 3, 2] or per vertex [{V}, 2], got {st.shape}")
    if not np.isfinite(values).all():
        raise InputError("garment_st has non-finite values (a shell garment has no flat pattern: give its per-vertex "
                         "uv, or none)")
    pv = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, interpolation)
    pv.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(values, dtype=np.float32)))


def _matrices(translations: np.ndarray):
    """Gf (row-vector) 4x4 translation matrices [J] as a ``Vt.Matrix4dArray``."""
    from pxr import Vt

    m = np.tile(np.eye(4), (len(translations), 1, 1))
    m[:, 3, :3] = translations
    return Vt.Matrix4dArray.FromNumpy(m)


def _write_skeleton(stage, sk: SkeletonAnimation, poses: np.ndarray, trans: np.ndarray, rest: np.ndarray,
                    body_faces: np.ndarray, normals: bool) -> None:
    from pxr import Gf, Usd, UsdGeom, UsdSkel, Vt

    from datagen.body.skeleton import SMPL_JOINT_NAMES
    from datagen.geometry.rotations import axis_angle_to_quaternion_np

    J = len(sk.parents)
    parents = np.asarray(sk.parents, dtype=np.int64)
    names = list(sk.joint_names) if sk.joint_names is not None else (
        list(SMPL_JOINT_NAMES) if J == len(SMPL_JOINT_NAMES) else [f"joint{j}" for j in range(J)])
    paths = Vt.TokenArray(joint_paths(parents, names))
    local = rest.copy()
    local[1:] -= rest[parents[1:]]

    UsdSkel.Root.Define(stage, f"{ROOT}/Skel")
    skel = UsdSkel.Skeleton.Define(stage, f"{ROOT}/Skel/Skeleton")
    skel.CreateJointsAttr(paths)
    skel.CreateJointNamesAttr(Vt.TokenArray(names))
    skel.CreateBindTransformsAttr(_matrices(rest))
    skel.CreateRestTransformsAttr(_matrices(local))
    anim = UsdSkel.Animation.Define(stage, f"{ROOT}/Skel/Animation")
    anim.CreateJointsAttr(paths)
    anim.CreateScalesAttr(Vt.Vec3hArray([Gf.Vec3h(1, 1, 1)] * J))
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets([anim.GetPath()])
    translations, rotations = anim.CreateTranslationsAttr(), anim.CreateRotationsAttr()
    quats = axis_angle_to_quaternion_np(poses)[..., [1, 2, 3, 0]].astype(np.float32)  # Gf order: x, y, z, w
    tr = np.repeat(local[None], len(poses), axis=0)
    tr[:, 0] += trans
    tr = tr.astype(np.float32)
    for k in range(len(poses)):
        t = Usd.TimeCode(k)
        translations.Set(Vt.Vec3fArray.FromNumpy(tr[k]), t)
        rotations.Set(Vt.QuatfArray.FromNumpy(np.ascontiguousarray(quats[k])), t)
    if not sk.bindable:
        return
    rv = np.ascontiguousarray(sk.rest_vertices, dtype=np.float32)
    w = np.asarray(sk.weights, dtype=np.float32)
    k = max(1, int((w > 0).sum(axis=1).max()))
    idx = np.argsort(-w, axis=1, kind="stable")[:, :k]
    wk = np.take_along_axis(w, idx, axis=1)
    mesh = define_mesh(stage, f"{ROOT}/Skel/Body", body_faces, color=BODY_COLOR)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(rv))
    mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(np.stack([rv.min(0), rv.max(0)])))
    if normals:
        mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(vertex_normals(rv, body_faces)))
        mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateSkeletonRel().SetTargets([skel.GetPath()])
    binding.CreateJointIndicesPrimvar(False, k).Set(Vt.IntArray.FromNumpy(np.ascontiguousarray(idx.reshape(-1),
                                                                                               dtype=np.int32)))
    binding.CreateJointWeightsPrimvar(False, k).Set(Vt.FloatArray.FromNumpy(np.ascontiguousarray(wk.reshape(-1))))
    binding.CreateGeomBindTransformAttr(Gf.Matrix4d(1.0))


def usd_validation_errors(path: str | os.PathLike) -> list[str]:
    """Problems that usd-core's validators find in the USD file at ``path`` (empty: none).

    Uses ``pxr.UsdValidation`` (usd-core >= 24.11: every registered validator, run on the
    stage) when present, else ``pxr.UsdUtils.ComplianceChecker`` (errors and failed checks).
    """
    require("pxr", "USD validation", extra="usd")
    from pxr import Usd

    try:
        from pxr import UsdValidation
    except ImportError:
        UsdValidation = None
    if UsdValidation is not None:
        validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
        stage = Usd.Stage.Open(os.fspath(path))
        errors = UsdValidation.ValidationContext(validators).Validate(stage)
        return [e.GetErrorAsString() for e in errors
                if not e.HasNoError() and e.GetType() != UsdValidation.ValidationErrorType.Info]
    try:
        from pxr.UsdUtils.complianceChecker import ComplianceChecker
    except ImportError:
        from pxr.UsdUtils import ComplianceChecker  # type: ignore[attr-defined, no-redef]
    checker = ComplianceChecker()
    checker.CheckCompliance(os.fspath(path))
    return list(checker.GetErrors()) + list(checker.GetFailedChecks())
