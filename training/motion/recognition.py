"""Table 4's generation metrics (Action2Motion's protocol, which paper 001 and ACTOR follow) with a
motion-recognition model trained on drape's own data.

- The recogniser: a two-layer GRU (hidden 128) over a segment's frame features (the generator's
  147: 6D rotations and the translation from the first frame), its last state through a 30-wide
  layer (ReLU; the *features*) and a linear classifier. Trained on the store's labelled train
  segments (Adam 1e-3, cross-entropy, a fixed number of epochs, seeded); its accuracy on the real
  test segments is reported with every table.
- FID: the Fréchet distance between the Gaussian fits of the features of generated and of real test
  motions. Accuracy: the recogniser's accuracy on generated motions against the labels they were
  generated for. Diversity: the mean feature distance of ``diversity_pairs`` random pairs of the
  whole generated set. Multimodality: per label, the mean distance of ``multimodality_pairs``
  random pairs of that label's generated motions, averaged over labels.
- Generated sets are drawn ``repetitions`` times (paper 001: 20) with as many motions per label as
  the real test set has; mean and spread (1.96 standard errors: the 95 % interval) are reported,
  and the real test motions' own figures beside them (FID of the real test set against the real
  train set).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import torch
from torch import nn

from training.paper001.frames import FRAME_FEATURES


class Recognizer(nn.Module):
    def __init__(self, labels: int, hidden: int = 128, features: int = 30):
        super().__init__()
        self.gru = nn.GRU(FRAME_FEATURES, hidden, num_layers=2, batch_first=True)
        self.features = nn.Sequential(nn.Linear(hidden, features), nn.ReLU())
        self.classify = nn.Linear(features, labels)

    def embed(self, x: torch.Tensor) -> torch.Tensor:
        """Features [B, 30] of sequences [B, T, 147]."""
        _, h = self.gru(x)
        return self.features(h[-1])

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.classify(self.embed(x))


def train_recognizer(x: torch.Tensor, y: torch.Tensor, labels: int, *, epochs: int = 100, seed: int = 0,
                     batch_size: int = 64) -> Recognizer:
    """A recogniser fitted to sequences ``x`` [N, T, 147] with labels ``y`` [N] (on x's device)."""
    g = torch.Generator().manual_seed(seed)
    torch.manual_seed(seed)
    model = Recognizer(labels).to(x.device)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    for _ in range(epochs):
        order = torch.randperm(len(x), generator=g).to(x.device)
        for k in range(0, len(x), batch_size):
            idx = order[k:k + batch_size]
            loss = nn.functional.cross_entropy(model(x[idx]), y[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
    return model.eval()


def frechet_distance(a: np.ndarray, b: np.ndarray) -> float:
    """FID between feature sets a [N, D] and b [M, D]."""
    from scipy import linalg

    mu1, mu2 = a.mean(0), b.mean(0)
    s1, s2 = np.cov(a, rowvar=False), np.cov(b, rowvar=False)
    s1, s2 = np.atleast_2d(s1), np.atleast_2d(s2)
    with warnings.catch_warnings():  # a singular product (few samples) is handled below
        warnings.simplefilter("ignore", linalg.LinAlgWarning)
        covmean = linalg.sqrtm(s1 @ s2)
        if not np.isfinite(covmean).all():  # offset the diagonals (the usual fix)
            eps = np.eye(len(s1)) * 1e-6
            covmean = linalg.sqrtm((s1 + eps) @ (s2 + eps))
    covmean = covmean.real
    return float(((mu1 - mu2) ** 2).sum() + np.trace(s1) + np.trace(s2) - 2 * np.trace(covmean))


def diversity(features: np.ndarray, pairs: int, rng: np.random.Generator) -> float:
    """Mean distance of ``pairs`` random pairs of ``features`` [N, D]."""
    n = len(features)
    if n < 2:
        return float("nan")
    i, j = rng.integers(0, n, pairs), rng.integers(0, n, pairs)
    return float(np.linalg.norm(features[i] - features[j], axis=1).mean())


def multimodality(features: np.ndarray, labels: np.ndarray, pairs: int, rng: np.random.Generator) -> float:
    """Per label, the mean distance of ``pairs`` random pairs of its features; averaged over labels."""
    out = [diversity(features[labels == lab], pairs, rng) for lab in np.unique(labels) if (labels == lab).sum() >= 2]
    return float(np.mean(out)) if out else float("nan")


def motion_speed(x: torch.Tensor) -> float:
    """Mean frame-to-frame change of the joint-rotation features (the 6D part of [N, T, 147]): how much
    a set of motions moves. Not in paper 001's Table 4; FID and accuracy in the recogniser's feature
    space reward a label's pose even when it is held still, which this shows."""
    rot = x[..., : x.shape[-1] - 3].float()
    return float((rot[:, 1:] - rot[:, :-1]).abs().mean())


def generation_metrics(recognizer: Recognizer, generate, real_test: torch.Tensor, test_labels: torch.Tensor,
                       real_train: torch.Tensor, *, repetitions: int = 20, diversity_pairs: int = 200,
                       multimodality_pairs: int = 20, seed: int = 0) -> dict[str, Any]:
    """Table 4: ``generate(labels [N], generator) -> sequences [N, T, 147]`` drawn ``repetitions``
    times for the real test set's labels; returns mean and 95 % interval of each metric for the
    generated sets and the real test set (with :func:`motion_speed`, how much each set moves)."""
    with torch.no_grad():
        f_test = recognizer.embed(real_test).cpu().numpy()
        f_train = recognizer.embed(real_train).cpu().numpy()
        real_acc = float((recognizer(real_test).argmax(1) == test_labels).float().mean())
    y = test_labels.cpu().numpy()
    rows: dict[str, list[float]] = {"fid": [], "accuracy": [], "diversity": [], "multimodality": [], "speed": []}
    real_rows: dict[str, list[float]] = {"diversity": [], "multimodality": []}
    for r in range(repetitions):
        rng = np.random.default_rng([seed, r])
        g = torch.Generator().manual_seed(seed * 1000 + r)
        with torch.no_grad():
            x = generate(test_labels, g)
            f = recognizer.embed(x).cpu().numpy()
            acc = float((recognizer(x).argmax(1) == test_labels).float().mean())
        rows["fid"].append(frechet_distance(f, f_test))
        rows["accuracy"].append(acc)
        rows["diversity"].append(diversity(f, diversity_pairs, rng))
        rows["multimodality"].append(multimodality(f, y, multimodality_pairs, rng))
        rows["speed"].append(motion_speed(x))
        real_rows["diversity"].append(diversity(f_test, diversity_pairs, rng))
        real_rows["multimodality"].append(multimodality(f_test, y, multimodality_pairs, rng))

    def summary(values: list[float]) -> dict[str, float]:
        v = np.asarray(values, dtype=float)
        spread = 1.96 * v.std(ddof=1) / np.sqrt(len(v)) if len(v) > 1 else 0.0
        return {"mean": float(v.mean()), "interval": float(spread)}

    real = {"fid": {"mean": frechet_distance(f_test, f_train), "interval": 0.0},
            "accuracy": {"mean": real_acc, "interval": 0.0},
            "diversity": summary(real_rows["diversity"]), "multimodality": summary(real_rows["multimodality"]),
            "speed": {"mean": motion_speed(real_test), "interval": 0.0}}
    return {"generated": {k: summary(v) for k, v in rows.items()}, "real": real, "repetitions": repetitions,
            "recognizer_test_accuracy": real_acc, "test_segments": len(y)}
