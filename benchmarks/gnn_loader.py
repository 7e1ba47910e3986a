"""Paper 000's training input from a store against the same frames held in memory, in one run.

The loader of ``drape train gnn`` (:meth:`training.gnn.data.GNNDataModule.train_dataloader`:
torch_geometric's DataLoader over :class:`~training.gnn.data.FrameDataset`, spawned workers that open
the store and derive the features)
against a DataLoader over the same frames built beforehand and kept as ``Data`` objects (only
batching left). Figures are frames per second over whole passes, after one warm-up pass (which
starts the workers). If the first is well above a training step's rate (``gnn``: 110-186
frames/s on an H200), the loader is not what limits training.

    python -m benchmarks gnn-loader STORE [--frames 240] [--workers 0,2,4] [--batch 8]
"""

from __future__ import annotations

import argparse
import time

from datagen.store import open_store
from training.gnn.config import GNNConfig
from training.gnn.data import FrameDataset, GNNDataModule


def rate(loader, passes: int) -> float:
    """Frames per second over ``passes`` whole passes, after one warm-up pass."""
    for _ in loader:
        pass
    n, t0 = 0, time.perf_counter()
    for _ in range(passes):
        for batch in loader:
            n += batch.num_graphs
    return n / (time.perf_counter() - t0)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("store")
    ap.add_argument("--frames", type=int, default=240, help="training frames drawn (seeded) for the pass")
    ap.add_argument("--workers", default="0,2", help="DataLoader worker counts to measure, comma-separated")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--passes", type=int, default=2)
    args = ap.parse_args(argv)
    store = open_store(args.store)
    ds = FrameDataset(store, "train", max_frames=args.frames)
    t0 = time.perf_counter()
    memory = [ds[k] for k in range(len(ds))]
    build = len(memory) / (time.perf_counter() - t0)
    vertices = sum(d.num_nodes for d in memory) / len(memory)
    print(f"{args.store}: {len(ds)} training frames, {vertices:.0f} garment vertices on average; "
          f"batch {args.batch}; {args.passes} timed passes after a warm-up")
    print(f"one frame read and derived in this process: {build:.1f} frames/s")
    for w in (int(x) for x in args.workers.split(",")):
        data = GNNDataModule(store, GNNConfig(batch_size=args.batch, workers=w))
        from_store = rate(data.loader(ds, shuffle=True, graphs=True), args.passes)
        in_memory = rate(data.loader(memory, shuffle=True, graphs=True), args.passes)
        print(f"workers {w}: from the store {from_store:8.1f} frames/s | in memory {in_memory:8.1f} frames/s | "
              f"ratio {from_store / in_memory:.2f}")
