"""Render a contact sheet of the procedural motions on the default body (docs/motions.png).

    python -m benchmarks motion-sheet --out docs/motions.png --seed 1

One row per label: frames spread over 3 s, each seen from the front and from the side (the
body faces +Z; the red line is the ground).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from datagen.body.cache import default_body
from datagen.motion.labels import LABELS
from datagen.motion.library import make_motion


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="docs/motions.png")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--frames-shown", type=int, default=4)
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    body = default_body()
    ground = float(body.v_template[:, 1].min())
    n = args.frames_shown
    fig, axes = plt.subplots(len(LABELS), 2 * n, figsize=(2 * n * 0.9, len(LABELS) * 1.25))
    for r, label in enumerate(LABELS):
        motion = make_motion(label, seed=args.seed, frames=91)
        idx = np.linspace(0, 90, n).astype(int)
        verts, _ = body.pose(np.zeros((n, body.shape_dim)), motion.poses[idx].reshape(n, -1), motion.trans[idx])
        for k in range(n):
            v = verts[k][::2]
            for j, (a, depth) in enumerate(((0, 2), (2, 0))):
                ax = axes[r, 2 * k + j]
                centre = motion.trans[idx[k], a]
                ax.scatter(v[:, a] - centre, v[:, 1], s=0.02, c=v[:, depth], cmap="viridis", rasterized=True)
                ax.axhline(ground, color="r", lw=0.4)
                ax.set_xlim(-0.9, 0.9)
                ax.set_ylim(ground - 0.05, ground + 2.0)
                ax.set_aspect("equal")
                ax.axis("off")
        axes[r, 0].text(-0.9, ground + 1.9, label, fontsize=6)
    plt.subplots_adjust(wspace=0, hspace=0.02, left=0.01, right=0.99, top=0.995, bottom=0.005)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    plt.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
