"""Where things live inside a store directory, and the helpers that writer, reader, validator and
info share: staging names, chunk and shard shapes from :mod:`schemas.dataset`, atomic file
writes, disk-error translation and config comparison."""

from __future__ import annotations

import contextlib
import errno
import json
import math
import os
import shutil
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from datagen.errors import DrapeError
from schemas.dataset import ARRAYS, STORE_FORMAT, TABLES, ArraySpec, Chunking

STAGING = "staging"
"""Staging directory inside the store: one directory per staged sample or static group."""

MARKER = "_complete.json"
"""Completion marker, written last into a staged directory: its manifest (scalars, shapes)."""

TMP_PREFIX = ".tmp-"
"""Prefix of a staged directory still being written (renamed into place when done)."""

PACK_LOCK = ".drape-pack.lock"
"""Lock file that keeps two pack() calls on one store apart."""

ROOT_METADATA = "zarr.json"


class StorageError(DrapeError, OSError):
    """The store's disk refused a write (full, read-only, no permission); what was stored before is intact."""


def sample_dir_name(index: int) -> str:
    return f"sample-{index:09d}"


def static_dir_name(group: str) -> str:
    return f"static-{group}"


def parse_sample_dir_name(name: str) -> int | None:
    """Sample index of a staged directory name, or None for anything else."""
    if name.startswith("sample-") and name[7:].isdigit():
        return int(name[7:])
    return None


