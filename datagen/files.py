"""Output files of the exporters: checked up front, written whole or not at all.

:func:`check_output_path` refuses a wrong suffix, a missing or unwritable directory, or a
directory where a file should go, with an :class:`~datagen.errors.InputError` before any work is
done. :func:`atomic_output` hands out a temporary name next to the target (same suffix, so
writers that pick a format by suffix still do) and renames it onto the target only when the
write finished, so an interrupted or failed export never leaves a half-written file under the
target's name.
"""

from __future__ import annotations

import contextlib
import os
import uuid
from collections.abc import Iterator, Sequence
from pathlib import Path

from datagen.errors import InputError

__all__ = ["atomic_output", "check_output_dir", "check_output_path"]


def check_output_path(path: str | os.PathLike, suffixes: Sequence[str], what: str) -> Path:
    """``path`` as a :class:`Path` if a ``what`` file can be written there, else :class:`InputError`.

    Args:
        path: the file to write.
        suffixes: allowed file name endings (lower case, with the dot).
        what: what the file is, for messages (``"USD file"``).
    """
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        raise InputError(f"{what} {path} must end in one of {', '.join(suffixes)}")
    if path.is_dir():
        raise InputError(f"{path} is a directory; give a file name ending in one of {', '.join(suffixes)}")
    parent = path.parent
    if not parent.is_dir():
        raise InputError(f"directory {parent} does not exist; create it first")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {what} {path}: directory {parent} is not writable")
    if path.exists() and not os.access(path, os.W_OK):
        raise InputError(f"cannot write {what} {path}: the file exists and is read-only")
    return path


def check_output_dir(path: str | os.PathLike, what: str) -> Path:
    """``path`` as a directory to write into, created (with its parents) if missing."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{what} {path} exists and is not a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create {what} {path}: {exc.strerror or exc}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise InputError(f"cannot write into {what} {path}: it is not writable")
    return path


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path next to ``path`` to write to; renamed onto ``path`` when the block ends.

    If the block raises, the temporary file is removed and ``path`` is left as it was. An
    ``OSError`` from the rename (or raised inside the block) becomes an :class:`InputError`.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.tmp-{os.getpid()}-{uuid.uuid4().hex[:8]}{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:
        raise InputError(f"could not write {path}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
