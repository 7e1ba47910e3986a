"""A store's shard files against the digests pack recorded: the one check that ``validate`` and
every reader run.

zarr and tensorstore read a missing shard as the fill value (zeros), and flipped bytes inside a
compressed chunk often decode to other numbers without an error, so neither library notices a
damaged file. Pack records a :data:`~datagen.store.layout.CHECKSUM` digest of every shard file in
the root attribute ``checksums``; :func:`shard_problem` compares a file with it.
:class:`ShardGuard` runs that comparison the first time a reader touches a shard (one digest of
the file per shard per process and open store, then nothing), and raises
:class:`DamagedStoreError` for a shard that is missing, has no digest, or differs.

It is also the one place where what the storage libraries raise becomes that one line: an array
whose own ``zarr.json`` is missing or disagrees with the store's consolidated metadata
(:meth:`ShardGuard.check_metadata`), and any error tensorstore or zarr raise while opening or reading
an array (DATA_LOSS, NOT_FOUND, a codec's error: :func:`storage_errors`).
"""

from __future__ import annotations

import contextlib
import json
import logging
import threading
from collections.abc import Iterator
from pathlib import Path

from datagen.errors import DrapeError, InputError
from datagen.store.layout import file_digest, shard_keys
from schemas.dataset import ARRAYS

log = logging.getLogger(__name__)

MISSING = "is missing"
""":func:`shard_problem` of a shard file that is not there (a read would give the fill value)."""


class DamagedStoreError(InputError):
    """A shard file of a packed store is missing or differs from what pack wrote: nothing read from
    it is data. The CLI exits with status 1 (the store is bad, as ``drape validate`` says), not 2."""

    exit_status = 1


def damaged(store: Path, array: str, where: str) -> DamagedStoreError:
    """The one refusal of a damaged store: ``array``, what is wrong there (``where``: a shard and its
    rows, or the array's metadata) and the command that lists every damaged file."""
    return DamagedStoreError(
        f"the store is damaged at {array} ({where}): run `drape validate {store}` (it lists every damaged file), "
        "then restore the store from a copy or make it again; nothing was read from it")


READ_KEYS = ("shape", "data_type", "chunk_grid", "chunk_key_encoding", "codecs", "fill_value")
"""The keys of an array's zarr v3 metadata that say how its bytes are read: the array's own
``zarr.json`` and the store's consolidated copy must agree on them."""


