"""Contact sheet of sampled motions: per label, a film strip of a generated motion's skeleton beside
a real motion of the same label, and how fast each moves.

    python -m benchmarks sampled-motion-sheet SAMPLES_DIR --store STORE --out sheet.png [--frames 6]

``SAMPLES_DIR`` holds one folder per label of ``drape sample motion`` output (``<label>/*.npz``, as
``benchmarks/paper_motion_gpu_run.sh PHASE=eval` (at 62ea0bb)` writes); the real motion is the procedural
library's ``<label>:9`` (seed 9: the test split's seed in paper-motion, never trained on). The skeleton
is the store's body (its regular body's β) posed by forward kinematics, seen from the front, frames
drawn evenly over the sequence, left to right. Printed per label: the mean joint speed (m/s) of every
generated sample against the real motion's, the figure that says whether samples move like motions.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def joint_positions(body, poses: np.ndarray, trans: np.ndarray, betas: np.ndarray) -> np.ndarray:
    """Posed joints [T, 24, 3] (m) of axis-angle poses [T, 24, 3] and translations [T, 3] on ``body``
    (a :class:`datagen.body.model.BodyModel`)."""
    T = len(poses)
    _, joints = body.pose(np.broadcast_to(betas, (T, len(betas))), poses.reshape(T, -1), trans)
    return joints


def speed(joints: np.ndarray, fps: float) -> float:
    """Mean joint speed (m/s) over a sequence's frames, the root's travel removed."""
    local = joints - joints[:, :1]
    return float(np.linalg.norm(np.diff(local, axis=0), axis=-1).mean() * fps)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("samples", type=Path)
    ap.add_argument("--store", required=True, help="a store whose body poses the skeletons")
    ap.add_argument("--out", type=Path, required=True, help="the sheet (.png)")
    ap.add_argument("--frames", type=int, default=6, help="frames per strip")
    args = ap.parse_args(argv)

    from datagen.body.model import BodyModel
    from datagen.body.render import VIEWS, pyplot, view_rotation
    from datagen.motion.library import make_motion
    from datagen.motion.motion import Motion
    from datagen.store import open_store

    store = open_store(args.store)
    arrays = store.body_model()
    body = BodyModel(**{k: arrays[k] for k in ("v_template", "shapedirs", "J_regressor", "weights", "parents",
                                               "faces")}, posedirs=None)
    betas = np.asarray(store.betas()[0], dtype=np.float64)
    parents = [int(p) for p in body.parents]
    labels = sorted(p.name for p in args.samples.iterdir() if p.is_dir() and any(p.glob("*.npz")))
    if not labels:
        print(f"{args.samples} has no <label>/*.npz folders", file=sys.stderr)
        return 1
    order = {name: k for k, name in enumerate(store.attrs.get("label_names") or labels)}
    labels.sort(key=lambda n: order.get(n, len(order)))
    rot = view_rotation(VIEWS["front"])
    plt = pyplot()
    fig, axes = plt.subplots(len(labels), 2, figsize=(2 * 0.55 * args.frames * 1.6, 1.25 * len(labels)), squeeze=False)
    print(f"{'label':14s} {'generated m/s (each sample)':>34s} {'real m/s':>9s} {'ratio':>6s}")
    for row, label in enumerate(labels):
        files = sorted((args.samples / label).glob("*.npz"))
        gen = [Motion.load_npz(f) for f in files]
        T = gen[0].frame_count
        real = make_motion(label, 9, frames=T, fps=gen[0].fps)
        speeds = [speed(joint_positions(body, m.poses, m.trans, betas), m.fps) for m in gen]
        real_speed = speed(joint_positions(body, real.poses, real.trans - real.trans[:1], betas), real.fps)
        print(f"{label:14s} {' '.join(f'{s:6.3f}' for s in speeds):>34s} {real_speed:9.3f} "
              f"{np.mean(speeds) / real_speed:6.2f}")
        for col, (name, m, v) in enumerate((("generated", gen[0], speeds[0]), ("real (seed 9)", real, real_speed))):
            ax = axes[row, col]
            j = joint_positions(body, m.poses, m.trans - m.trans[:1], betas) @ rot.T
            picks = np.linspace(0, T - 1, args.frames).round().astype(int)
            for k, t in enumerate(picks):
                p = j[t] - j[0, 0] * np.array([1.0, 0.0, 0.0]) + np.array([0.8 * k, 0.0, 0.0])
                colour = plt.cm.viridis(k / max(1, args.frames - 1))
                for c in range(1, len(parents)):
                    ax.plot(*p[[c, parents[c]], :2].T, color=colour, lw=1.2)
            ax.set_aspect("equal")
            ax.axis("off")
            ax.set_title(f"{label}, {name}: {v:.2f} m/s", fontsize=7)
    fig.tight_layout()
    fig.savefig(args.out, dpi=90)
    plt.close(fig)
    print(f"wrote {args.out}")
    return 0
