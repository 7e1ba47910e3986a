"""Paper 001's motion generator at the paper's size (d_model 256, N = 8, 4 heads, feed-forward
1024): parameters, sampling speed (60-frame sequences per second, with and without posing the
body's 13,348 vertices) and a training step's time, on the CPU or a GPU. No store needed: the
body is drape's default body and the weights are untrained (speed does not depend on them).

    python -m benchmarks motion-model [--device cpu|cuda] [--batch 1 8 64] [--repeat 5]
"""

from __future__ import annotations

import argparse
import time

import torch


def main(argv=None) -> int:
    from datagen.body.cache import default_body
    from training.motion.config import MotionConfig
    from training.motion.module import MotionModule
    from training.paper001.frames import features_to_frames

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--batch", type=int, nargs="+", default=[1, 8, 64])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    dev = torch.device(args.device)
    body = default_body()
    arrays = {k: getattr(body, k) for k in ("v_template", "shapedirs", "J_regressor", "weights", "parents")}
    module = MotionModule(MotionConfig(), 17, arrays, torch.zeros(1, body.shape_dim)).to(dev).eval()
    params = sum(p.numel() for p in module.model.parameters())
    print(f"motion generator: {params:,} parameters ({params * 4 / 2**20:.1f} MiB float32), device {dev}, "
          f"torch {torch.__version__}, {torch.get_num_threads()} CPU threads")

    def sync():
        if dev.type == "cuda":
            torch.cuda.synchronize()

    for b in args.batch:
        label = torch.zeros(b, dtype=torch.long, device=dev)
        for pose in (False, True):
            times = []
            for r in range(args.repeat + 1):
                sync()
                t = time.perf_counter()
                x = module.model.sample(label, 60)
                if pose:
                    rot, trans = features_to_frames(x)
                    module.vertices(rot, trans, torch.zeros(b, dtype=torch.long, device=dev))
                sync()
                if r:  # the first is a warm-up
                    times.append(time.perf_counter() - t)
            best = min(times)
            print(f"  sample {b:3d} sequences of 60 frames{' + posed body vertices' if pose else '':24s}: "
                  f"{best * 1000:8.1f} ms, {b / best:8.1f} sequences/s")
    module.train()
    opt = torch.optim.Adam(module.parameters(), lr=1e-4)
    b = 20
    batch = {"pose": 0.3 * torch.randn(b, 60, 24, 3, device=dev), "trans": torch.randn(b, 60, 3, device=dev),
             "label": torch.zeros(b, 60, dtype=torch.long, device=dev), "body": torch.zeros(b, dtype=torch.long, device=dev)}
    times = []
    for r in range(3):
        sync()
        t = time.perf_counter()
        loss = module.losses(batch)["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
        sync()
        if r:
            times.append(time.perf_counter() - t)
    print(f"  training step, batch {b} (the paper's), vertex loss on all {body.v_template.shape[0]:,} vertices: "
          f"{min(times) * 1000:.0f} ms ({b / min(times):.1f} segments/s)")
    return 0
