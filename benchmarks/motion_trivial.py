"""Table 4 for two trivial generators, the baselines beside paper 001's generation figures.

    python -m benchmarks motion-trivial STORE [--split test] [--repetitions 20]

No model is trained: with `drape evaluate`'s protocol (the same GRU recogniser, trained with seed 0 on
the train split's labelled segments; sets as large as the split, drawn ``--repetitions`` times) it
scores
- **still**: every motion is its label's mean training pose, held for the whole segment (what a
  generator scores that has learned each label's pose and none of its motion);
- **copy**: every motion is a training segment of its label, drawn at random (what a generator scores
  that memorised the training set).
Beside them the real motions of the split. The recogniser is retrained here, so its features are not
bitwise those of a GPU evaluation: compare with the real row printed in the same run.
"""

from __future__ import annotations

import argparse

import torch


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("store")
    ap.add_argument("--split", default="test")
    ap.add_argument("--repetitions", type=int, default=20)
    ap.add_argument("--recognizer-epochs", type=int, default=100)
    args = ap.parse_args(argv)

    from datagen.geometry.rotations import axis_angle_to_matrix
    from datagen.store import open_store
    from training.motion.data import label_names, labelled_segments
    from training.motion.recognition import generation_metrics, train_recognizer
    from training.motion.run import _mean_poses, _split_tensors  # private: training has no public name for these
    from training.paper001.frames import frames_to_features

    store = open_store(args.store)
    labels = len(label_names(store))
    x_train, y_train = _split_tensors(store, "train", "cpu")
    x_test, y_test = _split_tensors(store, args.split, "cpu")
    T = x_test.shape[1]
    torch.manual_seed(0)
    recognizer = train_recognizer(x_train, y_train, labels, epochs=args.recognizer_epochs, seed=0)
    mean = axis_angle_to_matrix(_mean_poses(labelled_segments(store, "train"), labels))  # [labels, 24, 3, 3]

    def still(lab: torch.Tensor, g: torch.Generator) -> torch.Tensor:
        rot = mean[lab][:, None].expand(-1, T, -1, -1, -1)
        return frames_to_features(rot, torch.zeros(len(lab), T, 3))

    def copy(lab: torch.Tensor, g: torch.Generator) -> torch.Tensor:
        out = []
        for k in lab.tolist():
            rows = torch.nonzero(y_train == k).flatten()
            out.append(x_train[rows[int(torch.randint(len(rows), (1,), generator=g))]])
        return torch.stack(out)

    rows = []
    for name, gen in (("still: the label's mean pose", still), ("copy: a training segment", copy)):
        r = generation_metrics(recognizer, gen, x_test, y_test, x_train, repetitions=args.repetitions)
        rows.append((name, r["generated"]))
    rows.insert(0, (f"real {args.split} motions", r["real"]))
    print(f"Table 4's protocol on the {args.split} split of {args.store}: {len(y_test)} segments, {args.repetitions} "
          f"sets; recogniser accuracy on the real motions {100 * r['recognizer_test_accuracy']:.1f} %")
    print(f"{'':32s} {'FID':>16s} {'accuracy %':>16s} {'diversity':>16s} {'multimodality':>16s} {'speed (x1e-3)':>16s}")
    for name, m in rows:
        scale = {"accuracy": 100, "speed": 1000}
        cells = [f"{scale.get(k, 1) * m[k]['mean']:9.3f}±{scale.get(k, 1) * m[k]['interval']:<6.3f}"
                 for k in ("fid", "accuracy", "diversity", "multimodality", "speed")]
        print(f"{name:32s} " + " ".join(f"{c:>16s}" for c in cells))
    return 0
