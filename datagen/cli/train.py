"""``drape train``, ``drape evaluate``, ``drape predict`` and ``drape sample``: the model kinds of
``training.kinds`` (one ``drape train KIND`` per record; evaluate and predict dispatch on the run's kind)."""

from __future__ import annotations

import contextlib
import json
import shutil
import sys
from pathlib import Path

from datagen.cli import args as checks


def _run_arguments(p, config_class: str) -> None:
    """The arguments every `drape train MODEL` takes."""
    p.add_argument("--data", required=True, help="the dataset store")
    p.add_argument("--out", required=True, type=checks.out_dir, help="the run directory")
    p.add_argument("--config", default=None, help=f"training config (.toml/.yaml/.json; fields of {config_class})")
    p.add_argument("--epochs", type=checks.count, default=None, help="most epochs (overrides the config)")
    p.add_argument("--max-minutes", type=checks.number(0, above=True), default=None,
                   help="wall-time limit in minutes (overrides the config); with --resume the limit counts the "
                        "time already trained, so give the new total")
    p.add_argument("--device", default="auto", help="cpu, cuda or auto")
    again = p.add_mutually_exclusive_group()  # both together: refused before the run directory is touched
    again.add_argument("--resume", action="store_true", help="continue the run in --out from its last checkpoint")
    again.add_argument("--force", action="store_true", help="replace the run in --out")


def _train_config(cls, args, **overrides):
    """``cls`` from ``--config`` (or its defaults) with ``--epochs`` and the given command-line
    overrides (None: not given), checked by the strict loader."""
    from datagen.config import load_config

    data = load_config(cls, args.config).as_dict() if args.config else cls().as_dict()
    data |= {k: v for k, v in {**overrides, "epochs": args.epochs, "max_minutes": args.max_minutes}.items()
             if v is not None}
    return load_config(cls, data)


