"""Bytes per stored garment-frame of a dataset store, per array, against what schema 3 stored.

After: each array's bytes on disk (its directory) over the store's recorded garment-frames.
Before: the arrays schema 3 kept per frame (float32 positions, the derived features, the posed
body) made again from this store for up to ``--samples`` samples (the derived ones through the
reader, the same function as on read) and compressed as schema 3 did (blosc lz4 + bit-shuffle,
256 KiB chunks), per garment-frame. Per-vertex and per-frame parts are also scaled to a
``--vertices``-vertex garment (the issue's figure is for ~4,000).

    python -m benchmarks store-size STORE [--samples 8] [--vertices 4000] [--codecs]

``--codecs`` also compresses ``detail`` of the first samples in the candidate encodings (float32
metres; int16/int32 steps of the quantum from the anchor or from the root joint) with the
candidate blosc codecs, and prints bytes per vertex-component and decode speed: the measurement
behind ``schemas.dataset.POSITION_COMPRESSION``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from datagen.store import open_store
from datagen.store.layout import directory_bytes
from schemas.dataset import ARRAYS

V3_PER_VERTEX = ("detail", "coarse", "anchor", "anchor_normal", "anchor_skin", "coarse_normal", "skin",
                 "joint_distance")
V3_PER_FRAME = ("pose", "trans", "joints", "label", "body_vertices")
CHUNK = 256 * 1024


def compressed(a: np.ndarray) -> int:
    from numcodecs import Blosc

    codec = Blosc(cname="lz4", clevel=5, shuffle=Blosc.BITSHUFFLE)
    raw = np.ascontiguousarray(a).reshape(len(a), -1)
    rows = max(1, CHUNK // max(1, raw[0].nbytes))
    return sum(len(codec.encode(raw[k:k + rows])) for k in range(0, len(raw), rows))


def codec_table(s, samples: list[int]) -> None:
    import time

    from numcodecs import Blosc

    from schemas.dataset import POSITION_QUANTUM as q

    codecs = [("lz4", Blosc.BITSHUFFLE), ("zstd", Blosc.SHUFFLE), ("zstd", Blosc.BITSHUFFLE)]
    print(f"\ndetail, bytes per vertex-component after compression (decode GB/s); {len(samples)} samples")
    print(f"{'encoding':<34}" + "".join(f"{c + ('+bitshuffle' if sh == Blosc.BITSHUFFLE else '+shuffle'):>26}"
                                         for c, sh in codecs))
    x = [s.sample(i, names=["detail", "anchor", "joints"]) for i in samples]
    encodings = {
        "float32 metres": lambda d: d["detail"],
        "int16 steps from the anchor": lambda d: np.rint((d["detail"] - d["anchor"]) / q).astype(np.int16),
        "int16 steps from the root joint": lambda d: np.rint((d["detail"] - d["joints"][:, None, 0]) / q).astype(
            np.int16),
        "int32 steps from the root joint": lambda d: np.rint((d["detail"] - d["joints"][:, None, 0]) / q).astype(
            np.int32),
    }
    for name, enc in encodings.items():
        row = f"{name:<34}"
        for cname, shuffle in codecs:
            codec = Blosc(cname=cname, clevel=5, shuffle=shuffle)
            nbytes, comps, dec, raw = 0, 0, 0.0, 0
            for d in x:
                a = np.ascontiguousarray(enc(d)).reshape(-1, 3)
                e = codec.encode(a)
                nbytes, comps, raw = nbytes + len(e), comps + a.size, raw + a.nbytes
                t = time.perf_counter()
                codec.decode(e)
                dec += time.perf_counter() - t
            row += f"{nbytes / comps:>14.2f} B ({raw / dec / 1e9:>4.1f} GB/s)"
        print(row)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("store", type=Path)
    ap.add_argument("--samples", type=int, default=8, help="samples to rebuild schema 3's arrays from")
    ap.add_argument("--vertices", type=int, default=4000, help="garment size to scale the figures to")
    ap.add_argument("--codecs", action="store_true", help="also compare position encodings and codecs")
    args = ap.parse_args(argv)
    s = open_store(args.store, backend="zarr")
    idx = s.index
    T = np.diff(idx["frame_start"])
    frames = int(T.sum())
    vrows = int((T * idx["vertex_count"]).sum())
    mean_v = vrows / max(frames, 1)
    print(f"store {args.store}: {frames} garment-frames, {mean_v:.0f} garment vertices on average")
    print(f"\nafter (schema {s.attrs['schema_version']}, on disk)")
    print(f"{'array':<28}{'B/garment-frame':>16}{'B/vertex':>10}{f'at V={args.vertices}':>12}")
    after_total, after_scaled = 0.0, 0.0
    for path, spec in ARRAYS.items():
        if spec.table not in ("vertex_frame", "frame"):
            continue
        b = directory_bytes(args.store / path) / max(frames, 1)
        scaled = b / mean_v * args.vertices if spec.table == "vertex_frame" else b
        after_total += b
        after_scaled += scaled
        per_v = f"{b / mean_v:.2f}" if spec.table == "vertex_frame" else "-"
        print(f"{path:<28}{b:>16.0f}{per_v:>10}{scaled:>12.0f}")
    print(f"{'total':<28}{after_total:>16.0f}{'':>10}{after_scaled:>12.0f}")

    ok = [i for i in range(s.sample_count) if s.frame_count(i)][: args.samples]
    sizes = {n: 0 for n in V3_PER_VERTEX + V3_PER_FRAME}
    n_frames, n_rows = 0, 0
    for i in ok:
        x = s.sample(i, names=list(V3_PER_VERTEX + V3_PER_FRAME))
        Ti, Vi = x["detail"].shape[:2]
        n_frames += Ti
        n_rows += Ti * Vi
        for n in sizes:
            a = x[n]
            sizes[n] += compressed(a.reshape(Ti * Vi, -1) if n in V3_PER_VERTEX else a)
    mean_v3 = n_rows / max(n_frames, 1)
    print(f"\nbefore (schema 3's arrays rebuilt from {len(ok)} samples, {n_frames} garment-frames, "
          f"{mean_v3:.0f} vertices on average; lz4 + bit-shuffle as schema 3 stored them)")
    print(f"{'array':<28}{'B/garment-frame':>16}{'B/vertex':>10}{f'at V={args.vertices}':>12}")
    before_total, before_scaled = 0.0, 0.0
    for n, total in sizes.items():
        b = total / max(n_frames, 1)
        scaled = b / mean_v3 * args.vertices if n in V3_PER_VERTEX else b
        before_total += b
        before_scaled += scaled
        per_v = f"{b / mean_v3:.2f}" if n in V3_PER_VERTEX else "-"
        group = "vertex_frames" if n in V3_PER_VERTEX else "frames"
        print(f"{group + '/' + n:<28}{b:>16.0f}{per_v:>10}{scaled:>12.0f}")
    print(f"{'total':<28}{before_total:>16.0f}{'':>10}{before_scaled:>12.0f}")
    print(f"\nper garment-frame: {before_total / 1024:.1f} KiB -> {after_total / 1024:.1f} KiB "
          f"({before_total / max(after_total, 1):.1f}x smaller); at {args.vertices} vertices "
          f"{before_scaled / 1024:.1f} KiB -> {after_scaled / 1024:.1f} KiB")
    if args.codecs:
        codec_table(s, ok[:3])
