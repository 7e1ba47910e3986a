"""Read a packed dataset store: samples, frames, segments, garment rest meshes, body and fit models.

:func:`open_store` returns a :class:`DatasetStore`. Reads go to the rows they need only: a sample's
frames are contiguous rows of the flat tables, so ``frames(i, slice(a, b))`` reads the chunks
holding rows of frames ``a .. b-1`` of sample ``i`` (inside their shards) and nothing else. The
per-sample tables (offsets, scalars; a few bytes per sample) are read once, on first use.

Two backends read the same store: ``zarr`` (zarr-python, always installed) and ``tensorstore``
(faster for many small reads; ``pip install tensorstore``). ``backend="auto"`` takes tensorstore
when it is installed. A :class:`DatasetStore` pickles without its open handles, so torch
``DataLoader`` workers can share one.

Every read is checked against the store's recorded shard digests: the first time a reader in a
process touches a shard file, the file is hashed and compared (:mod:`datagen.store.integrity`), so a
deleted, truncated, zeroed or bit-flipped shard raises :class:`~datagen.store.integrity.DamagedStoreError`
instead of reading as zeros or as other numbers.
"""

from __future__ import annotations

import logging
import os
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from datagen.errors import InputError
from datagen.geometry.positions import decode_positions
from datagen.store.integrity import ShardGuard, storage_errors
from datagen.store.layout import design_record, read_root_metadata
from schemas.dataset import (
    ARRAYS,
    DATASET_SCHEMA_VERSION,
    DERIVED,
    NAME_LISTS,
    REFUSED_VERSIONS,
    SPLIT_NAMES,
    STATIC_GROUPS,
    STORE_FORMAT,
)

logger = logging.getLogger(__name__)

VERTEX_FRAME_ARRAYS = tuple(a.name for a in ARRAYS.values() if a.table == "vertex_frame")
FRAME_ARRAYS = tuple(a.name for a in ARRAYS.values() if a.table == "frame")
SIM_FRAME_ARRAYS = tuple(a.name for a in ARRAYS.values() if a.table == "sim_frame")
SAMPLE_SCALARS = tuple(a.name for a in ARRAYS.values() if a.table == "sample")
_PATH = {a.name: a.path for a in ARRAYS.values() if a.written_by == "stage_sample"}
_DTYPE = {a.name: np.dtype(a.dtype) for a in ARRAYS.values() if a.written_by == "stage_sample"}
_QUANTUM = {a.name: a.quantum for a in ARRAYS.values() if a.quantum is not None}
DERIVED_ARRAYS = tuple(n for n in DERIVED if n not in FRAME_ARRAYS)
"""Per-frame arrays the reader derives on request (:mod:`datagen.features`), by name."""
DERIVED_VERTEX_ARRAYS = tuple(n for n in DERIVED_ARRAYS if n != "body_vertices")
BINDING_CACHE_SIZE = 256
"""Garment bindings (static data of one garment instance on its body) kept per open store."""


def version_problem(path, version) -> str | None:
    """Why a store of schema ``version`` cannot be read (None when it can)."""
    if version == DATASET_SCHEMA_VERSION:
        return None
    why = REFUSED_VERSIONS.get(version, "it is not a version this drape knows")
    return (f"store {path} has schema version {version}; this drape reads version {DATASET_SCHEMA_VERSION} "
            f"({why}). Make it again from the config it was made with (a store is a pure function of its config and "
            f"seed): `drape info {path} --config > config.yaml && drape generate config.yaml --out NEW`")

def incomplete_message(path) -> str:
    """Why a store whose pack has not finished cannot be read, and the command that finishes it."""
    return (f"store {path} is not complete: its generation or pack was interrupted. Run the same `drape generate` "
            f"command again (it resumes from the staged samples and packs; `drape info {path} --config > "
            f"config.yaml` recovers the config: `drape generate config.yaml --out {path}`)")


TENSORSTORE_CACHE_BYTES = 64 * 1024 * 1024
"""Tensorstore's chunk and shard-index cache per open store (decoded chunks read again are free)."""


