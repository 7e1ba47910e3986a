"""How fast :func:`datagen.export.usd.write_animation_usd` writes a long, dense animation, and whether
the file passes usd-core's validators and reads back exactly.

The animation: drape's default body (13,348 vertices, posed by LBS over a procedural ``walk`` of
``--frames`` frames at 30 fps) and a synthetic garment of ``--garment-vertices`` vertices (an open
tube around the hips that follows the body's translation and ripples), 30,000 vertices in all by
default. It is written as ``.usd`` (binary crate) and ``.usda`` (text), with time-sampled points,
normals and extents, region primvars and customData, and once more as ``.usd`` with the UsdSkel
rig (``--skeleton``: the body as skeleton + animation + skinned mesh). For each file: seconds to
write (normals included, array preparation excluded), MB on disk, frames per second, seconds to
validate, the validators' error count, and whether every frame's points read back equal to the
float32 input.

    python -m benchmarks export [--frames 300] [--garment-vertices 16652] [--out DIR] [--keep]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from datagen.export.usd import SkeletonAnimation, usd_validation_errors, write_animation_usd


def tube(vertex_count: int, radius: float = 0.2, height: float = 0.45, rows: int = 46):
    """An open tube [V, 3] around the Y axis with ``rows`` rings (V a multiple of ``rows``) and its triangles."""
    cols = vertex_count // rows
    a = np.linspace(0, 2 * np.pi, cols, endpoint=False)
    y = np.linspace(-height / 2, height / 2, rows)
    v = np.stack([radius * np.cos(a)[None].repeat(rows, 0), y[:, None].repeat(cols, 1),
                  radius * np.sin(a)[None].repeat(rows, 0)], axis=-1).reshape(-1, 3)
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(cols), indexing="ij")
    p0, p1 = r * cols + c, r * cols + (c + 1) % cols
    p2, p3 = (r + 1) * cols + (c + 1) % cols, (r + 1) * cols + c
    faces = np.concatenate([np.stack([p0, p3, p2], -1).reshape(-1, 3), np.stack([p0, p2, p1], -1).reshape(-1, 3)])
    return v, faces, (np.arange(len(v)) % cols >= cols // 2).astype(np.int32)


def make_animation(frames: int, garment_vertices: int):
    from datagen.body.cache import default_body
    from datagen.motion.library import make_motion

    model = default_body()
    motion = make_motion("walk", seed=0, frames=frames, fps=30.0)
    betas = np.zeros((1, model.shape_dim))
    body = np.empty((frames, model.vertex_count, 3), np.float32)
    for s in range(0, frames, 64):
        v, _ = model.pose(betas, motion.poses[s:s + 64].reshape(-1, 72), motion.trans[s:s + 64])
        body[s:s + 64] = v
    rest, faces, region = tube(garment_vertices)
    hips = np.array([0.0, -0.05, 0.0])
    t = np.arange(frames)[:, None] / 30.0
    ripple = 0.01 * np.sin(2 * np.pi * (1.5 * t + rest[None, :, 1] * 4))  # [T, V]
    radial = rest * np.array([1, 0, 1]) / np.linalg.norm(rest * np.array([1, 0, 1]), axis=1, keepdims=True)
    garment = (rest[None] + hips + motion.trans[:, None] + ripple[..., None] * radial[None]).astype(np.float32)
    sk = SkeletonAnimation(poses=motion.poses, trans=motion.trans, rest_joints=model.rest_joints(betas)[0],
                           parents=model.parents, rest_vertices=model.shaped(betas)[0], weights=model.weights)
    return model, body, garment, faces, region, sk


def read_back_exact(path: Path, body: np.ndarray, garment: np.ndarray, skinned: bool) -> bool:
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    g = UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Garment")).GetPointsAttr()
    b = None if skinned else UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Body")).GetPointsAttr()
    for t in range(len(garment)):
        if not np.array_equal(np.asarray(g.Get(t)), garment[t]):
            return False
        if b is not None and not np.array_equal(np.asarray(b.Get(t)), body[t]):
            return False
    return True


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--garment-vertices", type=int, default=16652, help="rounded down to a multiple of 46")
    ap.add_argument("--out", type=Path, default=None, help="directory for the files (default: a temporary one)")
    ap.add_argument("--keep", action="store_true", help="keep the files")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    model, body, garment, faces, region, sk = make_animation(args.frames, args.garment_vertices)
    T, B, V = len(body), body.shape[1], garment.shape[1]
    print(f"animation: {T} frames at 30 fps; body {B} vertices ({len(model.faces)} triangles) + garment {V} "
          f"vertices ({len(faces)} triangles) = {B + V} vertices; arrays made in {time.perf_counter() - t0:.1f} s")
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_export_"))
    out.mkdir(parents=True, exist_ok=True)
    print(f"{'file':<22}{'write s':>9}{'MB':>9}{'frames/s':>10}{'validate s':>12}{'errors':>8}  read-back")
    try:
        for name, skeleton in (("anim.usd", False), ("anim.usda", False), ("anim_skeleton.usd", True)):
            path = out / name
            t0 = time.perf_counter()
            write_animation_usd(path, body, model.faces, garment, faces, 30.0, region=region,
                                region_names=["left", "right"], skeleton=sk if skeleton else None,
                                metadata={"source": "bench_export", "frames": T})
            seconds = time.perf_counter() - t0
            t0 = time.perf_counter()
            errors = usd_validation_errors(path)
            validate = time.perf_counter() - t0
            exact = read_back_exact(path, body, garment, skeleton)
            print(f"{name:<22}{seconds:>9.2f}{path.stat().st_size / 1e6:>9.1f}{T / seconds:>10.1f}{validate:>12.2f}"
                  f"{len(errors):>8}  {'exact' if exact else 'DIFFERS'}", flush=True)
            for e in errors[:5]:
                print(f"    {e}")
    finally:
        if not args.keep and args.out is None:
            shutil.rmtree(out, ignore_errors=True)
    return 0
