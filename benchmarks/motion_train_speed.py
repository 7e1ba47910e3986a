"""Where paper 001's motion generator spends a training step: the data loader alone, one optimiser
step alone (forward, backward, Adam; batch 20 in memory), and the two together, on one device.

    python benchmarks/motion_train_speed.py STORE [--device cuda] [--steps 60] [--workers 2]

Prints segments/s of each, so that the training's own rate (``train_summary.json``) can be told
apart: loader-bound, step-bound or neither (Lightning's own overhead)."""
from __future__ import annotations

import argparse
import time

import torch


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("store")
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--batch", type=int, default=20)
    args = ap.parse_args()
    from datagen.store import open_store
    from training.motion.config import MotionConfig
    from training.motion.module import MotionModule
    from training.motion.run import _segments

    dev = torch.device(args.device)
    store = open_store(args.store)
    ds = _segments(store, "train")
    loader = torch.utils.data.DataLoader(ds, batch_size=args.batch, shuffle=True, num_workers=args.workers,
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
    cfg = MotionConfig().as_dict()
    module = MotionModule(cfg, len(store.attrs["label_names"]), store.body_model(), store.betas()).to(dev)
    opt = torch.optim.Adam(module.parameters(), lr=1e-4)
    fixed = {k: v.to(dev) for k, v in next(iter(loader)).items()}
    amp = dict(device_type=dev.type, dtype=torch.bfloat16, enabled=dev.type == "cuda")

    def step(batch):
        with torch.autocast(**amp):
            loss = module.losses(batch)["loss"]
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        return loss

    for vertex_loss in (True, False):
        module.config["vertex_loss"] = vertex_loss
        for _ in range(5):
            step(fixed)
        if dev.type == "cuda":
            torch.cuda.synchronize()
        t = time.perf_counter()
        for _ in range(args.steps):
            loss = step(fixed)
        float(loss.detach())
        dt = time.perf_counter() - t
        print(f"optimiser step alone (batch {args.batch} in memory, vertex loss {'on' if vertex_loss else 'off'}): "
              f"{args.steps * args.batch / dt:8.1f} segments/s, {1e3 * dt / args.steps:.1f} ms/step")
    module.config["vertex_loss"] = True
    t = time.perf_counter()
    n = 0
    for b in batches(args.steps):
        loss = step({k: v.to(dev, non_blocking=True) for k, v in b.items()})
        n += len(b["label"])
    float(loss.detach())
    print(f"loader + step: {n / (time.perf_counter() - t):8.1f} segments/s")


if __name__ == "__main__":
    main()
