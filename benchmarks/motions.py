"""Procedural motions: per-label quality over many seeds, generation speed, and label separability.

    python -m benchmarks motions --seeds 50 --frames 90

Prints, per label (means over seeds unless marked): share of checked frames with limb-torso
interpenetration and how many sequences the filter drops (with its defaults: any interpenetration,
or forearms within 1 cm of the legs), foot skate during contact (cm/s), deepest ground penetration
(mm, max over seeds), share of frames with a joint-limit violation, the smallest forearm-leg
clearance (mm, min over seeds), mean and 99th-percentile jerk (m/s^3), and generation speed
(frames/s, pose generation only).
Then a label classifier (logistic regression on 15-frame windows) trained on some seeds and
tested on unseen seeds, and a seed classifier within each label (trained on the first half of
each sequence, tested on the second) to show that seeds give distinct sequences.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from datagen.body.cache import default_body
from datagen.motion.labels import LABELS
from datagen.motion.library import default_rig, make_motion
from datagen.motion.quality import BodyProbe, measure_motion
from datagen.geometry.rotations import axis_angle_to_matrix_np, matrix_to_rotation_6d_np


def window_features(motion, window: int = 15, hop: int = 5) -> np.ndarray:
    """[N, F] features of windows: mean and std of joint 6D rotations, pelvis height and speed."""
    rot = matrix_to_rotation_6d_np(axis_angle_to_matrix_np(motion.poses[:, 1:])).reshape(motion.frame_count, -1)
    vel = np.linalg.norm(np.diff(motion.trans, axis=0, prepend=motion.trans[:1]), axis=1) * motion.fps
    per_frame = np.concatenate([rot, motion.trans[:, 1:2], vel[:, None]], axis=1)
    out = []
    for s in range(0, motion.frame_count - window + 1, hop):
        w = per_frame[s:s + window]
        out.append(np.concatenate([w.mean(0), w.std(0)]))
    return np.asarray(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--frames", type=int, default=90)
    ap.add_argument("--stride", type=int, default=3, help="check interpenetration every this many frames")
    ap.add_argument("--labels", default=",".join(LABELS))
    args = ap.parse_args(argv)
    labels = args.labels.split(",")
    body = default_body()
    probe = BodyProbe(body)
    default_rig()
    make_motion("walk", 0, 10)  # warm-up
    print(f"{args.seeds} seeds x {args.frames} frames at 30 fps per label; default body "
          f"({body.vertex_count} vertices); interpenetration checked every {args.stride} frames")
    head = (f"{'label':14s} {'interpen.':>9s} {'dropped':>7s} {'skate cm/s':>10s} {'contact':>7s} {'sink mm':>7s} "
            f"{'limit viol.':>11s} {'arm-leg mm':>10s} {'jerk':>7s} {'jerk p99':>8s} {'gen fps':>8s}")
    print(head)
    print("-" * len(head))
    feats, all_motions = {}, {}
    total_frames, total_time = 0, 0.0
    t_start = time.perf_counter()
    for label in labels:
        motions, gen = [], 0.0
        for seed in range(args.seeds):
            t0 = time.perf_counter()
            m = make_motion(label, seed=seed, frames=args.frames)
            gen += time.perf_counter() - t0
            motions.append(m)
        total_frames += args.seeds * args.frames
        total_time += gen
        qs = [measure_motion(m, probe, stride=args.stride) for m in motions]
        all_motions[label] = motions
        feats[label] = [window_features(m) for m in motions]
        mean = lambda k, qs=qs: float(np.mean([getattr(q, k) for q in qs]))
        dropped = sum(q.penetration_share > 0 or q.arm_leg_clearance < 0.01 for q in qs)  # filter_motions' defaults
        print(f"{label:14s} {mean('penetration_share'):9.2%} {dropped:4d}/{len(qs):<2d} {mean('foot_skate') * 100:10.2f} "
              f"{mean('contact_share'):7.2f} {max(q.ground_penetration for q in qs) * 1000:7.1f} "
              f"{mean('limit_violation_share'):11.2%} {min(q.arm_leg_clearance for q in qs) * 1000:10.0f} "
              f"{mean('jerk_mean'):7.0f} {mean('jerk_p99'):8.0f} "
              f"{args.seeds * args.frames / gen:8.0f}", flush=True)
    print(f"generation: {total_frames} frames in {total_time:.2f} s = {total_frames / total_time:.0f} frames/s "
          f"(all labels; quality checks excluded). Whole run {time.perf_counter() - t_start:.0f} s.")

    if len(labels) < 2:
        print("label classifier: skipped (it needs two labels or more)")
        return
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    n_train = max(1, int(args.seeds * 0.7))
    Xtr, ytr, Xte, yte = [], [], [], []
    for li, label in enumerate(labels):
        for seed, f in enumerate(feats[label]):
            (Xtr if seed < n_train else Xte).append(f)
            (ytr if seed < n_train else yte).extend([li] * len(f))
    clf = make_pipeline(StandardScaler(), LogisticRegression(max_iter=3000))
    clf.fit(np.concatenate(Xtr), ytr)
    acc = clf.score(np.concatenate(Xte), yte)
    print(f"label from 15 frames, seeds 0-{n_train - 1} -> unseen seeds {n_train}-{args.seeds - 1}: "
          f"accuracy {acc:.1%} (chance {1 / len(labels):.1%})")
    seed_accs = []
    k = min(10, args.seeds)
    for label in labels:
        Xa, ya, Xb, yb = [], [], [], []
        for seed, f in enumerate(feats[label][:k]):
            h = len(f) // 2
            Xa.append(f[:h]); ya += [seed] * h
            Xb.append(f[h:]); yb += [seed] * (len(f) - h)
        c = make_pipeline(StandardScaler(), LogisticRegression(max_iter=3000)).fit(np.concatenate(Xa), ya)
        seed_accs.append(c.score(np.concatenate(Xb), yb))
    print(f"seed among {k} of one label, first half -> second half of each sequence: mean accuracy "
          f"{np.mean(seed_accs):.1%} (chance {1 / k:.0%}); min {min(seed_accs):.1%} ({labels[int(np.argmin(seed_accs))]})")
