"""The motion generator's training config, read by drape's strict loader (``datagen.config``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field


@dataclass(frozen=True, kw_only=True)
class MotionConfig:
    """How paper 001's motion generator is built and trained (§4.2's values are the defaults).

    Attributes:
        seed: seeds torch, numpy, Python and the DataLoader workers.
        epochs: most epochs (paper: 5000).
        batch_size: segments per optimiser step over all processes (paper: 20).
        lr: Adam's learning rate (paper: 1e-4).
        lr_factor, lr_patience: the rate is multiplied by ``lr_factor`` when the validation loss has
            not fallen for ``lr_patience`` epochs (paper: 0.1 after 30).
        lr_patience_steps: ... and for at least this many optimiser steps (2,700: paper 001's 30 epochs
            of ~1,800 segments in batches of 20), so that a small store's short epochs do not cut the
            rate on the validation loss's noise (``training.loop.plateau_patience``); None: epochs only.
        early_stop_patience: stop when the validation loss has not fallen for this many epochs.
        workers: DataLoader worker processes per training process.
        precision: Lightning's precision; ``auto``: bf16 mixed on a GPU, 32-bit on the CPU.
        d_model, heads, layers, feedforward, dropout: the Transformers (paper: 256, 4, N = 8, 1024, 0.1).
        label_hidden: the label encoder's hidden width (paper: 128).
        kl_weight: λ_KL (paper: 1e-5).
        vertex_loss: include L_V^B (the body-vertex loss); false is Table 8's ablation.
        vertex_stride: the vertex loss and vertex metrics use every ``vertex_stride``-th body vertex
            (1: all 13,348, the paper's; larger only to make CPU tests fast).
        max_minutes: stop after this much wall time (None: no limit).
        cuda_graph: on one CUDA device, capture the training step's forward and backward pass (some
            15,000 operations, each a launch from Python) once as a CUDA graph and replay it for
            every full batch (:class:`~training.motion.module.MotionModule`); the optimiser step
            and the gradient clipping stay eager. Off, or on a CPU, with DDP or with "16-mixed"
            precision (its loss scaling happens in the backward), every operation is launched from
            Python.
    """

    seed: int = 0
    epochs: int = field(default=5000, metadata={"min": 1, "max": 1000000})
    batch_size: int = field(default=20, metadata={"min": 1, "max": 4096})
    lr: float = field(default=1e-4, metadata={"min": 1e-7, "max": 1.0})
    lr_factor: float = field(default=0.1, metadata={"min": 0.01, "max": 1.0})
    lr_patience: int = field(default=30, metadata={"min": 1, "max": 100000})
    lr_patience_steps: int | None = field(default=2700, metadata={"min": 1, "max": 10000000})
    early_stop_patience: int = field(default=200, metadata={"min": 1, "max": 100000})
    workers: int = field(default=0, metadata={"min": 0, "max": 64})
    precision: str = field(default="auto", metadata={"choices": ("auto", "32", "bf16-mixed", "16-mixed")})
    d_model: int = field(default=256, metadata={"min": 8, "max": 4096})
    heads: int = field(default=4, metadata={"min": 1, "max": 64})
    layers: int = field(default=8, metadata={"min": 1, "max": 64})
    feedforward: int = field(default=1024, metadata={"min": 8, "max": 16384})
    dropout: float = field(default=0.1, metadata={"min": 0.0, "max": 0.9})
    label_hidden: int = field(default=128, metadata={"min": 1, "max": 4096})
    kl_weight: float = field(default=1e-5, metadata={"min": 0.0, "max": 1e3})
    vertex_loss: bool = True
    vertex_stride: int = field(default=1, metadata={"min": 1, "max": 10000})
    max_minutes: float | None = field(default=None, metadata={"min": 0.1})
    cuda_graph: bool = True

    def __post_init__(self):
        if self.d_model % self.heads:
            from datagen.errors import ConfigError

            raise ConfigError(f"d_model ({self.d_model}) must be a multiple of heads ({self.heads})")

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)
