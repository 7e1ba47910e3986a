"""``drape motion``: list, make, import, export and check labelled motions."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

from datagen.cli import args as checks
from datagen.errors import InputError


MOTION_BYTES_PER_FRAME = 12_000
"""Peak host memory of ``make_motion`` per frame [bytes]: measured 11.2 kB (tracemalloc, walk, 2,000 and
20,000 frames, 2026-11-28)."""


def register(sub, formatter) -> None:
    motion = sub.add_parser(
        "motion", formatter_class=formatter, help="labelled motions: procedural, or read from AMASS/BVH",
        description="Labelled SMPL motions (24 joints, axis-angle, metres): drape's procedural library, which "
        "needs no download, or AMASS .npz and BVH files you have.",
        epilog="examples:\n  drape motion list\n  drape motion make --label walk --seed 3 --frames 120 --out walk.npz\n"
        "  drape motion import clip.bvh --label-name dance_sway --out clip.npz\n"
        "  drape motion export walk.npz --format usd --out walk.usda",
    )
    msub = motion.add_subparsers(dest="motion_command", metavar="MOTION_COMMAND")
    msub.required = True

    p = msub.add_parser("list", formatter_class=formatter, help="the procedural labels with their style parameters",
                        description="Every label drape generates, its class index and its style parameters with "
                        "their ranges (the seed draws each uniformly from its range).",
                        epilog="example:\n  drape motion list --json")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.set_defaults(func=_cmd_list)

    p = msub.add_parser("make", formatter_class=formatter, help="generate one procedural motion",
                        description="Generate a motion of a label, styled by a seed; the same arguments give the "
                        "same motion. Written as an AMASS-like .npz (poses [T, 72], trans, mocap_framerate, label).",
                        epilog="examples:\n  drape motion make --label walk --seed 3 --frames 120 --out walk.npz\n"
                        "  drape motion make --label squat --param depth=0.3 --param tempo=1.0 --out squat.npz")
    p.add_argument("--label", required=True, help="a label from `drape motion list`")
    p.add_argument("--seed", type=checks.seed, default=0, help="draws the style parameters")
    p.add_argument("--frames", type=checks.integer(2), default=120, help="number of frames")
    p.add_argument("--fps", type=checks.fps, default=30.0, help="frames per second")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="fix a style parameter instead of drawing it (repeatable)")
    p.add_argument("--out", required=True, type=checks.out_file(".npz"), help="output .npz")
    p.add_argument("--check", action="store_true",
                   help="also measure it on the default body (interpenetration, foot skate, joint limits, jerk)")
    p.set_defaults(func=_cmd_make)

    p = msub.add_parser("import", formatter_class=formatter, help="read an AMASS .npz or a BVH file into a drape motion",
                        description="Read a mocap file and write a drape motion .npz. AMASS (.npz: poses, trans, "
                        "mocap_framerate; SMPL, SMPL-H or SMPL-X) is converted to SMPL's 24 joints and to Y up. "
                        "BVH is retargeted by joint names (CMU, Mixamo and SMPL names built in; --joint-map for "
                        "others), with its units guessed from the skeleton's height unless --scale is given.",
                        epilog="examples:\n  drape motion import 01_01_poses.npz --label-map labels.json --out a.npz\n"
                        "  drape motion import 02_01.bvh --label-name walk --fps 30 --out b.npz\n"
                        "  drape motion import take.bvh --joint-map map.yaml --scale 0.01 --label-name box --out c.npz")
    p.add_argument("file", help="an AMASS .npz or a .bvh file")
    p.add_argument("--out", required=True, type=checks.out_file(".npz"), help="output .npz")
    p.add_argument("--label-map", help="JSON/YAML file: {patterns: {glob: label_name}} (first match wins)")
    p.add_argument("--label-name", help="label of this file (overrides the map)")
    p.add_argument("--allow-unlabelled", action="store_true", help="accept a file no label matches (label -1)")
    p.add_argument("--new-label", action="store_true",
                   help="allow a --label-name that is not one of drape's labels (`drape motion list`): a new class")
    p.add_argument("--fps", type=checks.fps, help="resample to this frame rate")
    p.add_argument("--up-axis", choices=["y", "z"], help="the file's up axis (default: z for AMASS, y for BVH)")
    p.add_argument("--joint-map", help="BVH only: JSON/YAML {bvh_joint: smpl_joint or null}")
    p.add_argument("--scale", type=checks.number(0, above=True), help="BVH only: metres per file unit (default: guessed)")
    p.set_defaults(func=_cmd_import)

    p = msub.add_parser("export", formatter_class=formatter, help="write a motion as BVH or as a USD animation of the body",
                        description="Write a drape motion .npz so a standard viewer can play it: BVH of the SMPL "
                        "skeleton (Blender, MotionBuilder), or USD with the posed body mesh per frame (usdview, "
                        "Omniverse, Blender).",
                        epilog="examples:\n  drape motion export walk.npz --format bvh --out walk.bvh\n"
                        "  drape motion export walk.npz --format usd --body fat --out walk.usda")
    p.add_argument("file", help="a drape motion .npz (from `make` or `import`)")
    p.add_argument("--format", choices=["bvh", "usd"], required=True, help="output format")
    p.add_argument("--out", required=True, type=checks.out_file(".bvh", ".usd", ".usda", ".usdc"),
                   help="output file (.bvh; .usd, .usda or .usdc)")
    p.add_argument("--body", default="regular", help="body shape preset for the skeleton and mesh: thin, regular, fat")
    p.set_defaults(func=_cmd_export)


def _cmd_list(args) -> int:
    from datagen.motion.labels import LABELS
    from datagen.motion.library import LABEL_PARAMS

    if args.json:
        print(json.dumps({name: {"class": i, "params": {k: {"low": s.low, "high": s.high, "doc": s.doc}
                                                          for k, s in LABEL_PARAMS[name].items()}}
                          for i, name in enumerate(LABELS)}, indent=2))
        return 0
    print(f"{len(LABELS)} procedural labels (class index, name, style parameters [range]):")
    common = ("tempo", "amplitude", "phase", "asymmetry", "arm_swing", "stance")
    for i, name in enumerate(LABELS):
        extra = ", ".join(f"{k} [{s.low:g}, {s.high:g}]" for k, s in LABEL_PARAMS[name].items() if k not in common)
        print(f"  {i:2d} {name:14s} {extra}")
    specs = LABEL_PARAMS["walk"]
    print("every label also has: " + ", ".join(f"{k} [{specs[k].low:g}, {specs[k].high:g}] ({specs[k].doc})"
                                               for k in common))
    return 0


def _cmd_make(args) -> int:
    from datagen.motion.library import make_motion
    from datagen.params import parse_param_args

    checks.check_memory(args.frames * MOTION_BYTES_PER_FRAME, f"--frames {args.frames}", "make fewer frames")
    t0 = time.perf_counter()
    motion = make_motion(args.label, seed=args.seed, frames=args.frames, fps=args.fps, params=parse_param_args(args.param))
    seconds = time.perf_counter() - t0
    out = Path(args.out)
    motion.save_npz(out)
    print(f"wrote {out}: {motion.label_name} (class {motion.label}), seed {args.seed}, {motion.frame_count} frames "
          f"at {motion.fps:g} fps ({seconds * 1000:.0f} ms)")
    if args.check:
        from datagen.body.cache import default_body
        from datagen.motion.quality import BodyProbe, measure_motion

        q = measure_motion(motion, BodyProbe(default_body()))
        print(f"check: interpenetration {q.penetration_share:.1%} of frames, forearms at least "
              f"{q.arm_leg_clearance * 100:.1f} cm from the legs, foot skate {q.foot_skate * 100:.2f} cm/s, "
              f"ground penetration {q.ground_penetration * 1000:.1f} mm, joint-limit violations "
              f"{q.limit_violation_share:.1%} of frames, jerk {q.jerk_mean:.0f} m/s^3 (mean)")
    return 0


_FLAGS = (("label_map (a pattern file)", "--label-map FILE (patterns)"), ("label_map", "--label-map"),
          ("label_name=...", "--label-name NAME"), ("label_name", "--label-name"),
          ("allow_unlabelled=True", "--allow-unlabelled"), ("joint_map=", "--joint-map"), ("joint_map", "--joint-map"),
          ("pass scale=", "pass --scale"), ("scale=", "--scale"), ("the new fps", "--fps"))


def _as_flags(message: str) -> str:
    """A library message with its Python argument names as this command's flags."""
    for name, flag in _FLAGS:
        message = message.replace(name, flag)
    return message


