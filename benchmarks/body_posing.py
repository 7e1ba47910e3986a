"""Batched posing speed: drape's numpy and torch LBS against smplx's ``lbs`` on the same arrays.

Bodies: the default body (13,348 vertices) and its 4-to-1 subdivision (53,386 vertices); 60
frames of random poses, CPU, float32. smplx is given the zero pose-blend-shape array its file
loader would create; drape skips B_p when the model has none (exactly the same result).

    python -m benchmarks body-posing [--frames 60] [--repeats 5] [--threads N]
"""

from __future__ import annotations

import argparse

import numpy as np
import torch

from benchmarks.common import Benchmark, best_of, print_table


class BodyPosing(Benchmark):
    description = __doc__

    def add_arguments(self, ap: argparse.ArgumentParser) -> None:
        ap.add_argument("--frames", type=int, default=60)
        ap.add_argument("--repeats", type=int, default=5)
        ap.add_argument("--threads", type=int, default=None, help="torch threads (default: torch's choice)")

    def setup(self, args):
        """The two bodies and the random shapes and poses (numpy and torch)."""
        if args.threads:
            torch.set_num_threads(args.threads)
        from datagen.body.cache import default_body

        base = default_body()
        rng = np.random.default_rng(0)
        betas = rng.normal(size=(args.frames, 10))
        pose = rng.normal(scale=0.4, size=(args.frames, 72))
        return args, (base, base.subdivided()), betas, pose

    def run(self, inputs):
        """Per body: (vertices, numpy s, torch s, smplx s, max |torch - smplx| m), best of ``--repeats``."""
        from smplx.lbs import lbs as smplx_lbs

        args, models, betas, pose = inputs
        rows = []
        for model in models:
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

            t_np, t_t, t_s = (best_of(f, args.repeats, warmup=1) for f in (run_np, run_torch, run_smplx))
            diff = (run_torch()[0] - run_smplx()[0]).abs().max().item()
            rows.append((model.vertex_count, t_np, t_t, t_s, diff))
        return args, rows

    def report(self, result) -> None:
        args, rows = result
        print(f"torch {torch.__version__}, {torch.get_num_threads()} threads; {args.frames} frames; best of {args.repeats}")
        ms = lambda t: f"{1000 * t / args.frames:.2f} ms/f"  # noqa: E731
        print_table(("vertices", "drape numpy", "drape torch", "smplx lbs", "smplx/drape torch", "max |diff| m"),
                    [(v, ms(t_np), ms(t_t), ms(t_s), f"{t_s / t_t:.2f}x", d) for v, t_np, t_t, t_s, d in rows],
                    ("", "", "", "", "", ".2e"))


main = BodyPosing().main