def register(sub, formatter) -> None:
    p = sub.add_parser("train", formatter_class=formatter, help="train a model on a dataset store",
                       description="Train one of drape's models on a store's train split, choosing the checkpoint "
                       "on its val split. A run directory keeps the config, checkpoints (resume with --resume "
                       "after a kill), TensorBoard and CSV logs.",
                       epilog="examples:\n  drape train gnn --data small.zarr --out runs/gnn --device cuda\n"
                       "  drape train gnn --data small.zarr --out runs/no-parser --ablation no_parser\n"
                       "  torchrun --nproc-per-node 2 -m datagen.cli train gnn --data small.zarr --out runs/ddp")
    models = p.add_subparsers(dest="model", metavar="MODEL", required=True)
    from training.kinds import kinds

    for kind in kinds():
        k = models.add_parser(kind.name, formatter_class=formatter, help=kind.help, description=kind.description,
                              epilog=kind.epilog)
        config = kind.config if isinstance(kind.config, str) else f"{kind.config.__module__}:{kind.config.__name__}"
        _run_arguments(k, config.replace(":", "."))
        if kind.arguments is not None:
            kind.arguments(k)
        k.set_defaults(func=_cmd_train, kind=kind.name)
    f = models.add_parser("refine", formatter_class=formatter, help="paper 001's collision refinement of a regressor",
                          description="Fine-tune a garment regressor on motions sampled from a motion generator with "
                          "the collision loss of paper 001 eq. 4 (no ground truth), dropping sequences with heavy "
                          "interpenetration; writes a new run and prints the share of garment vertices inside the "
                          "body on held-out sampled motions before and after.",
                          epilog="example:\n  drape train refine --garment-model runs/skirt --motion-model runs/motion "
                          "--out runs/skirt-refined")
    f.add_argument("--garment-model", required=True)
    f.add_argument("--motion-model", required=True)
    f.add_argument("--out", required=True, type=checks.out_dir, help="the refined run directory")
    f.add_argument("--samples", type=checks.count, default=64, help="motions sampled for the fine-tuning")
    f.add_argument("--steps", type=checks.count, default=200, help="optimiser steps (one sequence each)")
    f.add_argument("--seed", type=checks.seed, default=0)
    f.add_argument("--device", default="auto")
    f.add_argument("--force", action="store_true", help="replace the run in --out")
    f.add_argument("--latent", default="posterior", choices=("posterior", "prior"),
                   help="where Z is drawn from: posterior (default), each label's Gaussian fitted to the training "
                        "posteriors; prior, N(0, I) as paper 001 (docs/training.md measures both)")
    f.set_defaults(func=_cmd_refine)

    p = sub.add_parser("sample", formatter_class=formatter, help="new motions from a trained generator",
                       description="Sample new motions of a label from a trained motion generator and write them "
                       "as the motion library's .npz files (drape motion export turns them into BVH or USD).",
                       epilog="example:\n  drape sample motion runs/motion --label walk --count 8 --seed 0 --out gen/")
    samplers = p.add_subparsers(dest="what", metavar="WHAT", required=True)
    s = samplers.add_parser("motion", formatter_class=formatter, help="motions of a label")
    s.add_argument("run", help="a run directory of `drape train motion`")
    s.add_argument("--label", required=True,
                   help="one of the labels the model was trained on; several separated by commas, or all (each "
                        "label's motions then go into OUT/<label>/, the model loaded once)")
    s.add_argument("--count", type=checks.integer(1, 100_000), default=8)
    s.add_argument("--seed", type=checks.seed, default=0)
    s.add_argument("--out", required=True, type=checks.out_dir, help="a directory for the .npz files")
    s.add_argument("--frames", type=checks.integer(2, 100_000), default=None,
                   help="frames per motion (default: the segment length it was trained on). `drape generate` "
                        "with file: motions needs the recorded frames plus the ramp (e.g. 75 for 60 recorded)")
    s.add_argument("--device", default="cpu", help="cpu, cuda or auto")
    s.add_argument("--latent", default="posterior", choices=("posterior", "prior"),
                   help="where Z is drawn from: posterior (default), each label's Gaussian fitted to the training "
                        "posteriors; prior, N(0, I) as paper 001 (docs/training.md measures both)")
    s.set_defaults(func=_cmd_sample_motion)
    c = samplers.add_parser("clothed", formatter_class=formatter, help="a body animation dressed by the regressor",
                            description="Paper 001's application: a new motion from the motion generator (or a "
                            "motion file: a drape, AMASS-imported or BVH-imported .npz), the garment predicted for it "
                            "by the garment regressor, body and garment written as one USD animation (checked by "
                            "usd-core's validator) and optionally a video.",
                            epilog="examples:\n  drape sample clothed runs --garment skirt --label dance_disco --seed 0 "
                            "--out anim.usd --video clip.mp4\n"
                            "  drape sample clothed --motion-model runs/motion --garment-model runs/skirt --label walk "
                            "--out walk.usd\n"
                            "  drape sample clothed --garment-model runs/skirt --motion walk.npz --out walk.usd")
    c.add_argument("runs", nargs="?", default=None,
                   help="a folder of runs: the motion generator and the garment regressors (a refined run is "
                        "preferred); or name the runs with --garment-model and --motion-model")
    c.add_argument("--garment", default=None, help="the garment type to dress (with RUNS; e.g. skirt, tshirt, pants)")
    c.add_argument("--garment-model", default=None, help="a run directory of `drape train garment`")
    c.add_argument("--motion-model", default=None, help="a run directory of `drape train motion` (with --label)")
    c.add_argument("--label", default=None, help="the motion's label (sampled from --motion-model)")
    c.add_argument("--motion", default=None, help="a motion .npz to dress instead of a sampled one")
    c.add_argument("--seed", type=checks.seed, default=0)
    c.add_argument("--out", required=True, type=checks.out_file(".usd", ".usda", ".usdc"), help="a .usd/.usda/.usdc file")
    c.add_argument("--video", default=None, type=checks.out_file(".mp4", ".gif"), help="also render a .mp4 or .gif of it")
    c.add_argument("--device", default="cpu", help="cpu, cuda or auto")
    c.add_argument("--no-push-out", action="store_true",
                   help="keep garment vertices that end inside the body (no post-process)")
    c.add_argument("--latent", default="posterior", choices=("posterior", "prior"),
                   help="where Z is drawn from: posterior (default), each label's Gaussian fitted to the training "
                        "posteriors; prior, N(0, I) as paper 001 (docs/training.md measures both)")
    c.set_defaults(func=_cmd_sample_clothed)

    p = sub.add_parser("evaluate", formatter_class=formatter, help="a trained model's errors on a split",
                       description="The evaluation of the run's model kind (its run.json says which). For a GNN "
                       "run, paper 000's Tables 1 and 2 on a split: mean per-vertex error (mm) of the coarse and "
                       "detailed predictions per body and overall, beside trivial baselines, "
                       "and the share of predicted vertices inside the body. For a motion-generator run, paper 001's "
                       "Table 3 (reconstruction RMSE and Hausdorff beside the label's mean pose) and Table 4 (FID, "
                       "recognition accuracy, diversity, multimodality of generated sets, with a recogniser trained "
                       "on the store's train split).")
    p.add_argument("run", help="a run directory of `drape train`")
    p.add_argument("--data", default=None, help="the store (default: the one it trained on)")
    p.add_argument("--split", default="test", choices=("train", "val", "test"))
    p.add_argument("--max-frames", type=checks.count, default=None, help="evaluate this many frames, drawn evenly")
    p.add_argument("--device", default="auto")
    p.add_argument("--json", default=None, type=checks.out_file(".json"), metavar="FILE", help="also write the figures as JSON")
    p.add_argument("--repetitions", type=checks.integer(1, 10_000), default=20,
                   help="motion generator: generated sets drawn for Table 4's figures (paper: 20)")
    p.add_argument("--no-generation", action="store_true",
                   help="motion generator: Table 3's reconstruction only (no recogniser, no generated sets)")
    p.set_defaults(func=_cmd_evaluate)

    p = sub.add_parser("predict", formatter_class=formatter, help="predict a sample's garment with a trained model",
                       description="Predict every frame of a store sample and write it as USD (the body and the "
                       "predicted garment coloured by its per-vertex error, 0 to --max-error mm) and as an .npz "
                       "for `drape preview STORE --sample ID --prediction PRED.npz --color-by error`.")
    p.add_argument("run")
    p.add_argument("--data", required=True)
    p.add_argument("--sample", type=checks.integer(0), required=True)
    p.add_argument("--out", required=True, type=checks.out_file(".usd", ".usda", ".usdc"),
                   help="a .usd/.usda/.usdc file (the .npz goes beside it)")
    p.add_argument("--max-error", type=checks.number(0, above=True), default=30.0, help="error (mm) shown as the hottest colour")
    p.set_defaults(func=_cmd_predict)


