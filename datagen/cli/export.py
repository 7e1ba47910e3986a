"""``drape export usd`` and ``drape preview``: a store sample, a ``drape simulate`` result or an
``.npz`` of plain arrays (e.g. a model's prediction) to an animated USD file, a PNG, a GIF or an MP4."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from datagen.cli import args as checks
from datagen.errors import InputError

logger = logging.getLogger(__name__)

_SOURCE_HELP = ("a dataset store directory (with --sample), a 'drape simulate' result .npz, or an .npz of plain "
                "arrays (garment_vertices, garment_faces, body_vertices, body_faces, fps; see docs/export.md)")


def _add_npz_options(p) -> None:
    g = p.add_argument_group("for an .npz of plain arrays without an fps")
    g.add_argument("--fps", type=checks.number(0, above=True), default=None, help="its frame rate (None: the file's, else 30)")


def register(sub, formatter) -> None:
    p = sub.add_parser("export", formatter_class=formatter, help="write samples as animated USD files",
                       description="Export the body and the garment of a sample as animation files.",
                       epilog="examples:\n  drape export usd tiny.zarr --sample 5 --out anim.usd\n"
                       "  drape export usd tiny.zarr --split test --out usd/\n"
                       "  drape export usd run.npz --out run.usda --skeleton")
    fmt = p.add_subparsers(dest="format", metavar="FORMAT")
    fmt.required = True
    u = fmt.add_parser("usd", formatter_class=formatter, help="animated USD: body and garment meshes (+ UsdSkel rig)",
                       description="Write the body and the garment as separate meshes with time-sampled points, "
                       "normals and extents (frame k at time code k, the store's fps, Y up, metres), the garment's "
                       "region labels as the int primvar 'drape:region' with the names in customData, display "
                       "colours, and what the sample is in the root prim's customData. With --skeleton the body is a "
                       "UsdSkel rig instead: Skeleton (SMPL joints, rest and bind transforms), SkelAnimation "
                       "(per-frame joint rotations and root translation) and the body mesh bound with the body "
                       "model's skinning weights. Failed samples have no frames: exporting one is refused, and "
                       "--split/--all skip them with a warning. Files are written to a temporary name and renamed.",
                       epilog="examples:\n  drape export usd tiny.zarr --sample 5 --out anim.usd\n"
                       "  drape export usd tiny.zarr --sample 5 --out anim.usda --skeleton --validate\n"
                       "  drape export usd tiny.zarr --split test --out usd/           (one file per sample)\n"
                       "  drape export usd tiny.zarr --all --out usd/ --format usda\n"
                       "  drape export usd run.npz --out run.usd                        (a drape simulate result)")
    u.add_argument("source", help=_SOURCE_HELP)
    which = u.add_mutually_exclusive_group()
    which.add_argument("--sample", type=checks.integer(0), default=None, help="sample id of the store")
    which.add_argument("--split", default=None, help="every sample of this split (train, val, test)")
    which.add_argument("--all", action="store_true", help="every sample of the store")
    u.add_argument("--out", required=True, type=checks.out_path, help="the .usd/.usda/.usdc file; with --split/--all a directory")
    u.add_argument("--format", dest="usd_format", default="usd", choices=("usd", "usda", "usdc"),
                   help="file type of each file written with --split/--all (usd: binary crate)")
    u.add_argument("--skeleton", action="store_true", help="write the body as a UsdSkel skeleton, animation and "
                   "skinned mesh")
    u.add_argument("--no-normals", action="store_true", help="do not write vertex normals")
    u.add_argument("--validate", action="store_true", help="run usd-core's validators on every file written")
    _add_npz_options(u)
    u.set_defaults(func=_cmd_export_usd)

    p = sub.add_parser("preview", formatter_class=formatter, help="render a frame (PNG) or a clip (GIF, MP4)",
                       description="Render the body and the garment offscreen on the CPU (matplotlib, painter's "
                       "algorithm, Lambert shading) from a chosen view: one frame to a PNG, or a sequence of frames "
                       "to a GIF (Pillow) or an MP4 (needs imageio-ffmpeg). --color-by colours the garment by region "
                       "(with a legend) or by a per-vertex quantity with a colour bar: stretch (per-vertex mean of "
                       "edge length / rest length - 1, %), body-distance (signed distance to the posed body "
                       "surface, mm, negative inside) or error (distance from a prediction given with --prediction "
                       "to the simulation, mm; the prediction is drawn).",
                       epilog="examples:\n  drape preview tiny.zarr --sample 5 --frame 30 --out frame.png\n"
                       "  drape preview tiny.zarr --sample 5 --view three-quarter --color-by stretch --out f.png\n"
                       "  drape preview tiny.zarr --sample 5 --frames 0:60:2 --out clip.gif\n"
                       "  drape preview tiny.zarr --sample 5 --view 30 --color-by body-distance --out clip.mp4\n"
                       "  drape preview tiny.zarr --sample 5 --prediction pred.npz --color-by error --out err.png")
    p.add_argument("source", help=_SOURCE_HELP)
    p.add_argument("--sample", type=checks.integer(0), default=None, help="sample id of the store")
    p.add_argument("--out", required=True, type=checks.out_file(".png", ".gif", ".mp4"), help="frame.png, or clip.gif / clip.mp4")
    p.add_argument("--frame", default=None, help="the frame of a PNG (default 0)")
    p.add_argument("--frames", default=None, help="frames of a clip: A:B[:step] (default: all)")
    p.add_argument("--view", default="front", help="front, side, back, three-quarter, or an azimuth in degrees")
    p.add_argument("--color-by", default="none", choices=("none", "region", "stretch", "body-distance", "error"),
                   help="colour of the garment")
    p.add_argument("--range", dest="value_range", default=None, metavar="LO:HI",
                   help="colour bar range in its units (default: from the frames shown)")
    p.add_argument("--prediction", default=None, help="an .npz with garment_vertices [T, V, 3] predicted for the "
                   "sample's T frames: drawn instead of the simulation (needed by --color-by error)")
    p.add_argument("--size", default="512x640", help="picture size WIDTHxHEIGHT in pixels (even numbers)")
    p.add_argument("--clip-fps", type=checks.number(0, above=True), default=None, help="frame rate of a clip (default: the source's fps "
                   "divided by the frame step)")
    _add_npz_options(p)
    p.set_defaults(func=_cmd_preview)


def _npz_options(args) -> dict:
    return {"fps": args.fps}


def _mb(path: Path) -> str:
    return f"{path.stat().st_size / 1e6:.1f} MB"


def _validate(path: Path) -> list[str]:
    from datagen.export.usd import usd_validation_errors

    problems = usd_validation_errors(path)
    for p in problems:
        print(f"  {path}: {p}")
    print(f"  usd-core validators: {len(problems)} problem(s)" if problems else "  usd-core validators: no problems")
    return problems


def _cmd_export_usd(args) -> int:
    from datagen.errors import require
    from datagen.export.animation import from_npz, from_store
    from datagen.files import check_output_dir, check_output_path
    from datagen.export.usd import USD_SUFFIXES

    require("pxr", "USD export", extra="usd")
    source = Path(args.source)
    normals = not args.no_normals
    bulk = args.split is not None or args.all
    if not source.is_dir():
        if bulk or args.sample is not None:
            raise InputError(f"{source} is not a store; --sample, --split and --all are for stores")
        out = check_output_path(args.out, USD_SUFFIXES, "USD file")
        anim = from_npz(source, **_npz_options(args))
        path = anim.write_usd(out, skeleton=args.skeleton, normals=normals)
        print(f"wrote {path}: {anim.title}, {anim.frame_count} frames at {anim.fps:g} fps, "
              f"{_mb(path)}")
        return 1 if args.validate and _validate(path) else 0

    from datagen.store import open_store

    store = open_store(source)
    if not bulk:
        if args.sample is None:
            raise InputError(f"{source} is a store: say what to export with --sample ID, --split NAME or --all")
        out = check_output_path(args.out, USD_SUFFIXES, "USD file")
        anim = from_store(store, args.sample, skeleton=args.skeleton)
        path = anim.write_usd(out, skeleton=args.skeleton, normals=normals)
        print(f"wrote {path}: {anim.title}, {anim.frame_count} frames at {anim.fps:g} fps, {_mb(path)}")
        return 1 if args.validate and _validate(path) else 0

    indices = store.split(args.split) if args.split is not None else np.arange(len(store))
    store.check_files(indices.tolist())  # a damaged shard refuses before the first file is written
    out_dir = check_output_dir(args.out, "output directory")
    written, skipped, invalid = [], [], 0
    failure = store.index["failure"]
    for i in indices:
        i = int(i)
        if failure[i] != 0 and store.frame_count(i) == 0:
            logger.warning("sample %d failed (%s) and has no recorded frames: skipped", i,
                           store.names["failure_names"][failure[i]] if failure[i] < len(store.names["failure_names"])
                           else failure[i])
            skipped.append(i)
            continue
        anim = from_store(store, i, skeleton=args.skeleton)
        path = anim.write_usd(out_dir / f"sample{i:05d}.{args.usd_format}", skeleton=args.skeleton, normals=normals)
        print(f"wrote {path}: {anim.title}, {anim.frame_count} frames, {_mb(path)}", flush=True)
        written.append(i)
        if args.validate and _validate(path):
            invalid += 1
    what = f"split {args.split}" if args.split is not None else "the store"
    print(f"{len(written)} of {len(indices)} samples of {what} written to {out_dir}"
          + (f"; skipped {len(skipped)} failed samples without frames: {skipped}" if skipped else "")
          + (f"; {invalid} file(s) failed validation" if invalid else ""))
    return 1 if invalid else 0


def _parse_range(text: str | None) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise InputError(f"--range must be LO:HI (two numbers), got {text!r}") from None
    if not hi > lo:
        raise InputError(f"--range needs LO < HI, got {text!r}")
    return lo, hi


def _load_prediction(path: str, frame_count: int) -> np.ndarray:
    from datagen.export.animation import read_npz

    p = Path(path)
    d = read_npz(p, "prediction file")
    if "garment_vertices" not in d:
        raise InputError(f"{p} has no 'garment_vertices' array (the predicted garment [T, V, 3]); it has {sorted(d)}")
    pred = np.asarray(d["garment_vertices"], np.float32)
    if pred.ndim != 3 or pred.shape[0] != frame_count:
        raise InputError(f"the prediction in {p} has shape {pred.shape}; the sample has {frame_count} frames")
    if not np.isfinite(pred).all():
        raise InputError(f"the prediction in {p} has non-finite values (NaN or inf) in frame(s) "
                         f"{np.flatnonzero(~np.isfinite(pred).all(axis=(1, 2)))[:10].tolist()}")
    return pred


def _cmd_preview(args) -> int:
    from datagen.export.animation import check_sample, from_npz, from_store, parse_frames
    from datagen.files import check_output_path
    from datagen.export.preview import (
        CLIP_SUFFIXES,
        IMAGE_SUFFIXES,
        parse_size,
        parse_view,
        render_clip,
        render_frame,
    )

    out = check_output_path(args.out, IMAGE_SUFFIXES + CLIP_SUFFIXES, "picture or clip")
    clip = out.suffix.lower() in CLIP_SUFFIXES
    if clip and args.frame is not None:
        raise InputError(f"{out.name} is a clip: choose its frames with --frames A:B[:step], not --frame")
    if not clip and args.frames is not None:
        raise InputError("a PNG holds one frame: use --frame N, or --out clip.gif / clip.mp4 for --frames")
    size, view = parse_size(args.size), parse_view(args.view)  # fail early
    value_range = _parse_range(args.value_range)
    spec = args.frames if clip else (args.frame if args.frame is not None else "0")
    source = Path(args.source)
    if source.is_dir():
        from datagen.store import open_store

        store = open_store(source)
        if args.sample is None:
            raise InputError(f"{source} is a store: say which sample with --sample ID")
        i = check_sample(store, args.sample)
        T = store.frame_count(i)
        if T == 0:
            from_store(store, i)  # raises: a failed sample without frames
        index = parse_frames(spec, T)
        anim = from_store(store, i, frames=index)
    else:
        if args.sample is not None:
            raise InputError(f"{source} is not a store; --sample is for stores")
        full = from_npz(source, **_npz_options(args))
        from datagen.export.usd import check_animation

        check_animation(full)  # NaN positions or faces out of range: refused before drawing
        T = full.frame_count
        index = parse_frames(spec, T)
        anim = full.frames(index)
    prediction = _load_prediction(args.prediction, T)[index] if args.prediction else None
    if clip:
        step = int(np.median(np.diff(index))) if len(index) > 1 else 1
        fps = args.clip_fps if args.clip_fps is not None else anim.fps / max(step, 1)
        path = render_clip(anim, out, view=view, size=size, color_by=args.color_by, fps=fps, prediction=prediction,
                           value_range=value_range)
        print(f"wrote {path}: {anim.title}, frames {index[0]}..{index[-1]} ({len(index)} frames) at {fps:g} fps, "
              f"{size[0]}x{size[1]} pixels")
    else:
        path = render_frame(anim, out, frame=0, view=view, size=size, color_by=args.color_by,
                            prediction=prediction, value_range=value_range)
        print(f"wrote {path}: {anim.title}, frame {index[0]}, {size[0]}x{size[1]} pixels")
    return 0