class _ZarrRows:
    """Row reads through zarr-python."""

    name = "zarr"

    def __init__(self, path: Path):
        import zarr

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # consolidated metadata is not (yet) in the v3 spec
            self.root = zarr.open_group(store=str(path), mode="r", use_consolidated=True)
        self.arrays: dict[str, Any] = {}

    def array(self, path: str):
        if path not in self.arrays:
            self.arrays[path] = self.root[path]
        return self.arrays[path]

    def read_many(self, requests: Sequence[tuple[str, int, int]]) -> list[np.ndarray]:
        return [self.array(p)[a:b] for p, a, b in requests]

    def read_all(self, path: str) -> np.ndarray:
        return self.array(path)[...]


class _TensorstoreRows:
    """Row reads through tensorstore's zarr3 driver (all reads of one call run concurrently)."""

    name = "tensorstore"

    def __init__(self, path: Path):
        import tensorstore as ts

        self.ts = ts
        self.path = path
        self.context = ts.Context({"cache_pool": {"total_bytes_limit": TENSORSTORE_CACHE_BYTES}})
        self.arrays: dict[str, Any] = {}

    def array(self, path: str):
        if path not in self.arrays:
            spec = {"driver": "zarr3", "kvstore": {"driver": "file", "path": str(self.path / path)}}
            self.arrays[path] = self.ts.open(spec, read=True, context=self.context).result()
        return self.arrays[path]

    def read_many(self, requests: Sequence[tuple[str, int, int]]) -> list[np.ndarray]:
        futures = [self.array(p)[a:b].read() for p, a, b in requests]
        return [np.asarray(f.result()) for f in futures]

    def read_all(self, path: str) -> np.ndarray:
        return np.asarray(self.array(path).read().result())


class _CheckedRows:
    """A backend's row reads, each shard checked against its recorded digest before its first read
    (:class:`~datagen.store.integrity.ShardGuard`), with the array's metadata checked against the
    consolidated copy on its first open and what the backend raises turned into the damaged-store line
    (:func:`~datagen.store.integrity.storage_errors`)."""

    def __init__(self, rows, guard: ShardGuard):
        self.rows = rows
        self.guard = guard
        self.name = rows.name

    def array(self, path: str):
        self.guard.check_metadata(path)
        with storage_errors(self.guard.store, path):
            return self.rows.array(path)

    def read_many(self, requests: Sequence[tuple[str, int, int]]) -> list[np.ndarray]:
        for p, a, b in requests:
            self.guard.check_metadata(p)
            self.guard.check(p, a, b)
        with storage_errors(self.guard.store, ", ".join(sorted({p for p, _, _ in requests}))):
            return self.rows.read_many(requests)

    def read_all(self, path: str) -> np.ndarray:
        self.guard.check_metadata(path)
        self.guard.check(path)
        with storage_errors(self.guard.store, path):
            return self.rows.read_all(path)


def _backend(name: str):
    if name == "auto":
        try:
            import tensorstore  # noqa: F401
        except ImportError:
            return _ZarrRows
        return _TensorstoreRows
    if name == "zarr":
        return _ZarrRows
    if name == "tensorstore":
        from datagen.errors import require

        require("tensorstore", "reading a store with backend='tensorstore'")
        return _TensorstoreRows
    raise InputError(f"unknown store backend {name!r}; choose 'auto', 'zarr' or 'tensorstore'")


def open_store(path: str | Path, *, backend: str = "auto") -> DatasetStore:
    """Open the packed store at ``path`` for reading.

    Raises:
        InputError: ``path`` is not a drape store, is not complete (pack() has not finished), or has
            another schema version.

    Reads from it raise :class:`~datagen.store.integrity.DamagedStoreError` (an ``InputError``) when a
    shard file they touch is missing or differs from what pack wrote.
    """
    return DatasetStore(path, backend=backend)