def _diverged(result: dict, config) -> int:
    """Exit status of a train command: 1 with one line when the run diverged (NaN), else 0."""
    from training.loop import divergence_note

    note = divergence_note(result, config.precision)
    if note:
        print(note)
        return 1
    return 0


def _cmd_train(args) -> int:
    from training.kinds import get_kind

    kind = get_kind(args.kind)
    config = _train_config(kind.config_class(), args, **kind.overrides(args))
    if args.force and (Path(args.out) / "run.json").is_file():
        # --force deletes the run there: every shard the new run reads is checked first, so that a damaged
        # store is refused while the old run is still there
        from datagen.store import open_store

        open_store(args.data).check_files()
    with _kept_only_if_started(Path(args.out)):
        result = kind.part("train")(args.data, args.out, config, device=args.device, resume=args.resume,
                                    force=args.force)
    report = kind.part("report")
    print(report(result, config) if report is not None else
          f"trained {result['epochs']} epochs in {result['seconds']:.0f} s; best validation value {result['best']} "
          f"({result['best_checkpoint']})")
    return _diverged(result, config)


@contextlib.contextmanager
def _kept_only_if_started(out: Path):
    """A run directory that this command created is removed again when the command is refused (a
    :class:`~datagen.errors.DrapeError`, e.g. a damaged store found by a DataLoader worker) before the
    run wrote its first checkpoint: a refusal leaves nothing behind. One that was there is left as it is."""
    from datagen.errors import DrapeError

    existed = out.exists()
    try:
        yield
    except DrapeError:
        if not existed and out.is_dir() and not any((out / "checkpoints").glob("*.ckpt")):
            shutil.rmtree(out, ignore_errors=True)
        raise


