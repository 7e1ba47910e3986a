"""``drape generate``, ``drape validate`` and ``drape info``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from datagen.cli import args as checks
from datagen.errors import InputError


def register(sub, formatter) -> None:
    p = sub.add_parser("generate", formatter_class=formatter, help="simulate a dataset into a zarr store",
                       description="Turn a dataset config (garments x bodies x motions per split) into a validated "
                       "zarr store with detail and coarse targets, features and fit attributes. A killed run resumes "
                       "where it stopped; a finished store is left as it is; a store made from another config is "
                       "refused.",
                       epilog="examples:\n  drape generate --out tiny.zarr                 (the tiny preset)\n"
                       "  drape generate my.toml --out my.zarr --device cuda\n"
                       "  drape generate --preset paper-gnn --out gnn.zarr --executor ray --device cuda\n"
                       "  drape generate --preset medium --out medium.zarr --device cuda:0,cuda:1,cuda:2,cuda:3   "
                       "(four GPUs of this host)\n"
                       "  drape generate --preset paper-motion --out motion.zarr --device cuda --time-limit 50   "
                       "(again until it exits 0)\n"
                       "  drape generate --preset paper-motion --out motion.zarr --device cuda --batch-size 252   "
                       "(one batch)")
    p.add_argument("config", nargs="?", default=None, help="dataset config (.toml/.yaml); default: --preset tiny")
    p.add_argument("--preset", default=None, help="tiny (default), small, medium, paper-gnn, paper-motion; NAME-pattern / NAME-shell "
                   "for sewn pattern garments or shells (the plain names: datagen.generate.config.PRESET_GARMENTS)")
    p.add_argument("--out", required=True, type=checks.out_dir, help="the store directory")
    p.add_argument("--executor", default="local", choices=("local", "ray"))
    p.add_argument("--workers", type=checks.workers, default=None,
                   help="local: processes that build garments, compute targets and stage while the simulator runs "
                        "(default: cores - 1, at most 16; 0: none); ray: CPUs of the local Ray cluster (default: every core; "
                        "one task per GPU with --device cuda, else one per CPU)")
    p.add_argument("--device", default="cpu", help="warp device: cpu or cuda (cuda:N); local executor: several as a "
                   "comma list (cuda:0,cuda:1,...), one simulating process per device, each a share of the scenes")
    p.add_argument("--time-limit", type=checks.number(0, above=True), default=None, metavar="MINUTES",
                   help="local executor: start no batch that would not end within this many minutes (judged by the "
                        "last batch); what is simulated stays staged, the same command continues it, and the exit "
                        "status is 75 while the store is unfinished")
    # --batch-size: checked against the config's limits (1..4096) by with_batch_size, before anything is made
    p.add_argument("--batch-size", type=int, default=None, metavar="N",
                   help="scenes simulated together in one model, in place of the config's simulation.batch_size "
                        "(how the work is spread, not part of the store's identity: a run may be resumed with "
                        "another); e.g. a whole preset in one batch on a large GPU")
    p.add_argument("--print-config", action="store_true", help="print the resolved config and stop")
    p.set_defaults(func=_cmd_generate)
    p = sub.add_parser("validate", formatter_class=formatter, help="check a store against schemas/dataset.py",
                       description="Check that a store is complete and intact (every shard file present and unchanged "
                       "since pack, by the checksums pack recorded), then shapes, dtypes, units, offsets, finite "
                       "values, disjoint splits and the fit model, and that the dataset card beside it (README.md, "
                       "table/, croissant.json) says what the store holds; exit 1 and list every problem if any.")
    p.add_argument("store")
    p.add_argument("--quick", action="store_true",
                   help="structure only: metadata, every shard file present, offsets; no checksums, no values")
    p.set_defaults(func=_cmd_validate)
    p = sub.add_parser("info", formatter_class=formatter, help="splits, counts, sizes and failures of a store",
                       description="Print a store's splits, sample and frame counts, sizes on disk and failures; "
                       "with --plots also write PNG plots: samples per split, garment vertex counts, failure "
                       "reasons, and the distributions of the fit attribute α (per component) and of β.",
                       epilog="examples:\n  drape info tiny.zarr\n  drape info tiny.zarr --json\n  drape info tiny.zarr --samples\n"
                       "  drape info tiny.zarr --plots plots/   (splits, vertex_counts, failures, alpha, betas .png)")
    p.add_argument("store")
    p.add_argument("--json", action="store_true")
    p.add_argument("--config", action="store_true",
                   help="print only the config the store was made with (JSON, which is YAML: save it as .yaml and "
                        "give it to drape generate to make the store again)")
    p.add_argument("--plots", default=None, type=checks.out_dir, metavar="DIR", help="also write PNG plots into this directory")
    p.add_argument("--samples", action="store_true",
                   help="print only the per-sample table (one line per sample: garment, material, body, motion, "
                        "frames, gates, strain, penetration; all columns in STORE/table/*.parquet)")
    p.set_defaults(func=_cmd_info)


INCOMPLETE = 75
"""Exit status of ``drape generate --time-limit`` that stopped before the store was finished
(EX_TEMPFAIL: run it again)."""


def _cmd_generate(args) -> int:
    from datagen.generate.config import resolve_config, with_batch_size
    from datagen.generate.plan import Plan
    from datagen.generate.run import generate
    from datagen.store import format_store_info, store_info, validate

    config = resolve_config(args.config, args.preset)
    if args.batch_size is not None:
        config = with_batch_size(config, args.batch_size)
    if args.print_config:
        print(json.dumps(config.as_dict(), indent=2))
        return 0
    from datagen.cli.progress import reporter
    from datagen.generate.run import simulated_frames

    plan = Plan(config)
    rc = config.simulation
    sim = simulated_frames(plan)
    print(f"dataset: {plan.sample_count} scenes ({', '.join(f'{k} {v.scene_count}' for k, v in config.splits.items())}"
          f"), {len(plan.instances)} garment instances, {len(plan.bodies)} bodies, {len(plan.motions)} motions, "
          f"{config.frames} recorded frames each; device {args.device}, executor {args.executor}", flush=True)
    from datagen.generate.templates import settle_config
    from datagen.sim.scene import settled_frame

    ph = rc.phases(config.frames, config.fps)
    print(f"each scene simulates {sim} frames: {ph['settle_rest']} settling in the rest pose, {ph['lead_in']} leading "
          f"into the motion's first pose, {ph['settle_pose']} holding it and {ph['ramp']} ramping into the motion, then "
          f"the {ph['recorded']} that are recorded; first, each pattern garment instance is sewn on its body and "
          f"settled (at most {rc.sewing.most_frames()} frames; once static, that is its template) and each other "
          f"instance settles once at rest for its template ({settled_frame(settle_config(rc)) + 1} frames in the "
          "rest pose)", flush=True)
    side_by_side = args.executor == "ray" or "," in str(args.device)
    # Ray's tasks, or several devices, run side by side: the frame bar follows the furthest; else a
    # new batch restarts it
    frame_bar = reporter("frames", "frame", follow_furthest=side_by_side)
    scene_bar = reporter("scenes", "scene", follow_furthest=True)
    sew_bar = reporter("sewing", "garment", follow_furthest=True)

    def progress(kind, done, total, batch):
        if kind == 0:
            frame_bar(done, total, desc=f"batch of {batch} scenes")
        elif kind == 2:
            sew_bar(done, total)
        else:
            scene_bar(done, total)

    try:
        summary = generate(config, args.out, executor=args.executor, device=args.device, workers=args.workers,
                           progress=progress, time_limit=args.time_limit)
    finally:
        frame_bar.close()
        scene_bar.close()
        sew_bar.close()
    if not summary["complete"]:
        print(f"time limit of {args.time_limit:g} min: simulated {summary['simulated']} scenes in "
              f"{summary['batches']} batch(es) ({summary['seconds']:.0f} s, the simulator "
              f"{summary['simulate_seconds']:.0f} s); {summary['left']} of {summary['samples']} scenes are left "
              f"({summary['stopped']} batch(es)); run the same command again to continue", flush=True)
        return INCOMPLETE
    if summary["simulated"] == 0 and summary["seconds"] == 0.0:
        print(f"{args.out} is already complete for this config: nothing to do")
    info = store_info(args.out)
    print(format_store_info(info))
    frames = info["totals"]["frames"]
    if summary["seconds"] > 0 and summary["simulated"] < summary["samples"]:
        # a resumed run: the stored frames include scenes an earlier run simulated, so a rate over
        # this run's time would be wrong (a run that only packed read 174 garment-frames/s)
        print(f"simulated {summary['simulated']} of {summary['samples']} scenes in {summary['seconds']:.0f} s (the "
              f"others were staged by an earlier run, so no end-to-end rate is given); {frames} garment-frames stored")
    elif summary["seconds"] > 0:
        print(f"simulated {summary['simulated']} scenes in {summary['seconds']:.0f} s; {frames} garment-frames stored, "
              f"{frames / summary['seconds']:.2f} garment-frames/s end to end")
        if summary.get("simulate_seconds") and summary.get("simulator_garment_frames_per_second"):
            print(f"the simulator alone: {summary['simulator_garment_frames_per_second']:.2f} garment-frames/s "
                  f"({summary['simulate_seconds']:.0f} s in {summary['batches']} batch(es)); end to end is "
                  f"{summary['garment_frames_per_second'] / summary['simulator_garment_frames_per_second']:.2f}x "
                  f"that; the simulating process waited {summary['wait_seconds']:.1f} s for the workers")
        elif summary.get("simulate_seconds"):  # every scene failed: nothing recorded to give a rate of
            print(f"the simulator ran {summary['simulate_seconds']:.0f} s in {summary['batches']} batch(es) and every "
                  "scene failed, so no garment-frame was stored (drape info lists why)")
        for t in summary.get("tasks", []):
            if "device" in t:  # the local executor on several devices
                kind, gpu = "process", (f", CUDA_VISIBLE_DEVICES={t['cuda_visible_devices']}"
                                        if t["device"].startswith("cuda") else "")
                where = f"{t['device']} (pid {t['pid']}{gpu})"
            else:
                kind, where = "ray task", (f"GPU {t['gpus']} (CUDA_VISIBLE_DEVICES={t['cuda_visible_devices']})"
                                           if t["gpus"] else f"CPU (pid {t['pid']})")
            rate = f", {t['garment_frames'] / t['simulate_seconds']:.2f} garment-frames/s in the simulator" \
                if t["simulate_seconds"] else ""
            print(f"  {kind} {t['task']} on {t['host']} {where}: {t['samples']} scenes in {t['seconds']:.0f} s"
                  f"{rate}")
    problems = validate(args.out)
    if problems:
        print("validate found problems:\n  " + "\n  ".join(problems), file=sys.stderr)
        return 1
    print(f"drape validate {args.out}: ok")
    _card_pictures(Path(args.out))
    return 0


def _card_pictures(store: Path) -> None:
    """Draw the pictures beside the card pack wrote and list them in it (needs the render extra)."""
    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:
        print(f"dataset card: {store / 'README.md'} (no pictures: install drape[render] and run `drape card {store}`)")
        return
    from datagen.cli.card import write_card_with_pictures

    written = write_card_with_pictures(store, check_files=False)
    print(f"dataset card: {store / 'README.md'}, with {sum(p.suffix == '.png' for p in written)} pictures in "
          f"{store / 'card'}")


def _cmd_validate(args) -> int:
    from datagen.store import validate

    path = Path(args.store)
    if not path.exists():
        raise InputError(f"{path} does not exist; give a store directory made by drape generate")
    problems = validate(path, quick=args.quick)
    if not problems and not args.quick:  # a valid store: does its dataset card still say what it holds?
        from datagen.store.card import card_problems

        problems = card_problems(path)
    if problems and "is not a drape store" in problems[0]:  # not a store at all: a wrong argument, not damage
        raise InputError(problems[0].replace("is not a drape store", "is not a drape dataset store"))
    if problems:
        print(f"{args.store}: {len(problems)} problem(s)")
        for p in problems:
            print(f"  {p}")
        return 1
    print(f"{args.store}: valid")
    return 0


def _cmd_info(args) -> int:
    from datagen.store import format_store_info, store_info

    if args.config:
        from datagen.store.layout import read_root_attributes

        attrs = read_root_attributes(Path(args.store))
        if not attrs or "config" not in attrs:
            raise InputError(f"{args.store} is not a drape dataset store (no config in its zarr.json)")
        print(json.dumps(attrs["config"], indent=2))
        return 0
    if args.samples:
        from datagen.store.card import open_checked
        from datagen.store.samples_table import format_table, sample_table

        print(format_table(sample_table(open_checked(args.store, check_files=False))))
        return 0
    info = store_info(args.store)
    print(json.dumps(info, indent=2, default=str) if args.json else format_store_info(info))
    if info.get("damage"):  # missing shard files: what reads them would refuse; say so by the status too
        return 1
    if args.plots is not None:
        from datagen.export.plots import plot_store_info

        written = plot_store_info(args.store, args.plots)
        print(f"wrote {len(written)} plots to {args.plots}: {', '.join(p.name for p in written)}",
              file=sys.stderr if args.json else sys.stdout)
    return 0
