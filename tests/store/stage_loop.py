"""Synthetic store content for the store tests, and a staging loop to run (and kill) as a process.

Every array is a pure function of (seed, sample index), so an interrupted and resumed run must
give exactly what one uninterrupted run gives.

    python tests/store/stage_loop.py STORE [--samples N] [--vertices V] [--pause S]

stages every missing sample of STORE (creating it with :data:`CONFIG`), printing ``ready`` once
the store is open and ``done`` at the end.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

CONFIG = {"dataset": {"name": "tiny", "frames": [2, 5]}, "sim": {"substeps": 8, "thresholds": {"stretch": 1.0}}}
SEED = 11
BODY_VERTICES = 30
SHAPES = 4
SEGMENT_LENGTH = 2
GARMENT_VERTICES = (7, 11, 5)
GARMENT_FACES = (6, 10, 4)
FAILED = frozenset({5})
LABEL_NAMES = ["walk", "run", "jump"]
REGION_NAMES = ["front", "back", "sleeve"]


def static_groups(garment_vertices=GARMENT_VERTICES, garment_faces=GARMENT_FACES, body_vertices=BODY_VERTICES
                  ) -> dict[str, tuple[dict, dict]]:
    """group -> (arrays, names) for every static group; garment instance g is made for body g."""
    from datagen.geometry.topology import unique_edges

    rng = np.random.default_rng([SEED, 999])
    B, S, J, G = body_vertices, SHAPES, 24, len(garment_vertices)
    f32 = np.float32
    weights = rng.random((B, J)).astype(f32)
    body = {"v_template": rng.normal(size=(B, 3)).astype(f32), "shapedirs": rng.normal(size=(B, 3, S)).astype(f32),
            "J_regressor": rng.random((J, B)).astype(f32), "weights": weights / weights.sum(1, keepdims=True),
            "parents": np.array([-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21],
                                np.int32),
            "faces": rng.integers(0, B, (20, 3)).astype(np.int32)}
    tri = body["faces"]
    edges = unique_edges(tri)
    body["subdivision_edges"] = edges.astype(np.int32)
    body["subdivided_faces"] = rng.integers(0, B + len(edges), (80, 3)).astype(np.int32)
    n_bodies = 4
    bodies = {"betas": rng.normal(size=(n_bodies, S)).astype(f32)}
    M = 4
    motions = {"label": np.array([0, 1, 2, 1], np.int32), "seed": np.arange(M, dtype=np.int32) + 100,
               "frame_count": np.array([50, 60, 70, 80], np.int32), **motion_frames()}
    V, F = np.array(garment_vertices), np.array(garment_faces)
    nv, nf = int(V.sum()), int(F.sum())
    garments = {
        "vertex_start": np.concatenate([[0], np.cumsum(V)]).astype(np.int64),
        "face_start": np.concatenate([[0], np.cumsum(F)]).astype(np.int64),
        "rest_vertices": rng.normal(size=(nv, 3)).astype(f32),
        "faces": np.concatenate([rng.integers(0, v, (f, 3)) for v, f in zip(V, F, strict=True)]).astype(np.int32),
        "uv": rng.random((nv, 2)).astype(f32),
        "region": rng.integers(0, len(REGION_NAMES), nv).astype(np.int32),
        "seam": (rng.random(nv) < 0.2).astype(np.uint8),
        "indicator": rng.integers(0, B + len(edges), nv).astype(np.int32),
        "skin_weights": rng.random((nv, J)).astype(f32),
        "type": np.arange(G, dtype=np.int32) % 2, "seed": np.arange(G, dtype=np.int32) + 7,
        "body": np.arange(G, dtype=np.int32), "material": np.zeros(G, np.int32),
        "alpha": rng.normal(size=(G, 3)).astype(f32), "rest_area": rng.random(G).astype(f32),
        "settled": np.array([1, 1, 0] * G, np.uint8)[:G],
        **pattern_arrays(V, F, rng),
    }
    garments["built_vertices"] = garments["rest_vertices"] + f32(0.02)
    D = 12
    fit = {"components": rng.normal(size=(3, D)).astype(f32), "mean": rng.normal(size=D).astype(f32),
           "noise_variance": rng.random(D).astype(f32), "subsample": np.array([1, D, 0], dtype=np.int64)}
    return {
        "body": (body, {}),
        "bodies": (bodies, {"body_names": [f"body-{k}" for k in range(n_bodies)]}),
        "motions": (motions, {"label_names": LABEL_NAMES}),
        "garments": (garments, {"garment_type_names": ["tshirt", "skirt"], "material_names": ["cotton"],
                                "region_names": REGION_NAMES}),
        "fit": (fit, {}),
    }


PATTERN_GARMENT = 1
"""The synthetic garment instance that is a pattern garment (the others are shells)."""


def design(g: int) -> dict:
    """The design record of synthetic pattern garment ``g``."""
    return {"program": "skirt_straight", "seed": g + 7, "source": "program", "parameters": {"length": 0.5 + g},
            "pattern": {"pattern": {"panels": {"front": {}, "back": {}}}, "name": "skirt é"}}


def pattern_arrays(V, F, rng) -> dict[str, np.ndarray]:
    """The pattern arrays of the synthetic garments: instance :data:`PATTERN_GARMENT` has two panels,
    per-corner rest coordinates, stitches and a design record; the others are shells (-1, NaN, none)."""
    import json

    panel, face_panel, rest_uv, stitches, designs = [], [], [], [], []
    stitch_start, design_start = [0], [0]
    for g, (v, f) in enumerate(zip(V, F, strict=True)):
        pattern = g == PATTERN_GARMENT
        panel.append(np.arange(v) % 2 if pattern else np.full(v, -1))
        face_panel.append(np.arange(f) % 2 if pattern else np.full(f, -1))
        rest_uv.append(rng.random((f, 3, 2)) if pattern else np.full((f, 3, 2), np.nan))
        st = np.array([[0, v - 1], [1, v - 2]]) if pattern else np.zeros((0, 2))
        raw = json.dumps(design(g)).encode() if pattern else b""
        stitches.append(st)
        designs.append(np.frombuffer(raw, np.uint8))
        stitch_start.append(stitch_start[-1] + len(st))
        design_start.append(design_start[-1] + len(raw))
    return {"panel": np.concatenate(panel).astype(np.int32), "face_panel": np.concatenate(face_panel).astype(np.int32),
            "rest_uv": np.concatenate(rest_uv).astype(np.float32), "stitches": np.concatenate(stitches).astype(np.int32),
            "design": np.concatenate(designs).astype(np.uint8),
            "stitch_start": np.array(stitch_start, np.int64), "design_start": np.array(design_start, np.int64)}


MOTION_FRAMES = 8
"""Recorded frames of every motion (``motions/pose``): a sample records the first ``T`` of them."""


def motion_frames() -> dict[str, np.ndarray]:
    """``pose`` [M, MOTION_FRAMES, 24, 3] and ``trans`` [M, MOTION_FRAMES, 3] of the four motions."""
    rng = np.random.default_rng([SEED, 998])
    return {"pose": rng.normal(scale=0.3, size=(4, MOTION_FRAMES, 24, 3)).astype(np.float32),
            "trans": rng.normal(size=(4, MOTION_FRAMES, 3)).astype(np.float32)}


def sample(i: int, garment_vertices=GARMENT_VERTICES, body_vertices=BODY_VERTICES, frames: int | None = None
           ) -> tuple[dict, dict]:
    """(arrays, scalars) of sample ``i``: split i % 3 uses garment, body and motion i % 3 (disjoint
    splits); samples in :data:`FAILED` failed (no frames)."""
    rng = np.random.default_rng([SEED, i])
    split = i % 3
    V, J = garment_vertices[split], 24
    failed = i in FAILED
    T = 0 if failed else (frames if frames is not None else 2 + i % 4)
    lead = 3
    T_sim = lead + (T or 4)
    f32 = np.float32
    arrays: dict[str, np.ndarray] = {}
    if not failed:
        for name in ("detail", "coarse"):
            arrays[name] = rng.normal(size=(T, V, 3)).astype(f32)
        mo = motion_frames()
        arrays["pose"] = mo["pose"][split, :T]  # its motion's (motion i % 3) first T recorded frames
        arrays["trans"] = mo["trans"][split, :T]
        arrays["joints"] = rng.normal(size=(T, J, 3)).astype(f32)
        arrays["label"] = np.full(T, split, np.int32)
    arrays |= {"metric_stretch_max": rng.random(T_sim).astype(f32),
               "metric_stretch_mean": rng.random(T_sim).astype(f32),
               "metric_penetration_count": rng.integers(0, 5, T_sim).astype(np.int32),
               "metric_penetration_depth": rng.random(T_sim).astype(f32) * 1e-3,
               "metric_self_intersections": rng.integers(0, 3, T_sim).astype(np.int32),
               "metric_kinetic_energy": rng.random(T_sim).astype(f32),
               "metric_nan": np.zeros(T_sim, np.uint8),
               "metric_slip": rng.random(T_sim).astype(f32) * 1e-2}
    if failed:  # blew up at its frame 2: the metrics say so
        arrays["metric_nan"][2:] = 1
        arrays["metric_kinetic_energy"][2:] = np.inf
    scalars = {"garment": split, "body": split, "motion": split, "split": split, "failure": 1 if failed else 0,
               "failure_frame": 2 if failed else -1, "recorded_from": lead, "seconds": float(0.5 + i)}
    return arrays, scalars


def open_writer(path, samples: int, *, durable: bool = True):
    from datagen.store import StoreWriter

    return StoreWriter.open(path, config=CONFIG, seed=SEED, sample_count=samples, segment_length=SEGMENT_LENGTH,
                            durable=durable)


def stage_all(writer, *, garment_vertices=GARMENT_VERTICES, body_vertices=BODY_VERTICES, pause: float = 0.0) -> None:
    for group, (arrays, names) in static_groups(garment_vertices, body_vertices=body_vertices).items():
        writer.stage_static(group, arrays, names)
    for i in writer.missing():
        arrays, scalars = sample(i, garment_vertices, body_vertices)
        writer.stage_sample(i, arrays, scalars)
        if pause:
            time.sleep(pause)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("store", type=Path)
    ap.add_argument("--samples", type=int, default=12)
    ap.add_argument("--vertices", type=int, default=0, help="scale garment vertex counts up to about this many")
    ap.add_argument("--pause", type=float, default=0.0, help="seconds between two staged files (widens the window)")
    args = ap.parse_args(argv)
    gv = GARMENT_VERTICES if not args.vertices else tuple(args.vertices + k for k in GARMENT_VERTICES)
    if args.pause:
        import datagen.store.writer as w

        save = w._save_npy

        def slow_save(*a, **k):
            save(*a, **k)
            time.sleep(args.pause)

        w._save_npy = slow_save
    writer = open_writer(args.store, args.samples)
    print("ready", flush=True)
    stage_all(writer, garment_vertices=gv)
    print("done", flush=True)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    sys.exit(main())
