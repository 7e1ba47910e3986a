"""The argument checks every ``drape`` command uses: argparse ``type=`` callables, so a command that
declares its arguments with them refuses a bad value while its arguments are parsed, before it
reads, computes or writes anything (argparse prints one ``error:`` line and exits with status 2).

- :func:`out_file` / :func:`out_dir`: an output file (its suffix, its folder there and writable, not a
  directory) or an output directory (not a file, inside a writable folder).
- :func:`seed`, :func:`integer`, :func:`number`: integers and finite numbers in a range.
- :func:`check_memory`: a host-memory estimate checked before a large array is allocated.

A command adding an argument writes e.g. ``p.add_argument("--out", type=out_file(".npz"))`` and
``p.add_argument("--seed", type=seed)``: nothing else is needed for its refusals to be the same as
every other command's.
"""

from __future__ import annotations

import argparse
import math
import os
import uuid
from collections.abc import Callable
from pathlib import Path

from datagen.errors import InputError

SEED_MAX = 2**32 - 1
"""Largest seed a drape command takes (numpy's legacy seeding and torch's manual_seed take up to 2^32 - 1
without complaint on every platform)."""


def writable_folder(folder: Path) -> str | None:
    """Why no file can be created in ``folder`` (None: one can). Tried, not guessed from permission
    bits: a probe file is created and removed at once (root ignores the bits; /sys and read-only
    mounts refuse even root)."""
    if not folder.is_dir():
        return f"the folder {folder} does not exist; create it first" if not folder.exists() else \
            f"{folder} is a file, not a folder"
    probe = folder / f".drape-probe-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    try:
        fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
    except OSError as exc:
        return f"the folder {folder} is not writable ({exc.strerror or exc})"
    os.close(fd)
    try:
        probe.unlink()
    except OSError:
        pass
    return None


def output_file_problem(path: Path, suffixes: tuple[str, ...] = ()) -> str | None:
    """Why ``path`` cannot be written as an output file (None: it can)."""
    if path.is_dir():
        return f"{path} is a directory; give a file name" + (f" ending in {' or '.join(suffixes)}" if suffixes else "")
    if suffixes and path.suffix.lower() not in suffixes:
        return f"{path} must end in {' or '.join(suffixes)}"
    problem = writable_folder(path.parent if str(path.parent) else Path("."))
    if problem:
        return problem
    if path.exists() and not os.access(path, os.W_OK):
        return f"{path} exists and is read-only"
    return None


def output_dir_problem(path: Path) -> str | None:
    """Why ``path`` cannot be a directory drape writes into (made with its parents when missing)."""
    if path.exists() and not path.is_dir():
        return f"{path} exists and is a file, not a directory"
    folder = path
    while not folder.exists():  # the nearest folder that is there is the one the new ones go into
        folder = folder.parent
    return writable_folder(folder)


def _named(fn: Callable, name: str) -> Callable:
    fn.__name__ = name  # argparse names the type in "invalid <name> value"; the message says the rest
    return fn


def out_file(*suffixes: str) -> Callable[[str], Path]:
    """An argparse type: a file to be written (``suffixes`` lower case with the dot; none: any)."""
    allowed = tuple(s.lower() for s in suffixes)

    def check(text: str) -> Path:
        path = Path(text)
        problem = output_file_problem(path, allowed)
        if problem:
            raise argparse.ArgumentTypeError(problem)
        return path

    return _named(check, "output file")


def out_dir(text: str) -> Path:
    """An argparse type: a directory to write into (created, with its parents, when the command writes)."""
    path = Path(text)
    problem = output_dir_problem(path)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return path


out_dir = _named(out_dir, "output directory")


def out_path(text: str) -> Path:
    """An argparse type: a file or a directory to write (the command says which it takes; here: its
    folder, or the nearest folder above it that is there, is writable)."""
    path = Path(text)
    folder = path if path.is_dir() else path.parent
    while not folder.exists():
        folder = folder.parent
    problem = writable_folder(folder)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return path


out_path = _named(out_path, "output path")


def integer(lo: int | None = None, hi: int | None = None, *, what: str = "") -> Callable[[str], int]:
    """An argparse type: an integer in ``[lo, hi]`` (None: unbounded on that side)."""

    def check(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise argparse.ArgumentTypeError(f"{value} is out of range: give {_range(lo, hi)}{what}")
        return value

    return _named(check, "integer")


def number(lo: float | None = None, hi: float | None = None, *, above: bool = False,
           what: str = "") -> Callable[[str], float]:
    """An argparse type: a finite number in ``[lo, hi]`` (``above``: strictly greater than ``lo``)."""

    def check(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text} is not a finite number")
        low_bad = lo is not None and (value <= lo if above else value < lo)
        if low_bad or (hi is not None and value > hi):
            where = (f"a number > {lo:g}" + (f" and <= {hi:g}" if hi is not None else "")) if above else \
                _range(lo, hi, float)
            raise argparse.ArgumentTypeError(f"{value:g} is out of range: give {where}{what}")
        return value

    return _named(check, "number")


def _range(lo, hi, kind=int) -> str:
    f = (lambda v: f"{v:g}") if kind is float else str
    if lo is not None and hi is not None:
        return f"a {'number' if kind is float else 'whole number'} from {f(lo)} to {f(hi)}"
    if lo is not None:
        return f"{f(lo)} or more"
    return f"{f(hi)} or less"


seed = _named(integer(0, SEED_MAX, what=" (a seed)"), "seed")
"""An argparse type: a seed, 0 .. 2^32 - 1."""

count = _named(integer(1, None), "count")
"""An argparse type: a count of things, 1 or more."""

workers = _named(integer(0, 1024), "workers")
"""An argparse type: worker processes, 0 (none) .. 1024."""

fps = _named(number(1, 240, what=" frames per second"), "fps")
"""An argparse type: a frame rate, 1 .. 240 frames per second."""


def check_memory(need_bytes: float, what: str, advice: str) -> None:
    """Refuse (:class:`~datagen.errors.InputError`) work whose arrays would take more host memory than
    is available, before anything is allocated.

    Args:
        need_bytes: the estimate [bytes].
        what: what needs it (``"--frames 100000"``).
        advice: what to do instead.
    """
    from datagen.sim.device import available_ram  # light: no warp

    free = available_ram()
    if free is not None and need_bytes > free:
        raise InputError(f"{what} needs about {need_bytes / 2**30:,.1f} GiB of memory and this machine has "
                         f"{free / 2**30:,.1f} GiB available; {advice}")