def read_root_metadata(path: Path) -> dict[str, Any] | None:
    """The root ``zarr.json`` of the zarr v3 group at ``path`` (attributes and consolidated metadata),
    or None if there is no readable root group metadata."""
    try:
        meta = json.loads((path / ROOT_METADATA).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(meta, dict) or meta.get("zarr_format") != 3 or meta.get("node_type") != "group":
        return None
    return meta


def read_root_attributes(path: Path) -> dict[str, Any] | None:
    """Root attributes of the zarr v3 group at ``path``, or None if there is no readable root metadata."""
    meta = read_root_metadata(path)
    attrs = meta.get("attributes", {}) if meta is not None else None
    return attrs if isinstance(attrs, dict) else None




def is_complete(path: Path) -> bool:
    attrs = read_root_attributes(path)
    return attrs is not None and attrs.get("format") == STORE_FORMAT and attrs.get("complete") is True


def chunk_layout(spec: ArraySpec, shape: tuple[int, ...], chunking: Chunking | None = None) -> tuple[tuple, tuple]:
    """Chunk and shard shapes of an array of ``shape``: split along the first axis only.

    A chunk holds the largest power of two of rows within ``chunk_bytes``, a shard the largest power
    of two of chunks within ``shard_bytes``; an array no longer than one chunk is one chunk (and one
    shard), and a shard never extends past the chunk holding the array's last row.
    """
    chunking = chunking or TABLES[spec.table].chunking
    tail = tuple(int(s) for s in shape[1:])
    row_bytes = max(1, int(np.prod(tail, dtype=np.int64)) * np.dtype(spec.dtype).itemsize)
    rows = int(shape[0])
    chunk_rows = 1 << max(0, int(math.floor(math.log2(max(1, chunking.chunk_bytes // row_bytes)))))
    shard_chunks = 1 << max(0, int(math.floor(math.log2(max(1, chunking.shard_bytes // (chunk_rows * row_bytes))))))
    shard_rows = chunk_rows * shard_chunks
    if rows <= chunk_rows:
        chunk_rows = shard_rows = max(1, rows)
    else:
        shard_rows = min(shard_rows, -(-rows // chunk_rows) * chunk_rows)
    tail = tuple(max(1, t) for t in tail)  # an empty axis (D = 0: no fit attribute) still has a chunk size
    return (chunk_rows, *tail), (shard_rows, *tail)




CHECKSUM = "blake2b-128"
"""The digest of every shard file, recorded at pack (root attribute ``checksums``)."""


def file_digest(path: Path) -> str:
    """:data:`CHECKSUM` of a file, as hex."""
    import hashlib

    h = hashlib.blake2b(digest_size=16)
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 22), b""):
            h.update(block)
    return h.hexdigest()


def shard_checksums(array_dir: Path) -> dict[str, str]:
    """Chunk key (``c/0/0``) -> digest of every shard file of a zarr v3 array directory."""
    root = Path(array_dir)
    return {str(f.relative_to(root)): file_digest(f) for f in sorted((root / "c").rglob("*")) if f.is_file()} \
        if (root / "c").is_dir() else {}


def shard_keys(shape: list[int], shard_shape: list[int]) -> list[str]:
    """The chunk keys (``c/i/j/...``) of every shard that an array of ``shape`` has (default encoding,
    separator ``/``): the files a complete array holds."""
    import itertools

    counts = [-(-int(n) // int(s)) if int(n) else 0 for n, s in zip(shape, shard_shape, strict=True)]
    return ["c/" + "/".join(map(str, k)) for k in itertools.product(*(range(c) for c in counts))]


def specs_of_group(group: str) -> list[ArraySpec]:
    return [a for a in ARRAYS.values() if a.group == group]


def to_json(value: Any, what: str) -> Any:
    """``value`` as plain JSON data (tuples become lists), or InputError naming ``what``."""
    from datagen.errors import InputError

    try:
        return json.loads(json.dumps(value, allow_nan=False))
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be JSON data (dicts, lists, strings, finite numbers, booleans): {exc}") from exc


def json_differences(stored: Any, given: Any, prefix: str = "") -> list[str]:
    """Dotted keys where two JSON values differ, each as ``key (stored X, given Y)``."""
    if isinstance(stored, dict) and isinstance(given, dict):
        out = []
        for key in sorted(set(stored) | set(given), key=str):
            name = f"{prefix}.{key}" if prefix else str(key)
            if key not in given:
                out.append(f"{name} (stored {_short(stored[key])}, not given)")
            elif key not in stored:
                out.append(f"{name} (not stored, given {_short(given[key])})")
            else:
                out.extend(json_differences(stored[key], given[key], name))
        return out
    if stored != given or type(stored) is not type(given) and not (_number(stored) and _number(given)):
        return [f"{prefix or '(value)'} (stored {_short(stored)}, given {_short(given)})"]
    return []


def _number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _short(x: Any) -> str:
    text = json.dumps(x)
    return text if len(text) <= 60 else text[:57] + "..."


def fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def unique_temporary(directory: Path, stem: str) -> Path:
    """A fresh name in ``directory`` for a temporary file or directory (hidden, unique per process and call)."""
    return directory / f"{TMP_PREFIX}{stem}-{os.getpid()}-{uuid.uuid4().hex[:12]}"


def write_json_atomic(path: Path, value: Any, *, durable: bool = True) -> None:
    """Write ``value`` as JSON to a temporary file next to ``path`` and rename it into place
    (permissions follow the umask, as for any new file)."""
    tmp = unique_temporary(path.parent, path.name)
    try:
        with open(tmp, "x", encoding="utf-8") as fh:
            json.dump(value, fh, indent=2, allow_nan=False)
            fh.write("\n")
            if durable:
                fh.flush()
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    if durable:
        fsync_dir(path.parent)


_DISK_ERRNOS = {errno.ENOSPC: "the disk is full", errno.EDQUOT: "the disk quota is exhausted",
                errno.EROFS: "the file system is read-only", errno.EACCES: "permission denied",
                errno.EPERM: "operation not permitted", errno.EIO: "input/output error"}


@contextlib.contextmanager
def storage_errors(store: Path, action: str, after: str) -> Iterator[None]:
    """Turn an ``OSError`` raised while ``action`` into a :class:`StorageError` that says what happened
    and what to do; ``after`` says what is left on disk."""
    try:
        yield
    except StorageError:
        raise
    except OSError as exc:
        reason = _DISK_ERRNOS.get(exc.errno or -1, exc.strerror or type(exc).__name__)
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        if exc.errno in (errno.ENOSPC, errno.EDQUOT):
            free = ""
            with contextlib.suppress(OSError):
                free = f" ({shutil.disk_usage(store if store.exists() else store.parent).free / 2**20:,.0f} MiB free now)"
            reason = f"the disk is full{free}"
            hint = ("free space on that disk (drape generate estimates what a whole run needs before it starts) and run "
                    "the same command again: it resumes from what is already staged")
        elif exc.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
            hint = "make the directory writable for this user (or give another store path) and run again"
        else:
            hint = "fix the disk problem and run again"
        error = StorageError(f"could not {action} in store {store}: {reason}{where}. {after} To go on: {hint}.")
        error.errno = exc.errno or errno.EIO
        raise error from exc


def directory_bytes(path: Path) -> int:
    """Bytes of the regular files under ``path`` (0 if it does not exist)."""
    total = 0
    for dirpath, _, files in os.walk(path):
        for name in files:
            with contextlib.suppress(OSError):
                total += os.lstat(os.path.join(dirpath, name)).st_size
    return total


def segment_table(frame_counts: np.ndarray, failure: np.ndarray, segment_length: int) -> np.ndarray:
    """(sample, first frame) of every non-overlapping ``segment_length``-frame segment of every
    non-failed sample with at least that many frames, [n_segments, 2] int64, in sample order."""
    rows = [(i, t0) for i, (T, f) in enumerate(zip(np.asarray(frame_counts).tolist(), np.asarray(failure).tolist(),
                                                   strict=True)) if f == 0
            for t0 in range(0, T - segment_length + 1, segment_length)]
    return np.asarray(rows, dtype=np.int64).reshape(-1, 2)


def design_record(design: np.ndarray, design_start: np.ndarray, g: int) -> dict | None:
    """The design record of garment instance ``g`` (the JSON of ``garments/design``), or None for a
    shell garment (no bytes). Raises ValueError when the bytes are not UTF-8 JSON of an object."""
    raw = bytes(np.asarray(design[int(design_start[g]):int(design_start[g + 1])], dtype=np.uint8))
    if not raw:
        return None
    record = json.loads(raw.decode("utf-8"))
    if not isinstance(record, dict):
        raise ValueError("a design record is a JSON object")
    return record
