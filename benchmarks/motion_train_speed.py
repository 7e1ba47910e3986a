"""Where paper 001's motion generator spends a training step: the data loader alone, one optimiser
step alone (forward, backward, Adam; batch 20 in memory), and the two together, on one device.

    python -m benchmarks motion-train-speed STORE [--device cuda] [--steps 60] [--workers 2]
        [--modes eager,compile,graph]

Prints segments/s of each, so that the training's own rate (``train_summary.json``) can be told
apart: loader-bound, step-bound or neither (Lightning's own overhead). The optimiser step is timed
per mode: ``eager`` (every operation launched from Python, as the training runs today),
``compile`` (the loss through ``torch.compile(mode="reduce-overhead")``, fused Adam) and ``graph``
(the forward and backward pass replayed as the module's CUDA graph, ``MotionConfig.cuda_graph``; then clipping and
Adam eagerly, as training runs it; CUDA only)."""
from __future__ import annotations

import argparse
import time

import torch


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("store")
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--batch", type=int, default=20)
    ap.add_argument("--modes", default="eager", help="comma-separated: eager, compile, graph")
    args = ap.parse_args(argv)
    from datagen.store import open_store
    from training.motion.config import MotionConfig
    from training.motion.data import label_names, labelled_segments
    from training.motion.module import MotionModule

    dev = torch.device(args.device)
    store = open_store(args.store)
    ds = labelled_segments(store, "train")
    loader = torch.utils.data.DataLoader(ds, batch_size=args.batch, shuffle=True, num_workers=args.workers, drop_last=True,
                                         persistent_workers=args.workers > 0,
                                         multiprocessing_context="spawn" if args.workers else None)

    def batches(n):
        k = 0
        while True:
            for b in loader:
                yield b
                k += 1
                if k >= n:
                    return

    for _ in batches(3):
        pass
    t = time.perf_counter()
    n = sum(len(b["label"]) for b in batches(args.steps))
    print(f"loader alone ({args.workers} workers): {n / (time.perf_counter() - t):8.1f} segments/s")
    cfg = MotionConfig()
    fixed = {k: v.to(dev) for k, v in next(iter(loader)).items()}
    amp = dict(device_type=dev.type, dtype=torch.bfloat16, enabled=dev.type == "cuda")
    for mode in args.modes.split(","):
        torch.manual_seed(0)
        module = MotionModule(cfg, len(label_names(store)), store.body_model(), store.betas()).to(dev)
        cuda = dev.type == "cuda"
        opt = torch.optim.Adam(module.parameters(), lr=1e-4, fused=cuda and mode == "compile")
        losses = torch.compile(module.losses, mode="reduce-overhead") if mode == "compile" else module.losses

        def step(batch):
            with torch.autocast(**amp):
                loss = losses(batch)["loss"]
            opt.zero_grad(set_to_none=True)
            loss.backward()
            torch.nn.utils.clip_grad_norm_(module.parameters(), 1.0)
            opt.step()
            return loss

        if mode == "graph":
            if not cuda:
                print("graph: CUDA only")
                continue
            opt = torch.optim.Adam(module.parameters(), lr=1e-4)

            def run(batch):  # as training runs it: the module's graph (forward and backward), then clipping and Adam eagerly
                with torch.autocast(**amp):
                    loss = module._graph_losses(batch)["loss"]
                torch.nn.utils.clip_grad_norm_(module.parameters(), 1.0)
                opt.step()
                opt.zero_grad(set_to_none=False)
                return loss

            t = time.perf_counter()
            run(fixed)
            torch.cuda.synchronize()
            print(f"graph: captured in {time.perf_counter() - t:.1f} s")
        else:
            run = step
            t = time.perf_counter()
            for _ in range(3):
                run(fixed)
            if cuda:
                torch.cuda.synchronize()
            print(f"{mode}: first steps (compilation included) {time.perf_counter() - t:.1f} s")
        for _ in range(5):
            run(fixed)
        if cuda:
            torch.cuda.synchronize()
        t = time.perf_counter()
        for _ in range(args.steps):
            loss = run(fixed)
        first = float(loss.detach())
        dt = time.perf_counter() - t
        print(f"{mode}: optimiser step (batch {args.batch} in memory, vertex loss on): "
              f"{args.steps * args.batch / dt:8.1f} segments/s, {1e3 * dt / args.steps:.1f} ms/step, loss {first:.5f}")
        t = time.perf_counter()
        n = 0
        for b in batches(args.steps):
            loss = run({k: v.to(dev, non_blocking=True) for k, v in b.items()})
            n += len(b["label"])
        float(loss.detach())
        print(f"{mode}: loader + step: {n / (time.perf_counter() - t):8.1f} segments/s")
