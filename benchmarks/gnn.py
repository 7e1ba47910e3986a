"""Paper 000's GNN: model size, inference time per frame and training throughput, on a synthetic
garment-sized graph (a triangulated grid of about ``--vertices`` vertices; no store needed).

Inference is :meth:`GNNModule.predict_frames` on one frame: W_coarse, the detail features
recomputed from the predicted coarse mesh, W_parser and W_detail (what ``drape predict`` runs per
frame); then the same with static shapes (``set_static_shapes``), and on a GPU captured as one
CUDA graph (``GNNModule.captured_predictor``). Training throughput is frames per second of full optimiser steps (forward, backward, Adam)
at ``--batch`` frames per step. Paper 000: W_coarse 18.4 MB, W_detail + W_parser 19 MB, 21 ms per
frame on an RTX 2080 Ti.

    python -m benchmarks gnn [--vertices 3500] [--batch 8] [--device cpu|cuda] [--ablation full] [--compile]
"""

from __future__ import annotations

import argparse
import time

import torch

from training.gnn.config import GNNConfig
from tests.training.grids import grid_frame  # the GNN tests' synthetic frame (run from the repository root)
from training.gnn.module import GNNModule


def compiled_one_frame(module, one, per_frame, dev, tf32: bool = False, mode: str | None = None) -> None:
    """One frame's prediction through ``torch.compile`` (static shapes): inductor fuses the
    elementwise work of ~1,500 operations into fewer kernels; on CUDA ``reduce-overhead`` also
    replays them as CUDA graphs. Prints the compile time, ms per frame and the largest difference
    to the eager prediction (in float32 matmuls also where ``tf32``: the compiled model's matrix
    products then run on TF32 tensor cores, 10-bit mantissas, and the difference says what that costs).
    ``mode`` overrides inductor's mode (``max-autotune``: it also times candidate kernels for each
    matrix product and keeps the fastest, with CUDA graphs; minutes to compile)."""
    from types import SimpleNamespace

    names = module.PREDICT_INPUTS

    def predict(*xs):
        return module.predict_frames(SimpleNamespace(**dict(zip(names, xs, strict=True))))

    mode = mode or ("reduce-overhead" if dev.type == "cuda" else "default")
    module.model.set_static_shapes(True)
    inputs = [getattr(one, k) for k in names]
    eager = predict(*inputs)
    label = mode + (", TF32 matmuls" if tf32 else "")
    try:
        torch._dynamo.reset()
        if tf32:
            torch.set_float32_matmul_precision("high")
        t0 = time.perf_counter()
        compiled = torch.compile(predict, mode=mode, dynamic=False)
        out = compiled(*inputs)
        seconds = time.perf_counter() - t0
        diff = max(float((a - b).abs().max()) for a, b in zip(out, eager, strict=True))
        ms, n = per_frame(lambda _: compiled(*inputs), one, 1)
    except Exception as exc:  # noqa: BLE001 (a benchmark row: say what failed, time the rest)
        print(f"inference, torch.compile ({label}): failed: {type(exc).__name__}: {str(exc).splitlines()[0][:300]}")
        return
    finally:
        torch.set_float32_matmul_precision("highest")
    print(f"inference, torch.compile ({label}): {ms:.1f} ms per frame (batch of 1; {n} runs; compiled in "
          f"{seconds:.0f} s; largest difference to eager {diff:.2e} m)")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vertices", type=int, default=3500)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    ap.add_argument("--ablation", default="full")
    ap.add_argument("--seconds", type=float, default=5.0, help="minimum time per measurement")
    ap.add_argument("--compile", action="store_true",
                    help="also one frame through torch.compile (static shapes; on CUDA mode reduce-overhead, which "
                         "fuses the kernels and replays them as CUDA graphs): compile time, ms, difference to eager")
    ap.add_argument("--tf32", action="store_true", help="with --compile: a second compiled row with TF32 matmuls")
    ap.add_argument("--compile-only", action="store_true", help="with --compile: only the compiled rows")
    ap.add_argument("--max-autotune", action="store_true",
                    help="with --compile: also a row compiled in inductor's max-autotune mode (float32 matmuls)")
    args = ap.parse_args(argv)
    from torch_geometric.data import Batch

    dev = torch.device(args.device)
    module = GNNModule(GNNConfig(ablation=args.ablation), 85).to(dev)
    params = sum(p.numel() for p in module.parameters())
    parts = {name: sum(p.numel() * p.element_size() for p in m.parameters()) / 1e6
             for name, m in (("W_coarse", module.model.coarse), ("W_detail + W_parser", module.model.detail))
             if m is not None}
    one = Batch.from_data_list([grid_frame(args.vertices)]).to(dev)
    batch = Batch.from_data_list([grid_frame(args.vertices, s) for s in range(args.batch)]).to(dev)
    print(f"{args.ablation}: {params:,} parameters; " + ", ".join(f"{k} {v:.1f} MB" for k, v in parts.items())
          + f"; graph of {one.num_nodes} vertices, {one.edge_index.shape[1]} directed edges; device {dev}")

    def sync():
        if dev.type == "cuda":
            torch.cuda.synchronize()

    def per_frame(call, graph, frames: int) -> tuple[float, int]:
        """ms per frame of ``call(graph)`` over at least ``--seconds``, after 3 warm-up calls; and the calls."""
        for _ in range(3):
            call(graph)
        sync()
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < args.seconds:
            call(graph)
            sync()
            n += 1
        return 1000 * (time.perf_counter() - t0) / n / frames, n

    module.eval()
    with torch.no_grad():
        # as trained; with static shapes (the same outputs); and on a GPU captured as one CUDA graph
        # (the graph with each step's two branches on one stream, then side by side on two)
        runs = [] if args.compile_only else [("", False), (", static shapes", True)]
        if dev.type == "cuda" and not args.compile_only:
            runs += [(", one CUDA graph, one stream", True), (", one CUDA graph, two streams", True)]
        for label, static in runs:
            module.model.set_static_shapes(static)
            for frames, graph in ((1, one), (args.batch, batch)):  # one frame, and a batch of frames per call
                try:
                    call = (module.captured_predictor(graph, parallel_branches="two" in label) if "graph" in label
                            else module.predict_frames)
                    ms, n = per_frame(call, graph, frames)
                except RuntimeError as exc:  # a capture the device refuses: say so, time the rest
                    print(f"inference{label}: failed (batch of {frames}): {str(exc).splitlines()[0]}")
                    continue
                print(f"inference{label}: {ms:.1f} ms per frame (batch of {frames}, coarse + detail features + "
                      f"detail; {n} runs)")
        module.model.set_static_shapes(False)
    module.train()
    opt = torch.optim.Adam(module.parameters(), lr=1e-3)
    module.log = lambda *a, **k: None  # noqa: E731 (no trainer attached)
    module.log_dict = lambda *a, **k: None  # noqa: E731
    for _ in range(0 if args.compile_only else 2):
        opt.zero_grad()
        module.training_step(batch, 0).backward()
        opt.step()
    sync()
    n, t0 = 0, time.perf_counter()
    while not args.compile_only and time.perf_counter() - t0 < args.seconds:
        opt.zero_grad()
        module.training_step(batch, 0).backward()
        opt.step()
        sync()
        n += 1
    if n:
        dt = (time.perf_counter() - t0) / n
        print(f"training: {1000 * dt:.0f} ms per step of {args.batch} frames = {args.batch / dt:.1f} frames/s ({n} steps)",
              flush=True)
    if args.compile:  # last: a compile can take minutes, and a time limit then loses only this row
        module.eval()
        with torch.no_grad():
            compiled_one_frame(module, one, per_frame, dev)
            if args.max_autotune:
                compiled_one_frame(module, one, per_frame, dev, mode="max-autotune")
            if args.tf32:
                compiled_one_frame(module, one, per_frame, dev, tf32=True)
