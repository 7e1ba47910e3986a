"""``drape body``: build, export and describe the SMPL-format body model."""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np

from datagen.cli import args as checks

MESH_SUFFIXES = (".npz", ".obj", ".ply", ".usd", ".usda", ".usdc")


def register(sub, formatter) -> None:
    body = sub.add_parser(
        "body", formatter_class=formatter, help="build, export and describe the body model",
        description="The SMPL-format body: built offline from Anny (no licence, no download), or an SMPL file you have.",
        epilog="examples:\n  drape body build --out body.pkl\n  drape body export --body fat --pose a-pose --format obj --out fat.obj\n  drape body info\n  drape body measure --body fat",
    )
    bsub = body.add_subparsers(dest="body_command", metavar="BODY_COMMAND")
    bsub.required = True

    p = bsub.add_parser(
        "build", formatter_class=formatter, help="build (or load from cache) the Anny-derived body and write it as an SMPL file",
        description="Derive the SMPL-format body from Anny (T-pose, 24 joints, 10 PCA shape components) and cache it. "
        "The written .pkl loads in smplx (smplx.SMPL(model_path=...)); .npz is the same arrays compressed.",
        epilog="example:\n  drape body build --out body.pkl --subdivide",
    )
    p.add_argument("--config", help="TOML/YAML file with an [anny_body] section (sample_count, seed, shape_dim, age_years, regressor_vertex_count)")
    p.add_argument("--seed", type=checks.seed, default=None, help="seed of the phenotype sampling (overrides the config)")
    p.add_argument("--out", type=checks.out_file(".pkl", ".npz"), help="write the model here (.pkl or .npz); default: only build the cache")
    p.add_argument("--subdivide", action="store_true", help="write the 4-to-1 subdivided model (paper 000's resolution)")
    p.add_argument("--rebuild", action="store_true", help="ignore the cache and build again")
    p.set_defaults(func=_cmd_build)

    p = bsub.add_parser(
        "export", formatter_class=formatter, help="write a rest or posed body mesh (npz, obj, ply, usd)",
        description="Pose the body (shape from a preset, β values or a seed; pose by name or from a file) and write the mesh.",
        epilog="examples:\n  drape body export --format obj --out rest.obj\n  drape body export --body thin --pose walk.npz --frame 10 --format usd --out thin.usda",
    )
    _model_args(p)
    p.add_argument("--pose", default="t-pose", help="t-pose, a-pose, or a .npy (72 values) / .npz ('poses' [T, 72+], 'trans') file")
    p.add_argument("--frame", type=checks.integer(0), default=0, help="frame of an .npz pose file")
    p.add_argument("--format", choices=["npz", "obj", "ply", "usd"], default=None, help="file format (default: from --out's suffix)")
    p.add_argument("--out", required=True, type=checks.out_file(*MESH_SUFFIXES), help="output file")
    p.set_defaults(func=_cmd_export)

    p = bsub.add_parser(
        "info", formatter_class=formatter, help="vertex, face and joint counts, β range, presets, source and licence",
        description="Describe a body model: the default one (built if needed) or an SMPL-format file.",
        epilog="example:\n  drape body info --model body.pkl",
    )
    _model_args(p, shape=False)
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.set_defaults(func=_cmd_info)

    p = bsub.add_parser(
        "measure", formatter_class=formatter, help="girths, lengths and landmark heights of a body shape (for sewing patterns)",
        description="Measure a body shape on its T-pose rest mesh: girths from plane sections (convex hull, a taut "
        "tape), lengths along the surface, landmark heights above the floor; definitions in docs/body.md.",
        epilog="examples:\n  drape body measure --body fat\n  drape body measure --seed 3 --json",
    )
    _model_args(p)
    p.add_argument("--json", action="store_true", help="print machine-readable JSON (metres)")
    p.set_defaults(func=_cmd_measure)


def _model_args(p: argparse.ArgumentParser, shape: bool = True) -> None:
    p.add_argument("--model", help="an SMPL-format .pkl/.npz body file (default: drape's Anny-derived body)")
    p.add_argument("--subdivide", action="store_true", help="use the 4-to-1 subdivided body")
    if shape:
        g = p.add_mutually_exclusive_group()
        g.add_argument("--body", help="a shape preset: thin, regular or fat")
        g.add_argument("--betas", type=checks.number(), nargs="+", help="β values (up to the model's shape dimension)")
        g.add_argument("--seed", type=checks.seed, help="sample β ~ N(0, I) from this seed")


def _config(args):
    from datagen.body.anny_builder import AnnyBodyConfig
    from datagen.config import load_config

    return load_config(AnnyBodyConfig, args.config, section="anny_body") if getattr(args, "config", None) else AnnyBodyConfig()


