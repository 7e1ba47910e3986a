"""Write a dataset store: stage samples (many processes, crash-safe), then pack (one process).

Generation stages each sample as its own directory of ``.npy`` files under ``STORE/staging/``:
written under a temporary name, completion marker (the manifest) last, then renamed into place,
so a killed run leaves either a whole staged sample or nothing that counts. Processes never
share a file. :meth:`StoreWriter.pack` then builds the flat, sharded arrays of
:mod:`schemas.dataset` from the staging area, writes the root attributes and consolidated
metadata, marks the store complete (one atomic rename) and only then removes the staging area;
a killed pack is simply run again.

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
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from datagen import __version__
from datagen.errors import InputError
from datagen.store.layout import (
    MARKER,
    PACK_LOCK,
    ROOT_METADATA,
    STAGING,
    chunk_layout,
    fsync_dir,
    is_complete,
    json_differences,
    parse_sample_dir_name,
    read_root_attributes,
    sample_dir_name,
    segment_table,
    shard_checksums,
    specs_of_group,
    static_dir_name,
    storage_errors,
    to_json,
    unique_temporary,
    write_json_atomic,
)
from datagen.geometry.positions import encode_positions
from datagen.store.validation import Dimensions, value_problems
from schemas.dataset import (
    ARRAYS,
    COMPRESSION,
    DATASET_SCHEMA_VERSION,
    FAILURE_NAMES,
    IDENTITY_ATTRIBUTES,
    NAME_LISTS,
    SEGMENT_LENGTH,
    SPLIT_NAMES,
    STATIC_GROUPS,
    STORE_FORMAT,
    TABLES,
    ArraySpec,
    Chunking,
)

logger = logging.getLogger(__name__)

SAMPLE_ARRAYS: dict[str, ArraySpec] = {a.name: a for a in ARRAYS.values()
                                       if a.written_by == "stage_sample" and a.sample_shape != ()}
"""Per-sample arrays handed to :meth:`StoreWriter.stage_sample` (vertex-frame, frame, simulation-frame)."""

SAMPLE_SCALARS: dict[str, ArraySpec] = {a.name: a for a in ARRAYS.values()
                                        if a.written_by == "stage_sample" and a.sample_shape == ()}
"""Per-sample scalars handed to :meth:`StoreWriter.stage_sample`."""

_FRAME_ARRAYS = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.table in ("vertex_frame", "frame"))
_SIM_ARRAYS = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.table == "sim_frame")
_RANGED = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.codes)  # code arrays whose range pack checks
_QUANTISED = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.quantum is not None)


def compressor(spec: ArraySpec | None = None):
    """The chunk compressor of ``spec`` (``schemas.dataset.COMPRESSION`` unless the spec names its own;
    tensorstore's zarr3 driver reads both)."""
    from zarr.codecs import BloscCodec

    c = (spec.compression if spec is not None else None) or COMPRESSION
    return BloscCodec(cname=c["cname"], clevel=c["clevel"], shuffle=c["shuffle"])


# ------------------------------------------------------------------------------------------ checks


def _cast(spec: ArraySpec, value: Any, name: str, where: str, problems: list[str]) -> np.ndarray | None:
    """``value`` as an array of ``spec.dtype``, refusing other kinds (float for int, ...) and out-of-range ints."""
    try:
        arr = np.asarray(value)
    except Exception as exc:  # noqa: BLE001 (anything that is not array-like)
        problems.append(f"{where}: '{name}' is not an array ({exc})")
        return None
    target = np.dtype(spec.dtype)
    kind = arr.dtype.kind
    if spec.quantum is not None:  # positions handed in metres, quantised once the root joints are known
        if kind != "f":
            problems.append(f"{where}: '{name}' has dtype {arr.dtype}; give float positions in metres (the store "
                            f"keeps them as {spec.dtype} steps of {spec.quantum} m)")
            return None
        return arr.astype(np.float64, copy=False)
    if target.kind == "f":
        if kind != "f":
            problems.append(f"{where}: '{name}' has dtype {arr.dtype}; the schema says {spec.dtype} (give floats)")
            return None
        return arr.astype(target, copy=False)
    if not (kind in "iu" or kind == "b" and spec.unit == "bool"):
        problems.append(f"{where}: '{name}' has dtype {arr.dtype}; the schema says {spec.dtype} (give integers)")
        return None
    if arr.size and kind in "iu":
        info = np.iinfo(target)
        lo, hi = int(arr.min()), int(arr.max())
        if lo < info.min or hi > info.max:
            problems.append(f"{where}: '{name}' has values {lo} .. {hi} that do not fit {spec.dtype}")
            return None
    return arr.astype(target, copy=False)


def _raise(problems: list[str], hint: str) -> None:
    if problems:
        shown = "; ".join(problems[:10]) + (f"; and {len(problems) - 10} more" if len(problems) > 10 else "")
        raise InputError(f"{shown}. {hint}")


def check_sample(index: int, arrays: Mapping[str, Any], scalars: Mapping[str, Any], *, sample_count: int,
                 failure_names: list[str] | tuple[str, ...], garment_vertex_counts: np.ndarray | None = None,
                 ) -> tuple[dict[str, np.ndarray], dict[str, int | float], dict]:
    """Check one sample against the schema and cast it to the schema's dtypes.

    Returns:
        (arrays, scalars, dims): arrays as stored (no frame arrays for a failed sample; positions
        quantised), scalars as Python numbers, and the bound sizes ``{"T", "V", "T_sim"}`` (V None
        when unknown).

    Raises:
        InputError: naming every array or scalar that is missing, unknown, of the wrong dtype or
            shape, not finite or out of range.
    """
    where = f"sample {index}"
    problems: list[str] = []
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < sample_count:
        raise InputError(f"sample index {index!r} is not an integer in 0 .. {sample_count - 1} (the store holds "
                         f"{sample_count} samples)")
    unknown = sorted(set(scalars) - set(SAMPLE_SCALARS))
    if unknown:
        problems.append(f"{where}: unknown scalar(s) {unknown}; scalars are {sorted(SAMPLE_SCALARS)}")
    missing = sorted(set(SAMPLE_SCALARS) - set(scalars))
    if missing:
        problems.append(f"{where}: missing scalar(s) {missing}")
    out_scalars: dict[str, int | float] = {}
    for name in [n for n in SAMPLE_SCALARS if n in scalars]:
        spec = SAMPLE_SCALARS[name]
        value = _cast(spec, scalars[name], name, where, problems)
        if value is None:
            continue
        if value.shape != ():
            problems.append(f"{where}: scalar '{name}' has shape {value.shape}; give one number")
            continue
        upper = len(SPLIT_NAMES) if name == "split" else len(failure_names) if name == "failure" else None
        problems += [f"{where}: {p}" for p in value_problems(spec, value, name=name, upper=upper)]
        out_scalars[name] = value.item()
    if "seconds" in out_scalars and out_scalars["seconds"] < 0:
        problems.append(f"{where}: 'seconds' is negative ({out_scalars['seconds']})")
    _raise(problems, "Fix the sample's scalars and stage it again.")

    failed = out_scalars["failure"] != 0
    unknown = sorted(set(arrays) - set(SAMPLE_ARRAYS))
    if unknown:
        hint = " (per-sample scalars go in `scalars`)" if set(unknown) & set(SAMPLE_SCALARS) else ""
        problems.append(f"{where}: unknown array(s) {unknown}{hint}; arrays are {sorted(SAMPLE_ARRAYS)}")
    required = _SIM_ARRAYS if failed else _SIM_ARRAYS + _FRAME_ARRAYS
    missing = sorted(set(required) - set(arrays))
    if missing:
        problems.append(f"{where}: missing array(s) {missing}" + ("" if failed else " (a sample with failure = 0 "
                                                                                   "needs every frame array)"))
    dims = Dimensions(where)
    out: dict[str, np.ndarray] = {}
    for name in [n for n in SAMPLE_ARRAYS if n in arrays]:
        spec = SAMPLE_ARRAYS[name]
        arr = _cast(spec, arrays[name], name, where, problems)
        if arr is None or not dims.bind_shape(name, arr.shape, spec.sample_shape):
            continue
        allow = failed and spec.finite == "ok_samples"
        problems += [f"{where}: {p}" for p in value_problems(spec, arr, name=name, allow_nonfinite=allow)]
        out[name] = arr
    problems += dims.problems
    _raise(problems, "Fix the sample's arrays to the shapes and dtypes of schemas/dataset.py and stage it again.")

    T = dims.sizes.get("T", 0)
    T_sim = dims.sizes["T_sim"]
    V = dims.sizes.get("V")
    if failed and T:
        problems.append(f"{where} failed (failure = {out_scalars['failure']}) but has {T} recorded frames; a failed "
                        "sample has none: drop its frame arrays (or give them with T = 0)")
    if not failed and T == 0:
        problems.append(f"{where} has failure = 0 but no recorded frames; record at least one frame or give the "
                        "failure code")
    if out_scalars["recorded_from"] + T > T_sim:
        problems.append(f"{where}: recorded_from {out_scalars['recorded_from']} + {T} recorded frames is more than "
                        f"its {T_sim} simulated frames")
    ff = out_scalars["failure_frame"]
    if not failed and ff != -1:
        problems.append(f"{where}: failure_frame is {ff} but failure = 0; use -1")
    if ff >= T_sim:
        problems.append(f"{where}: failure_frame {ff} is past its {T_sim} simulated frames")
    if garment_vertex_counts is not None:
        g = out_scalars["garment"]
        if g >= len(garment_vertex_counts):
            problems.append(f"{where}: garment {g} does not exist (the staged garments/ tables hold "
                            f"{len(garment_vertex_counts)} instances)")
        elif V is not None and T and V != garment_vertex_counts[g]:
            problems.append(f"{where}: its arrays have V = {V} vertices but garment instance {g} has "
                            f"{garment_vertex_counts[g]}")
    _raise(problems, "Fix the sample and stage it again.")
    if failed:
        out = {n: a for n, a in out.items() if n in _SIM_ARRAYS}
    else:
        for name in _QUANTISED:
            out[name] = encode_positions(out[name], out["joints"][:, 0], SAMPLE_ARRAYS[name].quantum)
    return out, out_scalars, {"T": T, "V": V if T else None, "T_sim": T_sim}


def check_static(group: str, arrays: Mapping[str, Any], names: Mapping[str, Any] | None = None
                 ) -> tuple[dict[str, np.ndarray], dict[str, list[str]], dict[str, int]]:
    """Check one static group (``body``, ``bodies``, ``motions``, ``garments``, ``fit``) and its code
    name lists against the schema; returns the cast arrays, the name lists and the bound sizes."""
    if group not in STATIC_GROUPS:
        raise InputError(f"unknown static group {group!r}; static groups are {list(STATIC_GROUPS)}")
    where = f"static group '{group}'"
    specs = {s.name: s for s in specs_of_group(group)}
    problems: list[str] = []
    unknown, missing = sorted(set(arrays) - set(specs)), sorted(set(specs) - set(arrays))
    if unknown:
        problems.append(f"{where}: unknown array(s) {unknown}; its arrays are {sorted(specs)}")
    if missing:
        problems.append(f"{where}: missing array(s) {missing}")
    wanted = {k for k, a in NAME_LISTS.items() if a.staged_with == group}
    names = dict(names or {})
    if set(names) != wanted:
        problems.append(f"{where}: give names={{...}} with exactly the code name lists {sorted(wanted) or '(none)'}"
                        f"; got {sorted(names) or '(none)'}")
    out_names: dict[str, list[str]] = {}
    for key in wanted & set(names):
        value = names[key]
        if not isinstance(value, (list, tuple)) or not all(isinstance(s, str) for s in value):
            problems.append(f"{where}: names['{key}'] must be a list of strings")
        elif len(set(value)) != len(value):
            problems.append(f"{where}: names['{key}'] repeats a name")
        else:
            out_names[key] = list(value)
    dims = Dimensions(where)
    out: dict[str, np.ndarray] = {}
    for name in [n for n in specs if n in arrays]:
        arr = _cast(specs[name], arrays[name], name, where, problems)
        if arr is not None and dims.bind_shape(name, arr.shape, specs[name].shape):
            out[name] = arr
    problems += dims.problems
    _raise(problems, "Fix the static arrays to schemas/dataset.py and stage them again.")
    for name, arr in out.items():
        spec = specs[name]
        upper = len(out_names[spec.codes]) if spec.codes in out_names else dims.sizes.get(spec.index_of or "")
        if spec.finite == "fitted" and np.isnan(arr).all():  # no fit attribute in this store
            continue
        if spec.unit != "row":
            problems += [f"{where}: {p}" for p in value_problems(spec, arr, name=name, upper=upper)]
    if group == "garments":
        for key, rows in (("vertex_start", "n_garment_vertices"), ("face_start", "n_garment_faces")):
            off = out[key]
            if off[0] != 0 or np.any(np.diff(off) < 0) or off[-1] != dims.sizes[rows]:
                problems.append(f"{where}: '{key}' must start at 0, never decrease and end at {dims.sizes[rows]} "
                                f"(the rows of its table); it is {off[:3].tolist()} ... {off[-1]}")
        if not problems:
            Vg = np.repeat(np.diff(out["vertex_start"]), np.diff(out["face_start"]))
            bad = np.flatnonzero(((out["faces"] < 0) | (out["faces"] >= Vg[:, None])).any(1))
            if len(bad):
                g = int(np.searchsorted(out["face_start"], bad[0], side="right") - 1)
                problems.append(f"{where}: 'faces' row {bad[0]} (instance {g}) has {out['faces'][bad[0]].tolist()}; "
                                f"indices must be local to the instance (0 .. {Vg[bad[0]] - 1})")
    if group == "body" and out["parents"][0] != -1:
        problems.append(f"{where}: 'parents'[0] must be -1 (the root)")
    _raise(problems, "Fix the static arrays and stage them again.")
    return out, out_names, {k: v for k, v in dims.sizes.items()}


# ------------------------------------------------------------------------------------------ writer


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
        ranges = {n: [int(arrays[n].min()), int(arrays[n].max())] for n in _RANGED if n in arrays and arrays[n].size}
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

    def pack(self, *, chunking: Mapping[str, Chunking] | None = None) -> bool:
        """Build the packed store from the staging area, mark it complete, remove the staging area.

        Run it in one process once every sample and static group is staged. If it is interrupted,
        run it again: it starts over from the staging area, which is kept until the store is
        marked complete. On a complete store it does nothing.

        Args:
            chunking: per-table chunk/shard sizes overriding ``schemas.dataset.TABLES`` (tests, benchmarks).

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
            plan = _PackPlan.build(self)
            after = "The staging area is intact and the store is not marked complete."
            with storage_errors(self.path, "pack the store", after):
                _Packer(self, plan, dict(chunking or {})).run()
            self._remove_staging()
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


class _PackPlan:
    """What pack() will write: manifests, offsets, segments, static groups; all cross-checks done."""

    @classmethod
    def build(cls, writer: StoreWriter) -> _PackPlan:
        self = cls()
        self.writer = writer
        staging = writer.staging
        problems: list[str] = []
        missing = writer.missing()
        if missing:
            shown = ", ".join(map(str, missing[:20])) + (" ..." if len(missing) > 20 else "")
            problems.append(f"{len(missing)} of {writer.sample_count} samples are not staged ({shown}); run "
                            "generation again to stage them (StoreWriter.missing() lists them)")
        if writer.missing_static():
            problems.append(f"static group(s) {writer.missing_static()} are not staged; call stage_static() for them")
        _raise(problems, "Nothing was packed.")
        self.static = {}
        for group in STATIC_GROUPS:
            d = staging / static_dir_name(group)
            manifest = json.loads((d / MARKER).read_text())
            if manifest.get("store") != writer._digest:
                problems.append(f"staged static group {group} belongs to another store configuration; delete {d}")
            self.static[group] = manifest
        self.manifests = []
        for i in range(writer.sample_count):
            d = staging / sample_dir_name(i)
            m = json.loads((d / MARKER).read_text())
            if m.get("store") != writer._digest or m.get("sample") != i:
                problems.append(f"staged sample {i} belongs to another store configuration; delete {d}")
            self.manifests.append(m)
        _raise(problems, "Nothing was packed.")
        ms = self.manifests
        sc = {k: np.array([m["scalars"][k] for m in ms], dtype=SAMPLE_SCALARS[k].dtype).reshape(-1)
              for k in SAMPLE_SCALARS}
        self.scalars = sc
        self.failure = sc["failure"]
        gv = np.load(staging / static_dir_name("garments") / "vertex_start.npy")
        V_g = np.diff(gv)
        sizes = {g: self.static[g]["dims"] for g in STATIC_GROUPS}
        G, n_bodies, M = len(V_g), sizes["bodies"]["n_bodies"], sizes["motions"]["M"]
        names = {k: v for g in STATIC_GROUPS for k, v in self.static[g]["names"].items()}
        names["split_names"], names["failure_names"] = list(SPLIT_NAMES), writer.failure_names
        self.names = names
        for key, bound, what in (("garment", G, "garment instances"), ("body", n_bodies, "bodies"),
                                 ("motion", M, "motions")):
            for i in np.flatnonzero(sc[key] >= bound)[:10]:
                problems.append(f"sample {i}: {key} {sc[key][i]} is out of range (the store has {bound} {what})")
        if sizes["bodies"]["S"] != sizes["body"]["S"]:
            problems.append(f"bodies/betas has S = {sizes['bodies']['S']} shape components but body/shapedirs has "
                            f"{sizes['body']['S']}")
        gbody = np.load(staging / static_dir_name("garments") / "body.npy")
        for g in np.flatnonzero(gbody >= n_bodies)[:10]:
            problems.append(f"garment instance {g}: body {gbody[g]} is out of range (the store has {n_bodies} bodies)")
        alpha = np.load(staging / static_dir_name("garments") / "alpha.npy")
        fitted = sizes["fit"]["D"] > 0
        if alpha.size and (np.isnan(alpha).all() if fitted else not np.isnan(alpha).all()):
            problems.append("garments/alpha must be finite when fit/ has features and NaN when it has none (D = 0: "
                            f"no fit attribute); fit/ has D = {sizes['fit']['D']}")
        n_labels = len(names["label_names"])
        mlabel = np.load(staging / static_dir_name("motions") / "label.npy")
        for k in np.flatnonzero(mlabel >= n_labels)[:10]:
            problems.append(f"motions/label[{k}] = {mlabel[k]} but label_names has {n_labels} names")
        T = np.array([m["dims"]["T"] for m in ms], dtype=np.int64)
        T_sim = np.array([m["dims"]["T_sim"] for m in ms], dtype=np.int64)
        for i, m in enumerate(ms):
            if not T[i]:
                continue
            g = int(sc["garment"][i])
            if g < G and m["dims"]["V"] != V_g[g]:
                problems.append(f"sample {i}: V = {m['dims']['V']} vertices but garment instance {g} has {V_g[g]}; "
                                f"restage the sample (delete {staging / sample_dir_name(i)})")
            lo, hi = m["ranges"].get("label", (0, 0))
            if hi >= n_labels:
                problems.append(f"sample {i}: label code {hi} but label_names has {n_labels} names")
            if m["dims"]["T"] > sizes["motions"]["T_m"]:
                problems.append(f"sample {i}: T = {m['dims']['T']} recorded frames but motions/pose holds only "
                                f"{sizes['motions']['T_m']} per motion; stage the motions with the config's frames")
            if len(problems) > 30:
                break
        _raise(problems, "Nothing was packed.")
        V = np.where(T > 0, V_g[np.minimum(sc["garment"], G - 1)] if G else 0, 0).astype(np.int64)
        self.T, self.T_sim, self.V = T, T_sim, V
        self.frame_start = np.concatenate([[0], np.cumsum(T)]).astype(np.int64)
        self.sim_frame_start = np.concatenate([[0], np.cumsum(T_sim)]).astype(np.int64)
        self.vertex_row_start = np.concatenate([[0], np.cumsum(np.repeat(V, T))]).astype(np.int64)
        self.segments = segment_table(T, self.failure, writer.segment_length)
        return self


class _RowSink:
    """Appends row blocks to a zarr array, writing one whole shard at a time."""

    def __init__(self, array, shard_rows: int):
        self.array = array
        self.buffer = np.empty((min(shard_rows, max(1, array.shape[0])), *array.shape[1:]), dtype=array.dtype)
        self.fill = 0
        self.start = 0

    def add(self, block: np.ndarray) -> None:
        pos = 0
        while pos < len(block):
            n = min(len(block) - pos, len(self.buffer) - self.fill)
            self.buffer[self.fill:self.fill + n] = block[pos:pos + n]
            self.fill += n
            pos += n
            if self.fill == len(self.buffer):
                self.flush()

    def flush(self) -> None:
        if self.fill:
            self.array[self.start:self.start + self.fill] = self.buffer[:self.fill]
            self.start += self.fill
            self.fill = 0

    def close(self) -> None:
        self.flush()
        if self.start != self.array.shape[0]:
            raise RuntimeError(f"{self.array.path}: wrote {self.start} rows of {self.array.shape[0]}")  # a bug


class _Packer:
    def __init__(self, writer: StoreWriter, plan: _PackPlan, chunking: dict[str, Chunking]):
        self.w = writer
        self.plan = plan
        self.chunking = chunking

    def run(self) -> None:
        import zarr

        path = self.w.path
        self._clear()
        root = zarr.open_group(store=str(path), mode="r+", zarr_format=3, use_consolidated=False)
        groups = sorted({s.group for s in ARRAYS.values()})
        for g in groups:
            root.create_group(g, attributes={"doc": _GROUP_DOCS.get(g, STATIC_GROUPS.get(g, ""))}, overwrite=True)
        for group in STATIC_GROUPS:
            for spec in specs_of_group(group):
                data = np.load(self.w.staging / static_dir_name(group) / f"{spec.name}.npy", mmap_mode="r")
                self._write(root, spec, data.shape, [data])
        p = self.plan
        for spec in SAMPLE_ARRAYS.values():
            self._write(root, spec, self._packed_shape(spec), self._sample_blocks(spec))
        for spec in SAMPLE_SCALARS.values():
            self._write(root, spec, (self.w.sample_count,), [p.scalars[spec.name]])
        for name, data in (("index/frame_start", p.frame_start), ("index/vertex_row_start", p.vertex_row_start),
                           ("index/sim_frame_start", p.sim_frame_start), ("index/segments", p.segments)):
            self._write(root, ARRAYS[name], data.shape, [data])
        fit = p.static["fit"]
        checksums = {spec.path: shard_checksums(path / spec.path) for spec in ARRAYS.values()}
        attrs = {"format": STORE_FORMAT, **self.w._identity, "drape_version": __version__, "complete": False,
                 "units": {s.path: s.unit for s in ARRAYS.values()}, **p.names,
                 "fit_attribute": bool(fit["dims"]["D"] > 0), "fit_diagnostics": fit.get("diagnostics", {}),
                 "checksums": checksums}
        root.attrs.put(attrs)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "consolidated metadata is not part of the v3 spec": we know
            zarr.consolidate_metadata(str(path))
        if self.w.durable:
            _fsync_tree(path, skip=path / STAGING)
        # the commit point: one atomic rename of the root metadata with complete = true
        meta = json.loads((path / ROOT_METADATA).read_text())
        meta["attributes"]["complete"] = True
        write_json_atomic(path / ROOT_METADATA, meta, durable=True)

    def _clear(self) -> None:
        """Remove what an interrupted pack left, and reset the root metadata to the store's identity."""
        keep = {ROOT_METADATA, STAGING, PACK_LOCK}
        for entry in self.w.path.iterdir():
            if entry.name in keep:
                continue
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
        attrs = {"format": STORE_FORMAT, **self.w._identity, "drape_version": __version__, "complete": False}
        write_json_atomic(self.w.path / ROOT_METADATA, {"zarr_format": 3, "node_type": "group", "attributes": attrs})

    def _packed_shape(self, spec: ArraySpec) -> tuple[int, ...]:
        p = self.plan
        tail = tuple(self._size(s) for s in spec.shape[1:])
        rows = {"vertex_frame": p.vertex_row_start[-1], "frame": p.frame_start[-1],
                "sim_frame": p.sim_frame_start[-1]}[spec.table]
        return (int(rows), *tail)

    def _size(self, sym: str | int) -> int:
        if isinstance(sym, int):
            return sym
        if sym == "J":
            return 24
        return int(self.plan.static["body"]["dims"][sym])

    def _sample_blocks(self, spec: ArraySpec):
        staging = self.w.staging
        for i, m in enumerate(self.plan.manifests):
            if spec.name not in m["arrays"]:
                continue
            data = np.load(staging / sample_dir_name(i) / f"{spec.name}.npy", mmap_mode="r")
            if list(data.shape) != m["arrays"][spec.name]["shape"] or str(data.dtype) != spec.dtype:
                raise InputError(f"staged sample {i}: {spec.name}.npy has shape {data.shape} {data.dtype} but its "
                                 f"manifest says {m['arrays'][spec.name]}; delete {staging / sample_dir_name(i)} and "
                                 "stage it again")
            if spec.table == "vertex_frame":
                data = data.reshape(-1, data.shape[-1])
            yield data

    def _write(self, root, spec: ArraySpec, shape: tuple[int, ...], blocks) -> None:
        chunks, shards = chunk_layout(spec, shape, self.chunking.get(spec.table))
        attributes = {"unit": spec.unit, "doc": spec.doc, "table": spec.table}
        if spec.quantum is not None:
            attributes |= {"quantum": spec.quantum, "origin": "frames/joints[:, 0]",
                           "decode": "value * quantum + the frame's root joint (frames/joints[:, 0]), in metres"}
        # every shard is written, zeros too: a missing file then always means damage (validate checks)
        arr = root.create_array(spec.path, shape=shape, dtype=spec.dtype, chunks=chunks, shards=shards,
                                compressors=compressor(spec), fill_value=0, overwrite=True,
                                dimension_names=[str(s) if isinstance(s, str) else None for s in spec.shape],
                                attributes=attributes, config={"write_empty_chunks": True})
        if shape[0] == 0:
            return
        sink = _RowSink(arr, shards[0])
        for block in blocks:
            sink.add(np.asarray(block))
        sink.close()


def _fsync_tree(path: Path, skip: Path) -> None:
    """fsync every file and directory under ``path`` except ``skip`` (so 'complete' is never ahead of the data)."""
    for dirpath, dirnames, files in os.walk(path):
        if Path(dirpath) == skip or skip in Path(dirpath).parents:
            dirnames[:] = []
            continue
        for name in files:
            fd = os.open(os.path.join(dirpath, name), os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        fsync_dir(Path(dirpath))


_GROUP_DOCS = {
    "vertex_frames": TABLES["vertex_frame"].doc,
    "frames": TABLES["frame"].doc,
    "sim_frames": TABLES["sim_frame"].doc,
    "samples": "per-sample scalars, one row per sample",
    "index": "offsets into the row tables, and the segment table",
}
