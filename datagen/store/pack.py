"""Pack a dataset store: build the flat, sharded zarr arrays of :mod:`schemas.dataset` from the
staging area, write the root attributes and consolidated metadata, and mark the store complete
(one atomic rename of the root metadata), all in one process.

:class:`PackPlan` reads the staged manifests and cross-checks them (every sample and static group
staged, codes in range, vertex counts matching their garment instance) before anything is
written; :class:`Packer` writes. :meth:`datagen.store.writer.StoreWriter.pack` holds the lock,
runs both and removes the staging area; a killed pack is simply run again.
"""

from __future__ import annotations

import json
import os
import shutil
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from datagen import __version__
from datagen.errors import InputError
from datagen.store.checks import SAMPLE_ARRAYS, SAMPLE_SCALARS, raise_problems
from datagen.store.layout import (
    MARKER,
    PACK_LOCK,
    ROOT_METADATA,
    STAGING,
    chunk_layout,
    fsync_dir,
    sample_dir_name,
    segment_table,
    shard_checksums,
    specs_of_group,
    static_dir_name,
    write_json_atomic,
)
from schemas.dataset import ARRAYS, COMPRESSION, SPLIT_NAMES, STATIC_GROUPS, STORE_FORMAT, TABLES, ArraySpec, Chunking

if TYPE_CHECKING:
    from datagen.store.writer import StoreWriter

__all__ = ["PackPlan", "Packer", "compressor"]


def compressor(spec: ArraySpec | None = None):
    """The chunk compressor of ``spec`` (``schemas.dataset.COMPRESSION`` unless the spec names its own;
    tensorstore's zarr3 driver reads both)."""
    from zarr.codecs import BloscCodec

    c = (spec.compression if spec is not None else None) or COMPRESSION
    return BloscCodec(cname=c["cname"], clevel=c["clevel"], shuffle=c["shuffle"])


class PackPlan:
    """What pack() will write: manifests, offsets, segments, static groups; all cross-checks done."""

    @classmethod
    def build(cls, writer: StoreWriter) -> PackPlan:
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
        raise_problems(problems, "Nothing was packed.")
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
        raise_problems(problems, "Nothing was packed.")
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
        raise_problems(problems, "Nothing was packed.")
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


class Packer:
    """Writes the packed store from the staging area by a :class:`PackPlan`, then marks it complete."""

    def __init__(self, writer: StoreWriter, plan: PackPlan, chunking: dict[str, Chunking],
                 provenance: dict[str, str] | None = None):
        self.w = writer
        self.plan = plan
        self.chunking = chunking
        self.provenance = dict(provenance or {})

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
                 "checksums": checksums,
                 "provenance": {**self.provenance, "packed_at": _utc_now()}}  # how it was made (the card says)
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


def _utc_now() -> str:
    import datetime

    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")


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
