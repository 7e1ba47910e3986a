"""Paper 001's garment regressor at the paper's size (d_model 256, M = 2, 4 heads, feed-forward 512,
learned BOS MLP 1024/4096): parameters and the time to predict a garment sequence by greedy
decoding (T = 60 frames, each predicted frame fed back), per frame, on the CPU or a GPU. No store
needed: the weights are untrained (speed does not depend on them) and the poses random.

    python -m benchmarks garment-model [--device cpu|cuda] [--vertices 2950 3274] [--batch 1 8]

On CUDA each size is timed launched step by step and replayed as one captured CUDA graph
(``GarmentRegressor.generate(graph=True)``, what ``drape evaluate`` and ``drape sample clothed`` use).

Paper 001 reports 11.7-13.2 ms per frame on an RTX 3090 (about 300x ARCSim); drape's simulator on
the same kind of garment is in docs/simulator.md's throughput table (batch 1: 287 ms per frame with
self-collision on an H200).
"""

from __future__ import annotations

import argparse
import time

import torch


def main(argv=None) -> int:
    from training.garment.model import GarmentRegressor
    from training.paper001.frames import FRAME_FEATURES

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--vertices", type=int, nargs="+", default=[2950], help="template vertex counts")
    ap.add_argument("--batch", type=int, nargs="+", default=[1, 8], help="sequences predicted at once")
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    dev = torch.device(args.device)
    torch.manual_seed(0)

    def sync():
        if dev.type == "cuda":
            torch.cuda.synchronize(dev)

    name = torch.cuda.get_device_name(dev) if dev.type == "cuda" else "CPU"
    print(f"device {dev} ({name}), torch {torch.__version__}, T = {args.frames}, greedy decoding")
    print(f"{'vertices':>8} {'params':>10} {'MB':>6} {'batch':>5} {'graph':>5} {'ms/sequence':>12} {'ms/frame':>9} "
          f"{'frames/s':>9}")
    for v in args.vertices:
        model = GarmentRegressor(v).to(dev).eval()
        params = sum(p.numel() for p in model.parameters())
        for b in args.batch:
            poses = torch.randn(b, args.frames, FRAME_FEATURES, device=dev)
            for graph in (False, True) if dev.type == "cuda" else (False,):
                model.generate(poses, graph=graph)  # warm-up (kernels, allocator; the graph's capture)
                sync()
                t = time.perf_counter()
                for _ in range(args.repeat):
                    model.generate(poses, graph=graph)
                sync()
                seq = (time.perf_counter() - t) / args.repeat
                per_frame = seq / (b * args.frames)
                print(f"{v:8d} {params:10,d} {params * 4 / 2**20:6.1f} {b:5d} {'on' if graph else 'off':>5} "
                      f"{1000 * seq:12.1f} {1000 * per_frame:9.3f} {1 / per_frame:9.0f}", flush=True)
    return 0
