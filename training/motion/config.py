"""The motion generator's training config, read by drape's strict loader (``datagen.config``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from training.config import default
from training.paper001.config import Paper001Config


@dataclass(frozen=True, kw_only=True)
class MotionConfig(Paper001Config):
    """How paper 001's motion generator is built and trained (§4.2's values are the defaults; the
    shared fields: :class:`~training.paper001.config.Paper001Config`).

    Attributes:
        epochs: paper: 5000. batch_size: segments per optimiser step over all processes (paper: 20).
        lr: paper: 1e-4.
        lr_patience_steps: 2,700: paper 001's 30 epochs of ~1,800 segments in batches of 20.
        d_model, heads, layers, feedforward, dropout: paper: 256, 4, N = 8, 1024, 0.1.
        label_hidden: the label encoder's hidden width (paper: 128).
        kl_weight: λ_KL (paper: 1e-5), on the KL summed over the batch as ACTOR sums it
            (:mod:`training.motion.module`).
        vertex_loss: include L_V^B (the body-vertex loss); false is Table 8's ablation.
        vertex_stride: the vertex loss and vertex metrics use every ``vertex_stride``-th body vertex
            (1: all 13,348, the paper's; larger only to make CPU tests fast).
        cuda_graph: on one CUDA device, run the training step's forward and backward pass (some
            15,000 operations, each a launch from Python) as a CUDA graph made by
            ``torch.cuda.make_graphed_callables`` for every full batch
            (:class:`~training.motion.module.MotionModule`). Off, or on a CPU, with DDP or with
            "16-mixed" precision, every operation is launched from Python.
    """

    LEGACY = {"lr_patience_steps": None, "weight_decay": 0.0}

    epochs: int = default("epochs", 5000)
    batch_size: int = default("batch_size", 20)
    lr: float = default("lr", 1e-4)
    lr_patience_steps: int | None = default("lr_patience_steps", 2700, Paper001Config)
    label_hidden: int = field(default=128, metadata={"min": 1, "max": 4096})
    kl_weight: float = field(default=1e-5, metadata={"min": 0.0, "max": 1e3})
    vertex_loss: bool = True
    vertex_stride: int = field(default=1, metadata={"min": 1, "max": 10000})
    cuda_graph: bool = True