def _cmd_import(args) -> int:
    from datagen.motion.labels import LABELS

    path = Path(args.file)
    out = Path(args.out)
    suffix = path.suffix.lower()
    if not path.is_file():
        raise InputError(f"{path} does not exist" if not path.exists() else f"{path} is not a file")
    if out.suffix.lower() != ".npz":
        raise InputError(f"--out {out}: a drape motion is written as .npz")
    if not out.parent.is_dir():
        raise InputError(f"--out {out}: the folder {out.parent} does not exist; create it first")
    if args.scale is not None and not (math.isfinite(args.scale) and args.scale > 0):
        raise InputError(f"--scale must be a positive number of metres per file unit, got {args.scale:g}")
    if args.fps is not None and not (math.isfinite(args.fps) and 1 <= args.fps <= 240):
        raise InputError(f"--fps must be between 1 and 240 frames per second, got {args.fps:g}")
    if not (args.label_name or args.label_map or args.allow_unlabelled):
        raise InputError(f"no label for {path.name}: pass --label-name NAME (one of `drape motion list`), --label-map "
                         "FILE (patterns to labels), or --allow-unlabelled to read it as label -1")
    if args.label_name and args.label_name not in LABELS and not args.new_label and not args.label_map:
        raise InputError(f"--label-name {args.label_name!r} is not one of drape's labels ({', '.join(LABELS)}); pass "
                         f"--new-label to add it as a new class ({len(LABELS)}), or choose one of them")
    common = {"label_name": args.label_name, "fps": args.fps, "allow_unlabelled": args.allow_unlabelled}
    try:
        if suffix == ".bvh":
            from datagen.motion.bvh import read_bvh

            motion = read_bvh(path, args.joint_map, scale=args.scale, up_axis=args.up_axis or "y",
                              label_map=args.label_map, **common)
        elif suffix == ".npz":
            if args.joint_map or args.scale:
                raise InputError("--joint-map and --scale apply to BVH files only; AMASS files are in SMPL joints and "
                                 "metres")
            from datagen.motion.amass import read_amass

            motion = read_amass(path, args.label_map, up_axis=args.up_axis or "z", **common)
        else:
            raise InputError(f"{path}: unknown motion file type {suffix!r}; drape imports AMASS .npz and .bvh files")
    except InputError as exc:
        raise InputError(_as_flags(str(exc))) from None
    if motion.label_name not in LABELS and motion.label >= 0:
        print(f"note: {motion.label_name!r} is a new label (class {motion.label}); drape's own are "
              f"{', '.join(LABELS)}")
    motion.save_npz(out)
    print(f"wrote {out}: {motion.label_name} (class {motion.label}), {motion.frame_count} frames at {motion.fps:g} fps, "
          f"{motion.duration:.2f} s")
    return 0


def _cmd_export(args) -> int:
    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.motion.motion import Motion

    motion = Motion.load_npz(args.file)
    model = default_body()
    betas = resolve_betas(model, body=args.body)[0]
    if args.format == "bvh":
        from datagen.export.motion import write_motion_bvh

        out = write_motion_bvh(motion, args.out, model, betas)
    else:
        from datagen.export.motion import write_motion_usd

        out = write_motion_usd(motion, args.out, model, betas)
    print(f"wrote {out}: {motion.frame_count} frames at {motion.fps:g} fps")
    return 0
