"""Write a dataset store: stage samples (many processes, crash-safe), then pack (one process).

Generation stages each sample as its own directory of ``.npy`` files under ``STORE/staging/``:
written under a temporary name, completion marker (the manifest) last, then renamed into place,
so a killed run leaves either a whole staged sample or nothing that counts. Processes never
share a file. :meth:`StoreWriter.pack` then builds the flat, sharded arrays of
:mod:`schemas.dataset` from the staging area (:mod:`datagen.store.pack`), writes the root
attributes and consolidated metadata, marks the store complete (one atomic rename) and only then
removes the staging area; a killed pack is simply run again. What is staged is checked first
(:mod:`datagen.store.checks`).

Typical use (every worker process opens the same store with the same arguments)::

    writer = StoreWriter.open(out, config=resolved_config, seed=seed, sample_count=n)
    for i in writer.missing(my_share):
        writer.stage_sample(i, arrays, scalars)
    writer.stage_static("garments", garment_arrays, names={...})   # once, any process
    writer.pack()                                                  # once, after all workers
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import json
import logging
import os
import shutil
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from datagen import __version__
from datagen.errors import InputError
from datagen.store.checks import RANGED, SAMPLE_ARRAYS, SAMPLE_SCALARS, check_sample, check_static
from datagen.store.layout import (
    MARKER,
    PACK_LOCK,
    ROOT_METADATA,
    STAGING,
    fsync_dir,
    is_complete,
    json_differences,
    parse_sample_dir_name,
    read_root_attributes,
    sample_dir_name,
    static_dir_name,
    storage_errors,
    to_json,
    unique_temporary,
    write_json_atomic,
)
from datagen.store.pack import Packer, PackPlan
from schemas.dataset import (
    DATASET_SCHEMA_VERSION,
    FAILURE_NAMES,
    IDENTITY_ATTRIBUTES,
    SEGMENT_LENGTH,
    STATIC_GROUPS,
    STORE_FORMAT,
    Chunking,
)

__all__ = ["SAMPLE_ARRAYS", "SAMPLE_SCALARS", "StoreWriter", "check_sample", "check_static"]

logger = logging.getLogger(__name__)


def _save_npy(path: Path, array: np.ndarray, durable: bool) -> None:
    """Write one staged array (the single place staging writes array bytes)."""
    with open(path, "wb") as fh:
        np.save(fh, np.ascontiguousarray(array), allow_pickle=False)
        if durable:
            fh.flush()
            os.fsync(fh.fileno())


def _digest(identity: dict) -> str:
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()[:16]


class StoreWriter:
    """Stages samples and static groups into a store, and packs it. Open with :meth:`open`.

    Attributes:
        path: the store directory.
        config, seed, sample_count, segment_length, failure_names: the store's identity (fixed at creation).
    """

    def __init__(self, path: Path, identity: dict[str, Any], *, durable: bool):
        self.path = path
        self._identity = identity
        self._digest = _digest(identity)
        self.durable = durable
        self.config: dict = identity["config"]
        self.seed: int = identity["seed"]
        self.sample_count: int = identity["sample_count"]
        self.segment_length: int = identity["segment_length"]
        self.failure_names: list[str] = identity["failure_names"]
        self._garment_vertex_counts: np.ndarray | None = None

    # -- opening

    @classmethod
    def open(cls, path: str | Path, *, config: Mapping[str, Any], seed: int, sample_count: int,
             segment_length: int = SEGMENT_LENGTH, failure_names: Iterable[str] = FAILURE_NAMES,
             code_version: str = "", durable: bool = True) -> StoreWriter:
        """Create the store at ``path``, or open the one there if it was made with the same arguments.

        Args:
            path: store directory (created if missing; may be an existing empty directory).
            config: the resolved dataset configuration (JSON-able mapping).
            seed: the dataset seed.
            sample_count: number of samples (scenes) the store will hold, indices 0 .. sample_count - 1.
            segment_length: frames per segment of ``index/segments``.
            failure_names: names of the failure codes, "ok" (code 0) first.
            code_version: what made the samples (``datagen.generate.identity.code_version``); a store
                is resumed only by the same ("" records none).
            durable: fsync staged files and directories (off only for throwaway stores).

        Raises:
            InputError: ``path`` is a file, a non-empty directory that is not a drape store, or a drape
                store made with a different config, code version, seed, sample count, segment length,
                failure names or schema version (the message names what differs); nothing is changed.
            StorageError: the directory cannot be created or written (nothing is left behind).
        """
        path = Path(path)
        if not isinstance(config, Mapping):
            raise InputError(f"config must be a mapping (the resolved dataset config), got {type(config).__name__}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise InputError(f"seed must be an integer, got {seed!r}")
        if isinstance(sample_count, bool) or not isinstance(sample_count, (int, np.integer)) or sample_count < 0:
            raise InputError(f"sample_count must be an integer >= 0, got {sample_count!r}")
        if not isinstance(segment_length, (int, np.integer)) or segment_length < 1:
            raise InputError(f"segment_length must be an integer >= 1, got {segment_length!r}")
        failure_names = list(failure_names)
        if not failure_names or failure_names[0] != "ok" or len(set(failure_names)) != len(failure_names) \
                or not all(isinstance(s, str) for s in failure_names):
            raise InputError(f"failure_names must be distinct strings starting with 'ok' (code 0), got {failure_names}")
        if not isinstance(code_version, str):
            raise InputError(f"code_version must be a string, got {code_version!r}")
        identity = {"schema_version": DATASET_SCHEMA_VERSION, "config": to_json(dict(config), "config"),
                    "code_version": code_version,
                    "seed": int(seed), "sample_count": int(sample_count), "segment_length": int(segment_length),
                    "failure_names": failure_names}
        if path.exists() and not path.is_dir():
            raise InputError(f"store path {path} is a file; give a directory path (new or empty) for the store")
        attrs = read_root_attributes(path) if path.is_dir() else None
        if attrs is not None and attrs.get("format") == STORE_FORMAT:
            cls._check_identity(path, attrs, identity)
            if attrs.get("drape_version") != __version__:
                logger.warning("store %s was created by drape %s; this is drape %s", path, attrs.get("drape_version"),
                               __version__)
            logger.info("opened store %s (%s)", path, "complete" if attrs.get("complete") else "in progress")
        else:
            if path.is_dir() and any(path.iterdir()):
                raise InputError(f"{path} is a non-empty directory that is not a drape store (no {ROOT_METADATA} "
                                 f"with format '{STORE_FORMAT}'); give a new or empty directory for the store. "
                                 "Nothing was changed.")
            if not cls._create(path, identity):  # another process created it meanwhile: open that one
                return cls.open(path, config=config, seed=seed, sample_count=sample_count,
                                segment_length=segment_length, failure_names=failure_names,
                                code_version=code_version, durable=durable)
        return cls(path, identity, durable=durable)

    @staticmethod
    def _check_identity(path: Path, attrs: dict, identity: dict) -> None:
        if attrs.get("schema_version") != DATASET_SCHEMA_VERSION:
            raise InputError(f"store {path} has schema version {attrs.get('schema_version')}; this drape writes "
                             f"version {DATASET_SCHEMA_VERSION}. Give a new store path. Nothing was changed.")
        diffs: list[str] = []
        for key in IDENTITY_ATTRIBUTES:
            if key == "config":
                diffs += [f"config.{d}" if not d.startswith("(value)") else f"config {d}"
                          for d in json_differences(attrs.get("config"), identity["config"])]
            else:
                diffs += json_differences(attrs.get(key), identity[key], key)
        if diffs:
            code = (" The code_version differs: the store was started by other code or libraries (drape's "
                    "simulator, garments, bodies or targets, or warp, anny, torch, ...): finish it with the "
                    "installation that started it." if any(d.startswith("code_version") for d in diffs) else "")
            raise InputError(f"store {path} was made with different settings: {'; '.join(diffs)}. Nothing was "
                             f"changed.{code} Give a new store path, or delete {path} to start over with these "
                             "settings.")

    @staticmethod
    def _create(path: Path, identity: dict) -> bool:
        """Make the store at ``path`` (absent or an empty directory) in one rename: it is built in a
        sibling directory and renamed into place, so nobody sees ``path`` half made. False when
        another process put a store there first (two Ray tasks opening one new store at once)."""
        attrs = {"format": STORE_FORMAT, **identity, "drape_version": __version__, "complete": False}
        tmp = path.parent / f".{path.name}.creating-{os.getpid()}-{os.urandom(4).hex()}"
        try:
            with storage_errors(path, "create the store", "Nothing was written."):
                path.parent.mkdir(parents=True, exist_ok=True)
                tmp.mkdir()
                write_json_atomic(tmp / ROOT_METADATA, {"zarr_format": 3, "node_type": "group", "attributes": attrs})
                (tmp / STAGING).mkdir()
                try:
                    os.rename(tmp, path)  # replaces an empty directory, fails on a non-empty one
                except OSError as exc:
                    if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                        raise
                    return False
        finally:
            shutil.rmtree(tmp, ignore_errors=True)  # gone already after the rename
        logger.info("created store %s for %d samples", path, identity["sample_count"])
        return True

    # -- state

    @property
    def staging(self) -> Path:
        return self.path / STAGING

    @property
    def is_complete(self) -> bool:
        """True once :meth:`pack` has finished (the store is read-only from then on)."""
        return is_complete(self.path)

    def has_sample(self, index: int) -> bool:
        """True if sample ``index`` is staged completely or already packed."""
        return self.is_complete or (self.staging / sample_dir_name(index) / MARKER).is_file()

    def missing(self, indices: Iterable[int] | None = None) -> list[int]:
        """The indices among ``indices`` (default: all samples) that are neither staged nor packed."""
        indices = range(self.sample_count) if indices is None else indices
        if self.is_complete:
            return []
        staged = self._staged_indices()
        return [int(i) for i in indices if int(i) not in staged]

    def _staged_indices(self) -> set[int]:
        out = set()
        with contextlib.suppress(FileNotFoundError), os.scandir(self.staging) as it:
            for entry in it:
                i = parse_sample_dir_name(entry.name)
                if i is not None and os.path.isfile(os.path.join(entry.path, MARKER)):
                    out.add(i)
        return out

    def has_static(self, group: str) -> bool:
        return self.is_complete or (self.staging / static_dir_name(group) / MARKER).is_file()

    def missing_static(self) -> list[str]:
        """Static groups not yet staged (all are needed by :meth:`pack`)."""
        return [g for g in STATIC_GROUPS if not self.has_static(g)]

    # -- staging

    def stage_sample(self, index: int, arrays: Mapping[str, Any], scalars: Mapping[str, Any]) -> bool:
        """Check sample ``index`` against the schema and stage it atomically.

        Args:
            index: sample index, 0 .. sample_count - 1.
            arrays: per-sample arrays by name (``SAMPLE_ARRAYS``): vertex-frame arrays [T, V, k], frame
                arrays [T, ...], simulation-frame metrics [T_sim]; a failed sample gives only the metrics.
            scalars: per-sample scalars by name (``SAMPLE_SCALARS``).

        Returns:
            True if staged now, False if it was already staged or packed (then nothing is written).

        Raises:
            InputError: the sample does not match the schema (nothing is written).
            StorageError: the disk refused the write (nothing of this sample is kept).
        """
        if self.has_sample(index):
            logger.debug("sample %d is already in %s; not staged again", index, self.path)
            return False
        arrays, scalars, dims = check_sample(index, arrays, scalars, sample_count=self.sample_count,
                                             failure_names=self.failure_names,
                                             garment_vertex_counts=self._staged_garment_vertex_counts())
        ranges = {n: [int(arrays[n].min()), int(arrays[n].max())] for n in RANGED if n in arrays and arrays[n].size}
        manifest = {"kind": "sample", "sample": int(index), "store": self._digest, "scalars": scalars, "dims": dims,
                    "arrays": {n: {"shape": list(a.shape), "dtype": str(a.dtype)} for n, a in arrays.items()},
                    "ranges": ranges, "drape_version": __version__}
        written = self._stage_dir(sample_dir_name(index), arrays, manifest)
        if written:
            logger.debug("staged sample %d (T = %d, T_sim = %d)", index, dims["T"], dims["T_sim"])
        return written

    def stage_static(self, group: str, arrays: Mapping[str, Any], names: Mapping[str, Any] | None = None, *,
                     diagnostics: Mapping[str, Any] | None = None) -> bool:
        """Check a static group against the schema and stage it atomically (once per store).

        Args:
            group: ``body``, ``bodies``, ``motions``, ``garments`` or ``fit``.
            arrays: the group's arrays by name (schemas.dataset, paths ``group/name``).
            names: the code name lists this group brings: ``bodies``: body_names; ``motions``:
                label_names; ``garments``: garment_type_names, material_names, region_names.
            diagnostics: ``fit`` only: the factor analysis's health (JSON; root attribute
                ``fit_diagnostics``). A fit group with D = 0 features means "no fit attribute".

        Returns:
            True if staged now, False if the group was already staged or packed.
        """
        if self.has_static(group):
            logger.debug("static group %s is already in %s; not staged again", group, self.path)
            return False
        arrays, names, dims = check_static(group, arrays, names)
        if diagnostics is not None and group != "fit":
            raise InputError(f"diagnostics are given with the fit group only, not with {group!r}")
        manifest = {"kind": "static", "group": group, "store": self._digest, "names": names, "dims": dims,
                    "diagnostics": to_json(dict(diagnostics or {}), "diagnostics"),
                    "arrays": {n: {"shape": list(a.shape), "dtype": str(a.dtype)} for n, a in arrays.items()},
                    "drape_version": __version__}
        return self._stage_dir(static_dir_name(group), arrays, manifest)

    def _stage_dir(self, name: str, arrays: Mapping[str, np.ndarray], manifest: dict) -> bool:
        final = self.staging / name
        tmp: Path | None = None
        with storage_errors(self.path, f"stage {name}",
                            "Nothing of it was kept; everything staged before is intact."):
            try:
                self.staging.mkdir(exist_ok=True)
                tmp = unique_temporary(self.staging, name)
                os.mkdir(tmp)
                for key, arr in arrays.items():
                    _save_npy(tmp / f"{key}.npy", arr, self.durable)
                write_json_atomic(tmp / MARKER, manifest, durable=self.durable)  # the completion marker, last
                if self.durable:
                    fsync_dir(tmp)
                if final.exists() and not (final / MARKER).is_file():  # a directory without marker: not a sample
                    aside = unique_temporary(self.staging, f"broken-{name}")
                    with contextlib.suppress(FileNotFoundError):
                        os.rename(final, aside)
                    shutil.rmtree(aside, ignore_errors=True)
                try:
                    os.rename(tmp, final)
                except OSError as exc:
                    if exc.errno in (errno.ENOTEMPTY, errno.EEXIST) and (final / MARKER).is_file():
                        logger.debug("%s was staged by another process first; keeping that one", name)
                        return False
                    raise
                tmp = None
                if self.durable:
                    fsync_dir(self.staging)
            finally:
                if tmp is not None:
                    shutil.rmtree(tmp, ignore_errors=True)
        return True

    def _staged_garment_vertex_counts(self) -> np.ndarray | None:
        """Vertex count of every garment instance, once the garments group is staged (it never changes then)."""
        if self._garment_vertex_counts is None:
            f = self.staging / static_dir_name("garments") / "vertex_start.npy"
            if (f.parent / MARKER).is_file():
                self._garment_vertex_counts = np.diff(np.load(f))
        return self._garment_vertex_counts

    # -- packing

    def pack(self, *, chunking: Mapping[str, Chunking] | None = None, provenance: Mapping[str, str] | None = None,
             card: bool = True) -> bool:
        """Build the packed store from the staging area, mark it complete, remove the staging area.

        Run it in one process once every sample and static group is staged. If it is interrupted,
        run it again: it starts over from the staging area, which is kept until the store is
        marked complete. On a complete store it does nothing.

        Args:
            chunking: per-table chunk/shard sizes overriding ``schemas.dataset.TABLES`` (tests, benchmarks).
            provenance: how the store was made beyond its config (:func:`datagen.store.card.provenance`:
                device, executor, drape's commit), kept with the time of packing as the root attribute
                ``provenance``.
            card: write the dataset card, the per-sample table and ``croissant.json`` once the store is
                complete (:func:`datagen.store.card.write_card`; no pictures: ``drape card`` draws them).

        Returns:
            True if packed now, False if the store was already complete.

        Raises:
            InputError: samples or static groups are missing, or they disagree with each other
                (garment/body/motion indices out of range, vertex counts); the message lists them.
            StorageError: the disk refused a write; the staging area is intact, run pack() again.
        """
        if self.is_complete:  # also on a read-only disk: nothing to write
            if self.staging.exists():  # a pack interrupted after marking the store complete
                self._remove_staging()
            logger.info("store %s is already complete; nothing to pack", self.path)
            return False
        with self._pack_lock():
            if self.is_complete:  # another process packed it while we waited
                return False
            plan = PackPlan.build(self)
            after = "The staging area is intact and the store is not marked complete."
            with storage_errors(self.path, "pack the store", after):
                Packer(self, plan, dict(chunking or {}), dict(provenance or {})).run()
            self._remove_staging()
            if card:
                from datagen.store.card import write_card

                with storage_errors(self.path, "write the dataset card", "The store is complete; `drape card "
                                    f"{self.path}` writes the card again."):
                    write_card(self.path, check_files=False)
            logger.info("packed store %s: %d samples (%d failed), %d frames, %d segments", self.path,
                        self.sample_count, int(np.count_nonzero(plan.failure)), int(plan.frame_start[-1]),
                        len(plan.segments))
            return True

    @contextlib.contextmanager
    def _pack_lock(self):
        with storage_errors(self.path, "lock the store for packing", "Nothing was changed."):
            fh = open(self.path / PACK_LOCK, "a+")  # noqa: SIM115 (held for the whole pack)
        try:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                raise InputError(f"another process is packing {self.path}; wait for it to finish") from None
            yield
        finally:
            fh.close()

    def _remove_staging(self) -> None:
        if self.staging.exists():
            with storage_errors(self.path, "remove the staging area", "The store itself is complete."):
                shutil.rmtree(self.staging)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.path / PACK_LOCK)