def metadata_problem(store: Path, array: str, consolidated: dict | None) -> str | None:
    """What is wrong with the metadata of ``array`` (None: its ``zarr.json`` is there, readable, and
    agrees with the consolidated copy ``consolidated`` on :data:`READ_KEYS`)."""
    if consolidated is None:
        return "it is not in the store's consolidated metadata (zarr.json at the root)"
    f = store / array / "zarr.json"
    if not f.is_file():
        return "its zarr.json is missing" if (store / array).is_dir() else "its directory is missing"
    try:
        own = json.loads(f.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        return f"its zarr.json cannot be read ({exc})"
    if not isinstance(own, dict):
        return "its zarr.json is not a JSON object"
    different = [k for k in READ_KEYS if own.get(k) != consolidated.get(k)]
    if different:
        k = different[0]
        return (f"its zarr.json disagrees with the store's consolidated metadata on {', '.join(different)}: "
                f"{k} {json.dumps(own.get(k))[:80]} against {json.dumps(consolidated.get(k))[:80]}")
    return None


@contextlib.contextmanager
def storage_errors(store: Path, array: str) -> Iterator[None]:
    """Turn an error the storage libraries raise while opening or reading ``array`` (tensorstore's
    DATA_LOSS or NOT_FOUND, zarr's missing node, a codec that cannot decode) into the one line of
    :func:`damaged`; drape's own errors pass as they are."""
    try:
        yield
    except DrapeError:
        raise
    except Exception as exc:  # noqa: BLE001 - whatever the libraries raise about the bytes they read
        log.debug("reading %s of %s failed", array, store, exc_info=True)
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise damaged(store, array, f"reading it failed: {type(exc).__name__}: {first[:200]}") from exc


def shard_problem(store: Path, array: str, key: str, recorded: dict, *, digest: bool = True) -> str | None:
    """What is wrong with shard file ``key`` (``c/0/0``) of ``array`` in ``store`` (None: intact).

    Args:
        store: the store directory.
        array: array path (``vertex_frames/detail``).
        key: the shard's chunk key.
        recorded: the root attribute ``checksums`` (array -> key -> digest).
        digest: compare the file's digest with the recorded one (False: presence only).
    """
    f = store / array / key
    if not f.is_file():
        return MISSING
    if not digest:
        return None
    expected = (recorded.get(array) or {}).get(key) if isinstance(recorded, dict) else None
    if expected is None:
        return "has no checksum recorded at pack"
    if file_digest(f) != expected:
        return "differs from what pack wrote (its checksum); truncated, overwritten or flipped bytes"
    return None


def shard_rows(metadata: dict) -> tuple[list[int], list[int]]:
    """(shape, shard shape) of an array from its zarr v3 metadata (the outer chunk grid is the shard)."""
    return [int(v) for v in metadata["shape"]], [int(v) for v in metadata["chunk_grid"]["configuration"]["chunk_shape"]]


class ShardGuard:
    """Checks every shard a read touches against its recorded digest, once per shard.

    Args:
        store: the store directory.
        root_metadata: its root ``zarr.json`` (consolidated metadata and attributes).

    One guard belongs to one reader in one process (the reader makes a new one in a forked or
    spawned worker), so each process checks each shard it reads once; a shard found intact is not
    hashed again by that guard.
    """

    def __init__(self, store: Path, root_metadata: dict):
        self.store = Path(store)
        consolidated = (root_metadata.get("consolidated_metadata") or {}).get("metadata") or {}
        attrs = root_metadata.get("attributes") or {}
        self.recorded = attrs.get("checksums") if isinstance(attrs.get("checksums"), dict) else {}
        self.layout: dict[str, tuple[list[int], list[int], set[str]]] = {}
        self.consolidated: dict[str, dict] = {}
        for name in ARRAYS:
            m = consolidated.get(name)
            if m and m.get("node_type") == "array":
                shape, shard = shard_rows(m)
                self.layout[name] = (shape, shard, set(shard_keys(shape, shard)))
                self.consolidated[name] = m
        self.verified: set[tuple[str, int]] = set()
        self.metadata_verified: set[str] = set()
        self._lock = threading.Lock()

    def check_metadata(self, array: str) -> None:
        """Refuse (:class:`DamagedStoreError`) an array whose ``zarr.json`` is missing or disagrees with
        the consolidated metadata (once per array: the backends open an array once)."""
        if array in self.metadata_verified:
            return
        problem = metadata_problem(self.store, array, self.consolidated.get(array))
        if problem:
            raise damaged(self.store, array, problem)
        self.metadata_verified.add(array)

    def check(self, array: str, start: int | None = None, stop: int | None = None) -> None:
        """Refuse (:class:`DamagedStoreError`) if a shard holding rows ``start:stop`` (all by default)
        of ``array`` is missing or changed since pack."""
        if array not in self.layout:
            return  # not in the consolidated metadata: zarr itself refuses to open it
        shape, shard, keys = self.layout[array]
        n = shape[0]
        start, stop, _ = slice(start, stop).indices(n)
        if stop <= start:
            return
        for k in range(start // shard[0], (stop - 1) // shard[0] + 1):
            if (array, k) in self.verified:
                continue
            key = "c/" + "/".join([str(k)] + ["0"] * (len(shape) - 1))
            if key not in keys:
                continue  # an empty trailing axis: no file to hold
            with self._lock:
                if (array, k) in self.verified:
                    continue
                problem = shard_problem(self.store, array, key, self.recorded)
                if problem:
                    last = min((k + 1) * shard[0], n) - 1
                    raise damaged(self.store, array, f"shard {key}, rows {k * shard[0]} .. {last}: its file {problem}")
                self.verified.add((array, k))
