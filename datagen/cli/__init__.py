"""The ``drape`` command line. Each capability registers its own subcommands.

Library code logs; this module prints. A :class:`~datagen.errors.DrapeError` is shown as one
line (``error: ...``) with exit status 2 (1 for a damaged store, as ``drape validate`` gives), never as
a traceback.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys

from datagen import __version__
from datagen.errors import DrapeError


class _Formatter(argparse.RawDescriptionHelpFormatter, argparse.ArgumentDefaultsHelpFormatter):
    pass


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="drape",
        formatter_class=_Formatter,
        description="drape makes training data for learned garment animation: SMPL-format bodies, "
        "garments draped by a Warp cloth simulator, zarr datasets, and the trainers that use them.",
        epilog="example:\n  drape body build --out body.pkl\n  drape body info",
    )
    parser.add_argument("--version", action="version", version=f"drape {__version__}")
    parser.add_argument("--log-level", default="info", choices=["debug", "info", "warning", "error"],
                        help="how much progress to print")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    from datagen.cli import body as body_cli
    from datagen.cli import card as card_cli
    from datagen.cli import export as export_cli
    from datagen.cli import garment as garment_cli
    from datagen.cli import generate as generate_cli
    from datagen.cli import motion as motion_cli
    from datagen.cli import simulate as sim_cli
    from datagen.cli import train as train_cli

    body_cli.register(sub, _Formatter)
    motion_cli.register(sub, _Formatter)
    garment_cli.register(sub, _Formatter)
    sim_cli.register(sub, _Formatter)
    generate_cli.register(sub, _Formatter)
    export_cli.register(sub, _Formatter)
    card_cli.register(sub, _Formatter)
    train_cli.register(sub, _Formatter)
    return parser


_WARP_COMMANDS = frozenset({"garment", "simulate", "generate", "export", "preview", "predict", "card"})
"""Commands that run warp kernels (initialised quietly up front)."""

_RESUME_HINTS = {
    "generate": "what was staged is kept: run the same command again and it resumes from there",
    "train": "the last finished epoch is in checkpoints/last.ckpt: run the same command with --resume to continue",
}


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # a refused argument (datagen.cli.args): argparse printed its one line
        if exc.code == 2:
            return 2
        raise  # --help, --version
    logging.basicConfig(level=getattr(logging, args.log_level.upper()), format="%(message)s", stream=sys.stderr)
    for noisy in ("anny", "warp", "trimesh"):
        logging.getLogger(noisy).setLevel(max(logging.WARNING, logging.getLogger().level))
    if args.log_level != "debug":  # matplotlib's one-time "building the font cache" notice: debug only
        logging.getLogger("matplotlib.font_manager").setLevel(logging.ERROR)
    if args.log_level != "debug":  # warp's banner, kernel-compile lines and CPU-only driver notice: debug only
        try:
            from datagen.sim.device import quiet_warp

            quiet_warp(logging.ERROR, initialise=args.command in _WARP_COMMANDS)
        except ImportError:  # warp missing: the commands that need it say so
            pass
    try:
        return int(args.func(args) or 0)
    except DrapeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return getattr(exc, "exit_status", 2)  # 1 for a damaged store (what `drape validate` finds), else 2
    except KeyboardInterrupt:
        hint = _RESUME_HINTS.get(args.command)
        print("interrupted" + (f"; {hint}" if hint else ""), file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into `head` and the like: stop quietly
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
