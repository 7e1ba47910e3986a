"""Table 4's trivial generators on paper-motion's split and on a candidate split with a held-out
region of the style parameters, from the procedural motions alone (no store, no simulation: the
generator's data are the motions).

For each split the train and test motions are made by the motion library (240 frames at 30 fps, cut
into four 60-frame windows, as the store's motion tables are), a recogniser is trained on the train
windows (``training.motion.recognition``, 100 epochs), and Table 4's protocol scores two generators:
*copy* (a random training window of the label) and *still* (the label's mean training pose, held).
On paper-motion's split (test motions: seed 9 of the training generators) copying a training window
is the ideal generator by construction. The candidate (``held``) takes its test motions from the
middle of the two style parameters every label has (tempo in [0.95, 1.10], amplitude in [0.88,
1.02]) and its training motions from outside [0.92, 1.13] and [0.85, 1.05] on both (the first such
seeds of each label, 4 per label as before). Printed first for each split: how far each test window
lies from the nearest training window of its label.

    python -m benchmarks motion-split-copy [--repetitions 20] [--recognizer-epochs 100]
"""

from __future__ import annotations

import argparse

import numpy as np
import torch

LABELS17 = ("walk", "run", "jump", "squat", "lunge", "kick", "wave", "raise_arms", "arm_circles", "torso_twist",
            "bend_forward", "side_bend", "sit_stand", "turn_in_place", "box", "dance_sway", "dance_disco")
OLD = {"train": [f"{m}:{s}" for s in range(4) for m in LABELS17],
       "test": [f"{m}:9" for m in ("walk", "run", "jump", "squat", "kick", "wave", "arm_circles", "box", "dance_sway",
                                   "dance_disco")]}


# the first seeds of each label outside the margin (training) and inside the held-out region (test),
# from datagen.motion.library.style_params
HELD_TRAIN_SEEDS = {
    "walk": (2, 5, 8, 10), "run": (0, 1, 7, 22), "jump": (1, 6, 10, 11), "squat": (1, 2, 8, 11),
    "lunge": (0, 4, 20, 24), "kick": (2, 7, 11, 15), "wave": (0, 6, 7, 11), "raise_arms": (0, 1, 3, 4),
    "arm_circles": (1, 3, 7, 8), "torso_twist": (2, 5, 12, 16), "bend_forward": (4, 10, 11, 12),
    "side_bend": (4, 16, 17, 23), "sit_stand": (0, 2, 9, 21), "turn_in_place": (1, 2, 6, 9), "box": (0, 1, 9, 13),
    "dance_sway": (0, 1, 6, 7), "dance_disco": (0, 5, 7, 8)}
HELD_OUT_SEEDS = {  # (val, test)
    "walk": (4, 9), "run": (3, 4), "jump": (0, 9), "squat": (17, 21), "kick": (0, 1), "wave": (1, 8),
    "arm_circles": (2, 23), "box": (11, 18), "dance_sway": (5, 18), "dance_disco": (6, 19)}

HELD = {"train": [f"{m}:{seeds[k]}" for k in range(4) for m, seeds in HELD_TRAIN_SEEDS.items()],
        "test": [f"{m}:{HELD_OUT_SEEDS[m][1]}" for m in ("walk", "run", "jump", "squat", "kick", "wave", "arm_circles",
                                                          "box", "dance_sway", "dance_disco")]}


def windows(motions: list[str], frames: int = 240, length: int = 60) -> tuple[torch.Tensor, torch.Tensor]:
    """Frame features [N, length, 147] and labels [N] of every motion's fixed windows."""
    from datagen.geometry.rotations import axis_angle_to_matrix
    from datagen.generate.config import parse_motion
    from datagen.motion.labels import LABELS
    from datagen.motion.library import make_motion
    from training.paper001.frames import frames_to_features

    xs, ys = [], []
    for spec in motions:
        label, seed = parse_motion(spec)
        m = make_motion(label, seed=seed, frames=frames, fps=30.0)
        pose = torch.as_tensor(np.asarray(m.poses), dtype=torch.float32).reshape(frames, -1, 3)
        trans = torch.as_tensor(np.asarray(m.trans), dtype=torch.float32)
        for t0 in range(0, frames - length + 1, length):
            rot = axis_angle_to_matrix(pose[t0:t0 + length])[None]
            xs.append(frames_to_features(rot, trans[None, t0:t0 + length])[0])
            ys.append(LABELS.index(label))
    return torch.stack(xs), torch.tensor(ys)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repetitions", type=int, default=20)
    ap.add_argument("--recognizer-epochs", type=int, default=100)
    ap.add_argument("--nearest-only", action="store_true", help="only the nearest training window's distance")
    args = ap.parse_args(argv)

    from datagen.motion.labels import LABELS
    from training.motion.recognition import generation_metrics, train_recognizer
    from training.paper001.baselines import copy_generator, nearest_training_segments, still_generator
    from training.paper001.frames import features_to_frames

    print(f"{'split':6s} {'generator':10s} {'FID':>14s} {'accuracy %':>14s} {'diversity':>14s} {'speed x1e-3':>14s}"
          f"   (recogniser on the real test windows)")
    for name, split in (("preset", OLD), ("held", HELD)):
        x_train, y_train = windows(split["train"])
        x_test, y_test = windows(split["test"])
        near = nearest_training_segments(x_test, y_test, x_train, y_train)
        rot, rot_near = features_to_frames(x_test)[0], features_to_frames(x_train[near])[0]
        angle = torch.arccos(((rot_near.transpose(-1, -2) @ rot).diagonal(dim1=-2, dim2=-1).sum(-1) - 1)
                             .div(2).clamp(-1, 1))  # the joints' rotation angle between the two [N, T, 24]
        print(f"{name:6s} nearest training window of the label: joint rotation error {angle.mean():.4f} rad mean, "
              f"{angle.pow(2).mean().sqrt():.4f} rad RMS per joint; feature RMSE per coordinate "
              f"{(x_test - x_train[near]).pow(2).mean().sqrt():.4f}")
        if args.nearest_only:
            continue
        torch.manual_seed(0)
        recognizer = train_recognizer(x_train, y_train, len(LABELS), epochs=args.recognizer_epochs, seed=0)
        rot, _ = features_to_frames(x_train)
        mean = torch.zeros(len(LABELS), 24, 3, 3)
        for k in y_train.unique().tolist():  # the label's mean rotation, projected back onto rotations
            u, _, vt = torch.linalg.svd(rot[y_train == k].mean((0, 1)))
            mean[k] = u @ vt
        rows = {}
        for gen_name, gen in (("copy", copy_generator(x_train, y_train)), ("still", still_generator(mean, 60))):
            r = generation_metrics(recognizer, gen, x_test, y_test, x_train, repetitions=args.repetitions)
            rows[gen_name], real = r["generated"], r
        rows = {"real": real["real"], **rows}
        for gen_name, m in rows.items():
            cells = [f"{s * m[k]['mean']:8.3f}±{s * m[k]['interval']:<5.3f}"
                     for k, s in (("fid", 1), ("accuracy", 100), ("diversity", 1), ("speed", 1000))]
            print(f"{name:6s} {gen_name:10s} " + " ".join(f"{c:>14s}" for c in cells)
                  + f"   ({100 * real['recognizer_test_accuracy']:.1f} %, {len(y_train)} train / {len(y_test)} test)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
