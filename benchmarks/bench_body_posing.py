"""Batched posing speed: drape's numpy and torch LBS against smplx's ``lbs`` on the same arrays.

Bodies: the default body (13,348 vertices) and its 4-to-1 subdivision (53,386 vertices); 60
frames of random poses, CPU, float32. smplx is given the zero pose-blend-shape array its file
loader would create; drape skips B_p when the model has none (exactly the same result).

    python benchmarks/bench_body_posing.py [--frames 60] [--repeats 5] [--threads N]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch


def best_of(fn, repeats):
    fn()  # warm up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=None, help="torch threads (default: torch's choice)")
    args = ap.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)
    from smplx.lbs import lbs as smplx_lbs

    from datagen.body.cache import default_body

    base = default_body()
    rng = np.random.default_rng(0)
    betas = rng.normal(size=(args.frames, 10))
    pose = rng.normal(scale=0.4, size=(args.frames, 72))
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads; {args.frames} frames; best of {args.repeats}")
    print(f"{'vertices':>9} {'drape numpy':>14} {'drape torch':>14} {'smplx lbs':>14} {'smplx/drape torch':>18} {'max |diff| m':>13}")
    for model in (base, base.subdivided()):
        tm = model.torch(dtype=torch.float32)
        b, p = torch.tensor(betas, dtype=torch.float32), torch.tensor(pose, dtype=torch.float32)
        zeros_posedirs = torch.zeros(207, model.vertex_count * 3)
        parents = torch.tensor(model.parents)

        def run_np():
            return model.pose(betas, pose, dtype=np.float32)

        def run_torch():
            with torch.no_grad():
                return tm(b, p)

        def run_smplx():
            with torch.no_grad():
                return smplx_lbs(b, p, tm.v_template, tm.shapedirs, zeros_posedirs, tm.J_regressor, parents, tm.weights)

        t_np, t_t, t_s = (best_of(f, args.repeats) for f in (run_np, run_torch, run_smplx))
        diff = (run_torch()[0] - run_smplx()[0]).abs().max().item()
        ms = lambda t: f"{1000 * t / args.frames:10.2f} ms/f"  # noqa: E731
        print(f"{model.vertex_count:>9} {ms(t_np):>14} {ms(t_t):>14} {ms(t_s):>14} {t_s / t_t:>17.2f}x {diff:>13.2e}")


if __name__ == "__main__":
    main()