def _cmd_refine(args) -> int:
    from training.garment.refine import refine_garment

    if args.seed < 0:
        from datagen.errors import InputError

        raise InputError(f"--seed must be 0 or more, got {args.seed}")
    with _kept_only_if_started(Path(args.out)):
        r = refine_garment(args.garment_model, args.motion_model, args.out, samples=args.samples, steps=args.steps,
                           seed=args.seed, device=args.device, force=args.force, latent=args.latent)
    print(f"refined {args.garment_model} into {args.out}: {r['steps']} steps on {r['sampled'] - r['dropped']} sampled "
          f"motions ({r['dropped']} dropped for heavy interpenetration), loss {r['loss_first']:.4f} -> "
          f"{r['loss_last']:.4f}; garment vertices inside the body on {r['held_out']} held-out sampled motions: "
          f"{100 * r['inside_share_before']:.2f} % -> {100 * r['inside_share_after']:.2f} %")
    return 0


def _cmd_sample_motion(args) -> int:
    import time

    from training.motion.run import sample_motions

    t0 = time.perf_counter()
    paths = sample_motions(args.run, args.label, args.count, args.seed, args.out, device=args.device,
                           frames=args.frames, latent=args.latent)
    print(f"wrote {len(paths)} motions of {args.label} into {args.out} ({time.perf_counter() - t0:.1f} s): "
          f"{paths[0].name} .. {paths[-1].name}; e.g. drape motion export {paths[0]} --format bvh --out "
          f"{paths[0].with_suffix('.bvh')}")
    return 0


def _cmd_sample_clothed(args) -> int:
    import time

    from datagen.errors import InputError
    from datagen.export.animation import Animation
    from datagen.export.usd import usd_validation_errors
    from training.garment.run import clothed_runs, dress_motion

    out = Path(args.out)
    if out.suffix.lower() not in (".usd", ".usda", ".usdc"):
        raise InputError(f"--out {out}: write a .usd, .usda or .usdc file")
    for p in (out, Path(args.video) if args.video else None):
        if p is not None and not p.parent.is_dir():
            raise InputError(f"{p}: the folder {p.parent} does not exist; create it first")
    if args.video and Path(args.video).suffix.lower() not in (".mp4", ".gif"):
        raise InputError(f"--video {args.video}: write a .mp4 or .gif")
    if args.seed < 0:
        raise InputError(f"--seed must be 0 or more, got {args.seed}")
    garment_run, motion_run = clothed_runs(args.runs, args.garment, garment_run=args.garment_model,
                                           motion_run=args.motion_model, need_motion=args.motion is None)
    t0 = time.perf_counter()
    d = dress_motion(garment_run, motion_run=motion_run, label=args.label, motion_file=args.motion,
                     seed=args.seed, device=args.device, push_out_margin=None if args.no_push_out else 0.002,
                     latent=args.latent)
    anim = Animation(body_vertices=d["body_vertices"].astype("float32"), body_faces=d["body_faces"],
                     garment_vertices=d["garment_vertices"].astype("float32"), garment_faces=d["garment_faces"],
                     fps=d["fps"], title=f"{d['label']}, {d['garment']} (paper 001's models)",
                     metadata={"drape:label": str(d["label"]), "drape:garment": d["garment"],
                               "drape:seed": int(args.seed)})
    anim.write_usd(out)
    problems = usd_validation_errors(out)
    if problems:
        raise InputError(f"{out} was written but usd-core's validator found: {'; '.join(problems[:5])}")
    T = len(d["garment_vertices"])
    print(f"wrote {out}: {d['label']} dressed in a {d['garment']}, {T} frames at {d['fps']:g} fps; the regressor took "
          f"{1000 * d['seconds'] / T:.1f} ms a frame; garment vertices inside the body {100 * d['inside_share_predicted']:.1f} % "
          f"as predicted, {100 * d['inside_share']:.1f} % written"
          f"{'' if args.no_push_out else ' (after the push-out)'}; {time.perf_counter() - t0:.1f} s in all; usd-core's "
          "validator: ok")
    if args.video:
        from datagen.export.preview import render_clip

        render_clip(anim, args.video)
        print(f"wrote {args.video}")
    return 0


