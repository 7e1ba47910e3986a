"""A store's shard files against the digests pack recorded: the one check that ``validate`` and
every reader run.

zarr and tensorstore read a missing shard as the fill value (zeros), and flipped bytes inside a
compressed chunk often decode to other numbers without an error, so neither library notices a
damaged file. Pack records a :data:`~datagen.store.layout.CHECKSUM` digest of every shard file in
the root attribute ``checksums``; :func:`shard_problem` compares a file with it.
:class:`ShardGuard` runs that comparison the first time a reader touches a shard (one digest of
the file per shard per process and open store, then nothing), and raises
:class:`DamagedStoreError` for a shard that is missing, has no digest, or differs.
"""

from __future__ import annotations

import threading
from pathlib import Path

from datagen.errors import InputError
from datagen.store.layout import file_digest, shard_keys
from schemas.dataset import ARRAYS


MISSING = "is missing"
""":func:`shard_problem` of a shard file that is not there (a read would give the fill value)."""


class DamagedStoreError(InputError):
    """A shard file of a packed store is missing or differs from what pack wrote: nothing read from
    it is data. The CLI exits with status 1 (the store is bad, as ``drape validate`` says), not 2."""

    exit_status = 1


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
        for name in ARRAYS:
            m = consolidated.get(name)
            if m and m.get("node_type") == "array":
                shape, shard = shard_rows(m)
                self.layout[name] = (shape, shard, set(shard_keys(shape, shard)))
        self.verified: set[tuple[str, int]] = set()
        self._lock = threading.Lock()

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
                    raise DamagedStoreError(
                        f"the store is damaged at {array} (shard {key}, rows {k * shard[0]} .. {last}: its file {problem}): "
                        f"run `drape validate {self.store}` (it lists every damaged file), then restore the store "
                        "from a copy or make it again; nothing was read from that shard")
                self.verified.add((array, k))
