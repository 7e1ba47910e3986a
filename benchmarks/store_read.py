"""Read throughput of a dataset store against the same arrays held in memory, in one run.

Each access pattern goes through the same :class:`~datagen.store.DatasetStore` code, once reading
the store (zarr-python and/or tensorstore backends) and once reading numpy arrays loaded into
memory beforehand (derivation of the features included in both); the ratio is the price of the
store. Patterns: whole random samples (stored arrays), random segments with what paper 001 reads,
random single frames with every feature paper 000 needs (derived ones included), and a sequential
pass over the train split. Figures are samples (or segments, frames) per second and MB/s of decoded
array bytes. The store's files are usually in the OS page cache (a just-built store always is):
this measures decoding and library overhead, not the disk.

    python -m benchmarks store-read STORE [--reads 200] [--backends zarr,tensorstore]
    python -m benchmarks store-read --synthetic 16 [--vertices 4000 --frames 60 --body-vertices 6890] [--out DIR]

``--synthetic N`` builds (with the real writer and packer) a store of N samples of smooth random
motion at the given sizes, reports staging and packing speed, then benchmarks it.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from datagen.store import StoreWriter, open_store, store_info
from datagen.store.layout import directory_bytes
from schemas.dataset import ARRAYS

MB = 1e6
PAPER_000_FRAME = ["detail", "coarse", "anchor", "anchor_normal", "anchor_skin", "coarse_normal", "skin",
                   "joint_distance", "joints", "pose", "trans"]
"""Everything paper 000's GNN reads of one frame: positions, targets and node features (derived included)."""
PAPER_001_SEGMENT = ["pose", "trans", "label", "detail"]
"""What paper 001's models read of one segment: the motion, its label and the garment's vertices."""


class MemoryRows:
    """The reader's row interface over numpy arrays held in memory (copies on read, as a store read does)."""

    name = "memory"

    def __init__(self, arrays: dict[str, np.ndarray]):
        self.arrays = arrays

    def array(self, path):
        return self.arrays[path]

    def read_many(self, requests):
        return [self.arrays[p][a:b].copy() for p, a, b in requests]

    def read_all(self, path):
        return self.arrays[path].copy()


# --------------------------------------------------------------------------------------- synthetic