def _run_kind(run: str):
    """The record of the model kind a run directory holds (one line for a directory that is not a
    run, and for a kind drape does not know)."""
    from datagen.errors import InputError
    from training.loop import RUN_FILE, run_meta
    from training.kinds import get_kind

    meta = run_meta(run)
    if meta is None:
        raise InputError(f"{run} is not a drape run directory (no {RUN_FILE}); give the --out of `drape train`")
    return get_kind(meta.get("kind"))


def _cmd_evaluate(args) -> int:
    from datagen.cli.progress import reporter
    from datagen.errors import InputError
    from training.kinds import EvaluateRequest

    kind = _run_kind(args.run)
    if kind.evaluate is None:
        raise InputError(f"{args.run} holds a {kind.name!r} model, which has no evaluation")
    progress = reporter(f"evaluating on {args.split}", "frame")
    e = kind.part("evaluate")(EvaluateRequest(run=args.run, data=args.data, split=args.split, device=args.device,
                                              max_frames=args.max_frames, repetitions=args.repetitions,
                                              generation=not args.no_generation, progress=progress))
    progress.close()
    print(kind.part("format_evaluation")(e))
    if args.json:
        Path(args.json).write_text(json.dumps(e, indent=2))
        print(f"wrote {args.json}", file=sys.stderr)
    return 0


def _kinds():
    from training.kinds import kinds

    return kinds()


def _cmd_predict(args) -> int:
    from dataclasses import replace

    import numpy as np

    from datagen.errors import InputError
    from datagen.export.animation import from_store
    from datagen.store import open_store

    if not 0 < args.max_error < float("inf"):  # checked before the model runs (NaN fails too)
        raise InputError(f"--max-error is the error (mm) drawn as the hottest colour: give a number > 0, got "
                         f"{args.max_error:g}")
    kind = _run_kind(args.run)
    if kind.predict is None:
        raise InputError(f"{args.run} holds a {kind.name!r} model; drape predict predicts with "
                         f"{', '.join(k.name for k in _kinds() if k.predict is not None)} runs")
    p = kind.part("predict")(args.run, args.data, args.sample)
    anim = from_store(open_store(args.data), args.sample)
    out = Path(args.out)
    error_mm = 1000 * p["error"]
    t = np.clip(error_mm / args.max_error, 0, 1)[..., None]
    colours = (1 - t) * np.array([0.20, 0.35, 0.85]) + t * np.array([0.90, 0.15, 0.10])  # blue (0) to red (max)
    pred = replace(anim, garment_vertices=p["detail"].astype(np.float32))
    pred.write_usd(out, garment_colors=colours, garment_values=("error_mm", error_mm))
    npz = out.with_suffix(".npz")
    np.savez(npz, garment_vertices=p["detail"].astype(np.float32), coarse=p["coarse"].astype(np.float32),
             error_mm=error_mm.astype(np.float32))
    print(f"wrote {out} and {npz}: sample {args.sample}, {len(error_mm)} frames, mean error {error_mm.mean():.2f} mm "
          f"(max {error_mm.max():.1f}); preview: drape preview {args.data} --sample {args.sample} --prediction {npz} "
          "--color-by error")
    return 0
