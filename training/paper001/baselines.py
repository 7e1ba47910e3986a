"""The trivial baselines every table of paper 001's models is printed beside (``drape evaluate``).

Generation (Table 4's protocol, :func:`training.motion.recognition.generation_metrics`):

- :func:`still_generator`: every motion is its label's mean training pose, held for the whole
  segment at the origin (what a generator that learned each label's pose and none of its motion
  scores);
- :func:`copy_generator`: every motion is a training segment of its label drawn at random (a
  perfect sampler of the training set: on a split whose test motions are other seeds of the
  training generators it is the ideal generator, which no model can beat by construction).

Reconstruction (Table 3) and the garment regressor's tables: :func:`nearest_training_segments`,
for each test segment the training segment of its label (the regressor: of its template) nearest
in the frame features, whose motion (or simulated garment) is the copy (an oracle retrieval: it
looks at the test segment's poses); its error says how far the split lies from the training set.
"""

from __future__ import annotations

from collections.abc import Callable

import torch

from training.paper001.frames import frames_to_features

Generate = Callable[[torch.Tensor, torch.Generator], torch.Tensor]


def still_generator(mean_rotations: torch.Tensor, frames: int) -> Generate:
    """``generate(labels [N], generator) -> [N, frames, 147]``: each label's mean pose (rotation
    matrices ``mean_rotations`` [labels, 24, 3, 3]) held, the translation zero."""

    def generate(lab: torch.Tensor, g: torch.Generator) -> torch.Tensor:
        rot = mean_rotations.to(lab.device)[lab][:, None].expand(-1, frames, -1, -1, -1)
        return frames_to_features(rot, torch.zeros(len(lab), frames, 3, device=lab.device))

    return generate


def copy_generator(x_train: torch.Tensor, y_train: torch.Tensor) -> Generate:
    """``generate(labels [N], generator) -> [N, T, 147]``: for each label a training segment of it
    (features ``x_train`` [M, T, 147], labels ``y_train`` [M]) drawn with ``generator``."""

    def generate(lab: torch.Tensor, g: torch.Generator) -> torch.Tensor:
        out = []
        for k in lab.tolist():
            rows = torch.nonzero(y_train == k).flatten()
            out.append(x_train[rows[int(torch.randint(len(rows), (1,), generator=g))]])
        return torch.stack(out)

    return generate


def nearest_training_segments(x: torch.Tensor, y: torch.Tensor, x_train: torch.Tensor,
                              y_train: torch.Tensor) -> torch.Tensor:
    """For each segment of ``x`` [N, T, 147] (labels ``y`` [N]) the index [N] into ``x_train`` [M, T,
    147] of the training segment of the same label with the least squared feature distance over all
    frames; every label of ``y`` must have a training segment."""
    d = torch.cdist(x.flatten(1).double(), x_train.flatten(1).double())  # [N, M]
    d = d.masked_fill(y[:, None] != y_train[None, :], float("inf"))
    return d.argmin(dim=1)