def synthetic_static(G: int, V: int, B: int, S: int = 10, D: int = 256, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    f32, J = np.float32, 24
    w = rng.random((B, J)).astype(f32)
    V_g = V + np.arange(G) * 37
    F_g = 2 * V_g - 40
    nv, nf = int(V_g.sum()), int(F_g.sum())
    parents = np.array([-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21], np.int32)
    faces = rng.integers(0, B, (2 * B, 3)).astype(np.int32)
    edges = np.unique(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    Bs = B + len(edges)
    return {
        "body": ({"v_template": rng.normal(size=(B, 3)).astype(f32),
                  "shapedirs": rng.normal(size=(B, 3, S)).astype(f32),
                  "J_regressor": (np.eye(J, B) + 0).astype(f32), "weights": w / w.sum(1, keepdims=True),
                  "parents": parents, "faces": faces, "subdivision_edges": edges.astype(np.int32),
                  "subdivided_faces": rng.integers(0, Bs, (8 * B, 3)).astype(np.int32)}, {}),
        "bodies": ({"betas": rng.normal(size=(G, S)).astype(f32)}, {"body_names": [f"body-{g}" for g in range(G)]}),
        "motions": ({"label": np.zeros(G, np.int32), "seed": np.arange(G, dtype=np.int32),
                     "frame_count": np.full(G, 60, np.int32)}, {"label_names": ["walk"]}),
        "garments": ({"vertex_start": np.concatenate([[0], np.cumsum(V_g)]).astype(np.int64),
                      "face_start": np.concatenate([[0], np.cumsum(F_g)]).astype(np.int64),
                      "rest_vertices": rng.normal(size=(nv, 3)).astype(f32),
                      "faces": np.concatenate([rng.integers(0, v, (f, 3)) for v, f in zip(V_g, F_g, strict=True)]
                                              ).astype(np.int32),
                      "uv": rng.random((nv, 2)).astype(f32), "region": np.zeros(nv, np.int32),
                      "seam": np.zeros(nv, np.uint8), "indicator": rng.integers(0, Bs, nv).astype(np.int32),
                      "skin_weights": rng.random((nv, J)).astype(f32), "type": np.zeros(G, np.int32),
                      "seed": np.arange(G, dtype=np.int32), "body": np.arange(G, dtype=np.int32),
                      "material": np.zeros(G, np.int32), "alpha": rng.normal(size=(G, 3)).astype(f32),
                      "rest_area": np.ones(G, f32)},
                     {"garment_type_names": ["tshirt"], "material_names": ["cotton"], "region_names": ["panel0"]}),
        "fit": ({"components": rng.normal(size=(3, D)).astype(f32), "mean": rng.normal(size=D).astype(f32),
                 "noise_variance": rng.random(D).astype(f32), "subsample": np.array([1, D, 0], dtype=np.int64)}, {}),
    }, V_g


def synthetic_sample(i: int, V: int, T: int, B: int, G: int, lead: int = 30) -> tuple[dict, dict]:
    """Smooth motion: rest positions plus a slow random walk per vertex (compresses like real data roughly)."""
    rng = np.random.default_rng([7, i])
    f32, J = np.float32, 24

    def moving(shape_tail, scale=0.005):
        base = rng.normal(scale=0.3, size=shape_tail)
        walk = np.cumsum(rng.normal(scale=scale, size=(T, *shape_tail)), axis=0)
        return (base + walk).astype(f32)

    arrays = {name: moving((V, 3)) for name in ("detail", "coarse")}
    arrays |= {"pose": moving((J, 3), 0.02), "trans": moving((3,), 0.01), "joints": moving((J, 3)),
               "label": np.zeros(T, np.int32)}
    T_sim = lead + T
    arrays |= {"metric_stretch_max": rng.random(T_sim).astype(f32),
               "metric_stretch_mean": rng.random(T_sim).astype(f32),
               "metric_penetration_count": rng.integers(0, 5, T_sim).astype(np.int32),
               "metric_penetration_depth": (rng.random(T_sim) * 1e-3).astype(f32),
               "metric_self_intersections": rng.integers(0, 3, T_sim).astype(np.int32),
               "metric_kinetic_energy": rng.random(T_sim).astype(f32), "metric_nan": np.zeros(T_sim, np.uint8),
               "metric_slip": rng.random(T_sim).astype(f32) * 1e-2}
    g = i % G
    scalars = {"garment": g, "body": g, "motion": g, "split": 0 if g < max(1, G - 2) else (1 if g == G - 2 else 2),
               "failure": 0, "failure_frame": -1, "recorded_from": lead, "seconds": 1.0}
    return arrays, scalars


def build_synthetic(path: Path, n: int, V: int, T: int, B: int) -> None:
    G = max(3, min(n, 8))
    static, V_g = synthetic_static(G, V, B)
    writer = StoreWriter.open(path, config={"synthetic": {"samples": n, "vertices": V, "frames": T}}, seed=0,
                              sample_count=n)
    t0 = time.perf_counter()
    for group, (arrays, names) in static.items():
        writer.stage_static(group, arrays, names)
    staged_bytes, t_gen = 0, 0.0
    for i in writer.missing():
        tg = time.perf_counter()
        arrays, scalars = synthetic_sample(i, int(V_g[i % G]), T, B, G)
        t_gen += time.perf_counter() - tg
        staged_bytes += sum(a.nbytes for a in arrays.values())
        writer.stage_sample(i, arrays, scalars)
    t_stage = time.perf_counter() - t0 - t_gen
    t0 = time.perf_counter()
    writer.pack()
    t_pack = time.perf_counter() - t0
    print(f"built {path}: {n} samples of V ~ {V}, T = {T}, B = {B}; {staged_bytes / MB:.0f} MB of sample arrays; "
          f"staging {staged_bytes / MB / max(t_stage, 1e-9):.0f} MB/s (fsync on), packing "
          f"{staged_bytes / MB / t_pack:.0f} MB/s ({t_pack:.1f} s)")


# --------------------------------------------------------------------------------------- measuring


def sample_bytes(d: dict) -> int:
    return sum(v.nbytes for v in d.values() if isinstance(v, np.ndarray))


def measure(fn, items, min_seconds: float = 1.0) -> tuple[float, float, int]:
    """(items per second, MB per second, items) of ``fn`` over ``items`` (repeated until ``min_seconds``)."""
    fn(items[0])  # open handles, warm caches of metadata
    done, nbytes, t0 = 0, 0, time.perf_counter()
    while True:
        for it in items:
            nbytes += sample_bytes(fn(it))
            done += 1
        elapsed = time.perf_counter() - t0
        if elapsed >= min_seconds:
            return done / elapsed, nbytes / MB / elapsed, done


def measure_passes(store, min_seconds: float) -> tuple[float, float, int]:
    """Like :func:`measure`, for whole passes of ``store.iter_split("train")``."""
    done, nbytes, t0 = 0, 0, time.perf_counter()
    while True:
        for _, sample in store.iter_split("train", include_failed=False):
            nbytes += sample_bytes(sample)
            done += 1
        elapsed = time.perf_counter() - t0
        if elapsed >= min_seconds:
            return done / elapsed, nbytes / MB / elapsed, done


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("store", nargs="?", type=Path, help="a packed store (or where --synthetic builds one)")
    ap.add_argument("--synthetic", type=int, metavar="N", help="build a synthetic store of N samples first")
    ap.add_argument("--vertices", type=int, default=4000, help="garment vertices of synthetic samples")
    ap.add_argument("--frames", type=int, default=60, help="recorded frames of synthetic samples")
    ap.add_argument("--body-vertices", type=int, default=6890, help="body vertices of synthetic samples")
    ap.add_argument("--reads", type=int, default=64, help="random items per access pattern")
    ap.add_argument("--seconds", type=float, default=1.5, help="minimum time per measurement")
    ap.add_argument("--backends", default=None,
                    help="comma-separated: zarr, tensorstore (default: both, or zarr without tensorstore installed)")
    ap.add_argument("--keep", action="store_true", help="keep a synthetic store built in a temporary directory")
    args = ap.parse_args(argv)
    if args.backends is None:
        try:
            import tensorstore  # noqa: F401

            args.backends = "zarr,tensorstore"
        except ImportError:
            args.backends = "zarr"
    tmp = None
    if args.synthetic:
        if args.store is None:
            tmp = Path(tempfile.mkdtemp(prefix="drape-bench-store-"))
            args.store = tmp / "store"
        build_synthetic(args.store, args.synthetic, args.vertices, args.frames, args.body_vertices)
    elif args.store is None:
        ap.error("give a store path, or --synthetic N")
    try:
        run(args)
    finally:
        if tmp is not None and not args.keep:
            shutil.rmtree(tmp)


def run(args) -> None:
    info = store_info(args.store)
    raw = sum(v["uncompressed"] for v in info["sizes"].values())
    print(f"store {args.store}: {info['sample_count']} samples ({info['totals']['ok']} ok), "
          f"{info['totals']['frames']} frames, {info['totals']['segments']} segments; "
          f"{raw / MB:.0f} MB uncompressed, {directory_bytes(args.store) / MB:.0f} MB on disk")
    reference = open_store(args.store, backend="zarr")
    paths = list(ARRAYS)  # per-sample and static arrays alike
    t0 = time.perf_counter()
    memory = {p: reference.read(p) for p in paths}
    print(f"loaded the per-sample arrays into memory for the reference in {time.perf_counter() - t0:.1f} s "
          f"({sum(a.nbytes for a in memory.values()) / MB:.0f} MB)")
    rng = np.random.default_rng(0)
    ok = np.flatnonzero(reference.index["failure"] == 0)
    samples = rng.choice(ok, size=min(args.reads, len(ok)), replace=len(ok) < args.reads).tolist()
    frames = [(i, int(rng.integers(reference.frame_count(i)))) for i in samples]
    segments = rng.choice(reference.segment_count, size=min(args.reads, max(1, reference.segment_count))).tolist() \
        if reference.segment_count else []
    train = [None] if len(reference.split("train", include_failed=False)) else []
    readers = {"memory": open_store(args.store, backend="zarr")}
    readers["memory"]._rows = MemoryRows(memory)
    for name in args.backends.split(","):
        readers[name] = open_store(args.store, backend=name.strip())
    patterns = [("sample (random)", "samples", lambda s, i: s.sample(i), samples),
                ("segment (001)", "segments", lambda s, k: s.segment(k, names=PAPER_001_SEGMENT), segments),
                ("frame (000)", "frames", lambda s, it: s.frames(it[0], it[1], names=PAPER_000_FRAME), frames),
                ("iter_split(train)", "samples", None, train)]
    names = [n for n in readers if n != "memory"]
    print(f"{'access':<19}{'backend':<13}{'items/s':>10}{'MB/s':>9}{'memory items/s':>16}{'memory MB/s':>13}"
          f"{'memory/store':>14}")
    for label, unit, fn, items in patterns:
        if not items:
            print(f"{label:<19}(none in this store)")
            continue
        rates = {}
        for name, store in readers.items():
            if fn is None:  # sequential passes over the train split through iter_split
                rates[name] = measure_passes(store, args.seconds)
            else:
                rates[name] = measure(lambda it, store=store, fn=fn: fn(store, it), items, args.seconds)
        mem = rates["memory"]
        for k, name in enumerate(names):
            r = rates[name]
            print(f"{label if k == 0 else '':<19}{name:<13}{r[0]:>10.1f}{r[1]:>9.0f}{mem[0]:>16.1f}{mem[1]:>13.0f}"
                  f"{mem[0] / r[0]:>13.1f}x")
    print("(items: samples, segments or frames as the access names them; MB: decoded array bytes, 1e6 B)")