class DatasetStore:
    """A packed, complete dataset store, read-only.

    Attributes:
        path: the store directory.
        attrs: the root attributes (config, seed, names, units, ...).
        config: the resolved dataset configuration the store was made with.
        seed: the dataset seed.
        sample_count: samples, failed ones included.
        segment_length: frames per segment.
        names: code name lists (``label_names``, ``split_names``, ``failure_names``, ...).
        backend: ``"zarr"`` or ``"tensorstore"``.
    """

    def __init__(self, path: str | Path, *, backend: str = "auto"):
        path = Path(path)
        meta = read_root_metadata(path)
        attrs = meta.get("attributes") if meta is not None else None
        if not isinstance(attrs, dict) or attrs.get("format") != STORE_FORMAT:
            raise InputError(f"{path} is not a drape dataset store (no zarr.json with format '{STORE_FORMAT}')")
        problem = version_problem(path, attrs.get("schema_version"))
        if problem:
            raise InputError(problem)
        if attrs.get("complete") is not True:
            raise InputError(incomplete_message(path))
        self.path = path
        self.attrs = attrs
        self._meta = meta
        self.config: dict = attrs["config"]
        self.seed: int = attrs["seed"]
        self.sample_count: int = attrs["sample_count"]
        self.segment_length: int = attrs["segment_length"]
        self.names: dict[str, tuple[str, ...]] = {k: tuple(attrs[k]) for k in NAME_LISTS}
        self._backend_cls = _backend(backend)
        self.backend: str = self._backend_cls.name
        self._rows = None
        self._pid = os.getpid()
        self._index: dict[str, np.ndarray] | None = None
        self._bindings: dict[int, Any] = {}  # garment instance -> GarmentBinding
        self._body: dict[str, np.ndarray] | None = None
        self._motion_cache: tuple[np.ndarray, np.ndarray, np.ndarray, int] | None = None
        self._shapes: dict[int, Any] = {}

    def __repr__(self) -> str:
        return f"DatasetStore({str(self.path)!r}, samples={self.sample_count}, backend={self.backend!r})"

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_rows"] = None  # reopened lazily in the other process
        state["_bindings"], state["_shapes"] = {}, {}  # rebuilt on use (tensors do not cross processes)
        return state

    def __len__(self) -> int:
        return self.sample_count

    @property
    def rows(self):
        if self._rows is None or self._pid != os.getpid():  # opened here, or reopened in a forked child
            # a new guard per process: each process checks each shard it reads once
            self._rows = _CheckedRows(self._backend_cls(self.path), ShardGuard(self.path, self._meta))
            self._pid = os.getpid()
        return self._rows

    def array(self, path: str):
        """The backend's array object for ``path`` (a ``zarr.Array`` or ``tensorstore.TensorStore``),
        after checking every shard file of it (reads through this object are not checked again)."""
        if path not in ARRAYS:
            raise InputError(f"no array {path!r} in the schema; arrays are {sorted(ARRAYS)}")
        self.rows.guard.check(path)
        return self.rows.array(path)

    def check_files(self, samples: Sequence[int] | None = None) -> None:
        """Check now, against their recorded digests, every shard file that reading ``samples`` (all by
        default) and the static groups touches, so that a command writing one output per sample can
        refuse before it writes anything. Raises :class:`~datagen.store.integrity.DamagedStoreError`."""
        guard = self.rows.guard
        for a in ARRAYS.values():
            guard.check_metadata(a.path)  # an array's zarr.json missing or disagreeing: refused here too
            if a.written_by != "stage_sample" or samples is None:
                guard.check(a.path)
        if samples is None:
            return
        idx = self.index
        for i in (self._check(int(i)) for i in samples):
            f0, f1 = int(idx["frame_start"][i]), int(idx["frame_start"][i + 1])
            s0, s1 = int(idx["sim_frame_start"][i]), int(idx["sim_frame_start"][i + 1])
            v0 = int(idx["vertex_start"][i])
            for n in VERTEX_FRAME_ARRAYS:
                guard.check(_PATH[n], v0, v0 + (f1 - f0) * int(idx["vertex_count"][i]))
            for n in FRAME_ARRAYS:
                guard.check(_PATH[n], f0, f1)
            for n in SIM_FRAME_ARRAYS:
                guard.check(_PATH[n], s0, s1)

    def read(self, path: str, start: int | None = None, stop: int | None = None) -> np.ndarray:
        """Rows ``start:stop`` of the array at ``path`` (all rows by default)."""
        if path not in ARRAYS:
            raise InputError(f"no array {path!r} in the schema; arrays are {sorted(ARRAYS)}")
        if start is None and stop is None:
            return self.rows.read_all(path)
        arr = self.rows.array(path)
        n = int(arr.shape[0])
        start, stop, _ = slice(start, stop).indices(n)
        return self.rows.read_many([(path, start, max(start, stop))])[0]

    # -- per-sample tables (read once)

    @property
    def index(self) -> dict[str, np.ndarray]:
        """In-memory per-sample tables: every scalar by name, plus ``frame_start``, ``sim_frame_start``,
        ``vertex_start`` (first vertex row of each sample), ``vertex_count`` and ``segments``."""
        if self._index is None:
            idx = {name: self.rows.read_all(f"samples/{name}") for name in SAMPLE_SCALARS}
            idx["frame_start"] = self.rows.read_all("index/frame_start")
            idx["sim_frame_start"] = self.rows.read_all("index/sim_frame_start")
            vrs = self.rows.read_all("index/vertex_row_start")
            idx["vertex_start"] = vrs[idx["frame_start"]]
            idx["garment_vertex_start"] = self.rows.read_all("garments/vertex_start")
            idx["garment_face_start"] = self.rows.read_all("garments/face_start")
            idx["garment_stitch_start"] = self.rows.read_all("garments/stitch_start")
            idx["garment_design_start"] = self.rows.read_all("garments/design_start")
            idx["vertex_count"] = np.diff(idx["garment_vertex_start"])[idx["garment"]] if len(idx["garment"]) \
                else np.zeros(0, np.int64)
            idx["segments"] = self.rows.read_all("index/segments")
            self._index = idx
        return self._index

    def _check(self, i: int) -> int:
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= i < self.sample_count:
            raise IndexError(f"sample {i!r} is not in 0 .. {self.sample_count - 1}")
        return int(i)

    def frame_count(self, i: int) -> int:
        """Recorded frames T of sample ``i`` (0 for a failed sample)."""
        i = self._check(i)
        fs = self.index["frame_start"]
        return int(fs[i + 1] - fs[i])

    def sim_frame_count(self, i: int) -> int:
        """Simulated frames T_sim of sample ``i``."""
        i = self._check(i)
        ss = self.index["sim_frame_start"]
        return int(ss[i + 1] - ss[i])

    def vertex_count(self, i: int) -> int:
        """Garment vertices V of sample ``i``."""
        return int(self.index["vertex_count"][self._check(i)])

    def scalars(self, i: int) -> dict[str, Any]:
        """Per-sample scalars of sample ``i`` (numpy scalars of the schema's dtypes)."""
        i = self._check(i)
        return {name: self.index[name][i] for name in SAMPLE_SCALARS}

    # -- splits

    @property
    def splits(self) -> dict[str, np.ndarray]:
        """Split name -> sample indices (int64, ascending), failed samples included."""
        split = self.index["split"]
        return {name: np.flatnonzero(split == code) for code, name in enumerate(SPLIT_NAMES)}

    def split(self, name: str, *, include_failed: bool = True) -> np.ndarray:
        """Sample indices of split ``name`` (``train``, ``val``, ``test``)."""
        if name not in SPLIT_NAMES:
            raise InputError(f"unknown split {name!r}; splits are {list(SPLIT_NAMES)}")
        mask = self.index["split"] == SPLIT_NAMES.index(name)
        if not include_failed:
            mask &= self.index["failure"] == 0
        return np.flatnonzero(mask)

    def iter_split(self, name: str, *, names: Sequence[str] | None = None, include_failed: bool = True
                   ) -> Iterator[tuple[int, dict[str, Any]]]:
        """(index, :meth:`sample`) for every sample of split ``name``, in index order."""
        for i in self.split(name, include_failed=include_failed):
            yield int(i), self.sample(int(i), names=names)

    # -- samples and frames

    def sample(self, i: int, *, names: Sequence[str] | None = None) -> dict[str, Any]:
        """Everything of sample ``i``: vertex-frame arrays [T, V, k], frame arrays [T, ...],
        simulation-frame metrics [T_sim] and the scalars; ``names`` limits the arrays read and may
        name derived arrays (:data:`DERIVED_ARRAYS`; by default none are derived)."""
        i = self._check(i)
        names = self._names(names, VERTEX_FRAME_ARRAYS + FRAME_ARRAYS + SIM_FRAME_ARRAYS + DERIVED_ARRAYS,
                            default=VERTEX_FRAME_ARRAYS + FRAME_ARRAYS + SIM_FRAME_ARRAYS)
        out = self._read_frames(i, 0, self.frame_count(i), [n for n in names if n not in SIM_FRAME_ARRAYS],
                                extra=[n for n in names if n in SIM_FRAME_ARRAYS])
        out.update(self.scalars(i))
        return out

    def frames(self, i: int, frames: slice | int | Sequence[int] = slice(None), *,
               names: Sequence[str] | None = None) -> dict[str, np.ndarray]:
        """Vertex-frame and frame arrays of some recorded frames of sample ``i``.

        Args:
            i: sample index.
            frames: a slice, one frame, or frame indices (in any order) of the sample's T frames.
            names: arrays to read (default: every stored vertex-frame and frame array), stored or
                derived (:data:`DERIVED_ARRAYS`: ``anchor``, ``anchor_normal``, ``anchor_skin``,
                ``skin``, ``coarse_normal``, ``joint_distance``, ``body_vertices``), which are
                computed from the stored ones by :func:`datagen.features.derive`.

        Returns:
            name -> [n, V, k] (vertex-frame) or [n, ...] (frame) for the n selected frames, float32
            metres for positions (decoded from their quantised steps).
        """
        i = self._check(i)
        T = self.frame_count(i)
        names = self._names(names, VERTEX_FRAME_ARRAYS + FRAME_ARRAYS + DERIVED_ARRAYS,
                            default=VERTEX_FRAME_ARRAYS + FRAME_ARRAYS)
        if isinstance(frames, slice):
            start, stop, step = frames.indices(T)
            if step == 1:
                return self._read_frames(i, start, max(start, stop), names)
            wanted = np.arange(start, stop, step)
        else:
            wanted = np.atleast_1d(np.asarray(frames, dtype=np.int64))
            if wanted.ndim != 1:
                raise InputError(f"frames must be a slice, an int or a 1-D list of ints, got shape {wanted.shape}")
            if wanted.size and (wanted.min() < -T or wanted.max() >= T):
                raise IndexError(f"frames {wanted.tolist()} out of range for sample {i} with {T} frames")
            wanted = np.where(wanted < 0, wanted + T, wanted)
        if wanted.size == 0:
            return self._read_frames(i, 0, 0, names)
        lo, hi = int(wanted.min()), int(wanted.max()) + 1
        if hi - lo <= 2 * wanted.size:  # read the covering range once, then pick
            block = self._read_frames(i, lo, hi, names)
            return {n: a[wanted - lo] for n, a in block.items()}
        parts = [self._read_frames(i, int(t), int(t) + 1, names) for t in wanted]
        return {n: np.concatenate([p[n] for p in parts]) for n in names}

    def metrics(self, i: int, *, names: Sequence[str] | None = None) -> dict[str, np.ndarray]:
        """Simulation-frame metrics of sample ``i``, each [T_sim]."""
        i = self._check(i)
        return self._read_frames(i, 0, 0, [], extra=self._names(names, SIM_FRAME_ARRAYS))

    def _names(self, names: Sequence[str] | None, allowed: tuple[str, ...], default: tuple[str, ...] | None = None
               ) -> list[str]:
        if names is None:
            return list(default or allowed)
        unknown = [n for n in names if n not in allowed]
        if unknown:
            raise InputError(f"unknown array name(s) {unknown}; choose from {list(allowed)}")
        return list(names)

    def _read_frames(self, i: int, t0: int, t1: int, names: Sequence[str], extra: Sequence[str] = ()
                     ) -> dict[str, np.ndarray]:
        derived = [n for n in names if n in DERIVED_ARRAYS]
        if not derived and not any(n in _QUANTUM for n in names):
            return self._read_stored(i, t0, t1, names, extra)
        stored = [n for n in names if n not in DERIVED_ARRAYS]
        inputs = {k for n in derived for k in DERIVED[n]} | ({"joints"} if any(n in _QUANTUM for n in stored) else set())
        read = list(dict.fromkeys([*stored, *sorted(inputs)]))
        data = self._read_stored(i, t0, t1, read, extra)
        for n in _QUANTUM:
            if n in data:  # steps of quantum from the root joint (datagen.geometry.positions.encode_positions)
                data[n] = decode_positions(data[n], data["joints"][:, 0], _QUANTUM[n])
        if derived:
            if t1 > t0:
                from datagen.features import derive  # torch: imported when first needed

                data.update(derive(self.binding(int(self.index["garment"][i])), derived, pose=data.get("pose"),
                                   trans=data.get("trans"), coarse=data.get("coarse"), joints=data.get("joints")))
            else:
                V, B = self.vertex_count(i), self._body_model_arrays()["v_template"].shape[0]
                for n in derived:
                    tail = (B, 3) if n == "body_vertices" else (V, 24 if n == "joint_distance" else 3)
                    data[n] = np.zeros((0, *tail), np.float32)
        return {n: data[n] for n in [*names, *extra]}

    def _read_stored(self, i: int, t0: int, t1: int, names: Sequence[str], extra: Sequence[str] = ()
                     ) -> dict[str, np.ndarray]:
        idx = self.index
        V = int(idx["vertex_count"][i])
        f0 = int(idx["frame_start"][i])
        v0 = int(idx["vertex_start"][i])
        s0, s1 = int(idx["sim_frame_start"][i]), int(idx["sim_frame_start"][i + 1])
        requests, shapes = [], []
        for n in names:
            if n in VERTEX_FRAME_ARRAYS:
                requests.append((_PATH[n], v0 + t0 * V, v0 + t1 * V))
                shapes.append((t1 - t0, V, -1))
            else:
                requests.append((_PATH[n], f0 + t0, f0 + t1))
                shapes.append(None)
        for n in extra:
            requests.append((_PATH[n], s0, s1))
            shapes.append(None)
        data = self.rows.read_many(requests) if requests else []
        out = {}
        for n, a, shape in zip([*names, *extra], data, shapes, strict=True):
            a = np.asarray(a, dtype=_DTYPE[n])
            out[n] = a.reshape(shape[0], shape[1], a.shape[-1]) if shape is not None else a
        return out

    # -- segments

    @property
    def segments(self) -> np.ndarray:
        """(sample, first frame) of every segment, [n_segments, 2] int64."""
        return self.index["segments"]

    @property
    def segment_count(self) -> int:
        return len(self.index["segments"])

    def split_segments(self, name: str) -> np.ndarray:
        """Segment indices whose sample is in split ``name``."""
        if name not in SPLIT_NAMES:
            raise InputError(f"unknown split {name!r}; splits are {list(SPLIT_NAMES)}")
        seg = self.index["segments"]
        return np.flatnonzero(self.index["split"][seg[:, 0]] == SPLIT_NAMES.index(name)) if len(seg) else seg[:, 0]

    def motion_segments(self, name: str) -> np.ndarray:
        """(motion, body, first frame) of every ``segment_length``-frame segment of the motions that
        split ``name``'s samples play, once per (motion, body) pair and whether those samples passed
        or failed, [n, 3] int64 in (motion, body, frame) order: paper 001's motion generator learns
        from these (a motion whose every scene failed is still data for it). A motion that samples
        of several splits play is counted in each (give ``split_disjoint: [motions]`` to keep its
        segments out of the other splits)."""
        if name not in SPLIT_NAMES:
            raise InputError(f"unknown split {name!r}; splits are {list(SPLIT_NAMES)}")
        idx = self.index
        mask = idx["split"] == SPLIT_NAMES.index(name)
        pairs = np.unique(np.stack([idx["motion"][mask], idx["body"][mask]], axis=1).astype(np.int64), axis=0)
        L, T = self.segment_length, int(self._motion_tables()[0].shape[1])
        starts = np.arange(0, T - L + 1, L, dtype=np.int64)
        return np.concatenate([np.repeat(pairs.reshape(-1, 2), len(starts), axis=0),
                               np.tile(starts, len(pairs))[:, None]], axis=1).reshape(-1, 3)

    def motion_segment(self, motion: int, body: int, first_frame: int) -> dict[str, Any]:
        """One row of :meth:`motion_segments`: ``pose`` [L, J, 3], ``trans`` [L, 3], ``label`` [L]
        (the motion's), and ``motion``, ``body``, ``first_frame``."""
        m, b, t0 = int(motion), int(body), int(first_frame)
        sl = slice(t0, t0 + self.segment_length)
        pose, trans, labels, n_bodies = self._motion_tables()
        if not (0 <= m < len(pose) and 0 <= b < n_bodies and 0 <= t0 and sl.stop <= pose.shape[1]):
            raise IndexError(f"motion segment ({m}, {b}, {t0}) is outside the store's {len(pose)} motions of "
                             f"{pose.shape[1]} frames and {n_bodies} bodies")
        return {"pose": pose[m, sl], "trans": trans[m, sl], "label": np.full(self.segment_length, labels[m], np.int32),
                "motion": m, "body": b, "first_frame": t0}

    def motion_labels(self) -> np.ndarray:
        """``motions/label`` [M], read once per reader (as :meth:`motion_segment` reads it)."""
        return self._motion_tables()[2]

    def _motion_tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """``motions/pose``, ``motions/trans``, ``motions/label`` and the body count, read once per
        reader (a few MB): a segment is then a slice in memory, where reading the tables per segment
        would decode all of them (5.8 MB on the coarse paper-motion store) for each."""
        if self._motion_cache is None:
            r = self.rows
            self._motion_cache = (r.read_all("motions/pose"), r.read_all("motions/trans"),
                                  r.read_all("motions/label"), len(r.read_all("bodies/betas")))
        return self._motion_cache

    def segment(self, k: int, *, names: Sequence[str] | None = None) -> dict[str, Any]:
        """Segment ``k``: :meth:`frames` of its ``segment_length`` frames, the sample's scalars, and
        ``sample`` and ``first_frame``."""
        seg = self.index["segments"]
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 0 <= k < len(seg):
            raise IndexError(f"segment {k!r} is not in 0 .. {len(seg) - 1}")
        i, t0 = int(seg[k, 0]), int(seg[k, 1])
        out = self.frames(i, slice(t0, t0 + self.segment_length), names=names)
        out.update(self.scalars(i))
        out["sample"], out["first_frame"] = i, t0
        return out

    # -- static groups

    @property
    def garment_count(self) -> int:
        return len(self.index["garment_vertex_start"]) - 1

    def garment(self, g: int) -> dict[str, Any]:
        """Garment instance ``g``: its template (``rest_vertices`` [V, 3] m: the settled drape at rest,
        where ``settled``), ``built_vertices`` [V, 3] (the construction the simulation starts from),
        ``faces`` [F, 3] local indices, ``uv``, ``region``, ``seam``, ``indicator``, ``skin_weights``, its
        attributes (``type``, ``seed``, ``body``, ``material``, ``alpha`` [3], ``rest_area``, ``settled``)
        and its sewing pattern: ``panel`` [V], ``face_panel`` [F], ``rest_uv`` [F, 3, 2] (m, per corner),
        ``stitches`` [P, 2] and ``design`` (the design record as a dict: program, seed, source,
        parameters, pattern), or -1, NaN, no rows and None for a shell garment."""
        if isinstance(g, bool) or not isinstance(g, (int, np.integer)) or not 0 <= g < self.garment_count:
            raise IndexError(f"garment instance {g!r} is not in 0 .. {self.garment_count - 1}")
        idx = self.index
        starts = {"garment_vertex": idx["garment_vertex_start"], "garment_face": idx["garment_face_start"],
                  "garment_stitch": idx["garment_stitch_start"], "garment_design": idx["garment_design_start"]}
        specs = [a for a in ARRAYS.values() if a.group == "garments" and a.table != "offset"]
        requests = []
        for a in specs:
            off = starts.get(a.table)
            start, stop = (off[g], off[g + 1]) if off is not None else (g, g + 1)
            requests.append((a.path, int(start), int(stop)))
        data = self.rows.read_many(requests)
        out = {a.name: (d if a.table != "garment" else d[0]) for a, d in zip(specs, data, strict=True)}
        out["design"] = design_record(out["design"], np.array([0, len(out["design"])]), 0)
        return out

    def group(self, name: str) -> dict[str, np.ndarray]:
        """Every array of a static group (``body``, ``bodies``, ``motions``, ``garments``, ``fit``), whole."""
        if name not in STATIC_GROUPS:
            raise InputError(f"unknown static group {name!r}; groups are {list(STATIC_GROUPS)}")
        return {a.name: self.rows.read_all(a.path) for a in ARRAYS.values() if a.group == name}

    def body_model(self) -> dict[str, np.ndarray]:
        """The SMPL-format body model: ``v_template`` [B, 3], ``shapedirs`` [B, 3, S], ``J_regressor``
        [J, B], ``weights`` [B, J], ``parents`` [J], ``faces`` [Fb, 3], and the subdivided body's
        recipe: ``subdivision_edges`` [E, 2] (vertex B + e is edge e's midpoint) and
        ``subdivided_faces`` [4 Fb, 3]."""
        return dict(self._body_model_arrays())

    def _body_model_arrays(self) -> dict[str, np.ndarray]:
        if self._body is None:
            self._body = self.group("body")
        return self._body

    def binding(self, g: int):
        """What deriving garment instance ``g``'s features needs (its rest mesh, indicator rows of the
        subdivided body, its body's shape): :func:`datagen.features.bind_garment`, cached.
        Trainers call :func:`datagen.features.derive` with it on their own device."""
        from datagen.features import bind_garment, body_shape

        if g not in self._bindings:
            garment = self.garment(g)
            b = int(garment["body"])
            if b not in self._shapes:
                self._shapes[b] = body_shape(self._body_model_arrays(), self.betas()[b])
            if len(self._bindings) >= BINDING_CACHE_SIZE:
                self._bindings.pop(next(iter(self._bindings)))
            self._bindings[g] = bind_garment(self._shapes[b], garment["rest_vertices"], garment["faces"],
                                             garment["indicator"])
        return self._bindings[g]

    def betas(self) -> np.ndarray:
        """Shape coefficients of every body, [n_bodies, S]."""
        return self.rows.read_all("bodies/betas")

    def motions(self) -> dict[str, np.ndarray]:
        """Motion tables: ``label``, ``seed``, ``frame_count``, each [M]; ``pose`` [M, T_m, J, 3] and
        ``trans`` [M, T_m, 3], every motion's recorded frames."""
        return self.group("motions")

    def fit_model(self) -> dict[str, np.ndarray]:
        """The fit-attribute factor-analysis model: ``components`` [3, D], ``mean`` [D],
        ``noise_variance`` [D], ``subsample`` [3]; D = 0 when the store has no fit attribute (root
        attribute ``fit_attribute`` false; its health is in ``attrs["fit_diagnostics"]``)."""
        return self.group("fit")