def load_model(args):
    """The body model the arguments name: a file, or the cached default (built if missing)."""
    if args.model:
        from datagen.body.io import load_body_file

        model = load_body_file(args.model)
        return model.subdivided() if args.subdivide else model
    from datagen.body.cache import default_body

    return default_body(_config(args), subdivision_level=1 if args.subdivide else 0)


def _cmd_build(args) -> int:
    from datagen.body.cache import body_cache_path, default_body
    from datagen.body.io import save_body_file

    config = _config(args)
    if args.seed is not None:  # build's seed is the phenotype sampling's (export's samples β)
        config = dataclasses.replace(config, seed=args.seed)
    level = 1 if args.subdivide else 0
    cached = body_cache_path(config, level).is_file() and not args.rebuild
    t0 = time.perf_counter()
    model = default_body(config, subdivision_level=level, rebuild=args.rebuild)
    seconds = time.perf_counter() - t0
    print(f"body: {model.vertex_count} vertices, {model.face_count} faces, {model.joint_count} joints, "
          f"{model.shape_dim} shape components ({'cache hit' if cached else 'built'} in {seconds:.1f} s)")
    print(f"cache: {body_cache_path(config, level)}")
    if args.out:
        out = Path(args.out)
        save_body_file(model, out)
        print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB)")
    return 0


def _cmd_export(args) -> int:
    from datagen.body.export import read_pose, write_mesh
    from datagen.body.shapes import resolve_betas

    model = load_model(args)
    betas = resolve_betas(model, body=args.body, betas=args.betas, seed=args.seed)
    pose, trans = read_pose(args.pose, args.frame)
    verts, joints = model.pose(betas, pose[None], None if trans is None else trans[None])
    out = write_mesh(args.out, verts[0], model.faces, args.format, joints=joints[0],
                     extra={"betas": betas[0].astype(np.float32), "pose": pose.astype(np.float32)})
    print(f"wrote {out}: {model.vertex_count} vertices, {model.face_count} faces")
    return 0


def _cmd_info(args) -> int:
    model = load_model(args)
    meta = model.meta
    info = {
        "vertices": model.vertex_count,
        "faces": model.face_count,
        "joints": model.joint_count,
        "shape_dim": model.shape_dim,
        "beta_range": "β ~ N(0, I); drape samples within ±2.5",
        "pose_blendshapes": model.has_pose_blendshapes,
        "rest_pose": meta.get("rest_pose", "unknown"),
        "source": meta.get("source", "unknown"),
        "licence": meta.get("licence", "unknown"),
        "subdivision_level": meta.get("subdivision_level", 0),
    }
    if "shape_explained_variance" in meta:
        info["shape_explained_variance"] = round(float(sum(meta["shape_explained_variance"])), 5)
    if "beta_correlation" in meta:
        c = meta["beta_correlation"]
        info["population_height_m"] = [round(x, 3) for x in c["height_range_m"]]
        info["population_mass_kg"] = [round(x, 1) for x in c["mass_range_kg"]]
        info["height_beta"] = int(np.argmax(np.abs(c["height"]))) + 1
        info["mass_beta"] = int(np.argmax(np.abs(c["mass"]))) + 1
    presets = {name: {k: round(v, 3) for k, v in p.items() if k in ("height_m", "mass_kg", "bmi")} for name, p in meta.get("presets", {}).items()}
    if args.json:
        print(json.dumps({**info, "presets": presets}, indent=2))
        return 0
    for k, v in info.items():
        print(f"{k:>26}: {v}")
    for name, p in presets.items():
        print(f"{'preset ' + name:>26}: height {p['height_m']:.2f} m, mass {p['mass_kg']:.1f} kg, BMI {p['bmi']:.1f}")
    return 0


def _cmd_measure(args) -> int:
    from datagen.body.measurements import measure_body
    from datagen.body.shapes import resolve_betas

    model = load_model(args)
    betas = resolve_betas(model, body=args.body, betas=args.betas, seed=args.seed)
    measure_body(model, betas)  # first call builds the mesh topology (cached per model)
    wall, cpu = [], []
    for _ in range(5):
        t0, c0 = time.perf_counter(), time.process_time()
        m = measure_body(model, betas)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    values = m.as_dict()
    if args.json:
        print(json.dumps({k: round(v, 4) for k, v in values.items()}, indent=2))
        return 0
    name = args.body or ("seed " + str(args.seed) if args.seed is not None else "β " + str(args.betas) if args.betas else "mean shape")
    print(f"body measurements of {name} [cm] (T-pose rest mesh; heights above the floor):")
    for k, v in values.items():
        print(f"{k:>20}: {100 * v:7.1f}")
    print(f"measured in {1e3 * min(wall):.0f} ms wall, {1e3 * min(cpu):.0f} ms CPU (best of {len(wall)}; "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    return 0
