"""The config fields paper 001's two models share: the Transformers and the plateau schedule's steps."""

from __future__ import annotations

from dataclasses import dataclass, field

from training.config import BaseConfig, default


@dataclass(frozen=True, kw_only=True)
class Paper001Config(BaseConfig):
    """:class:`~training.config.BaseConfig` with paper 001's defaults (§4.2: a factor of 0.1 after 30
    epochs, early stopping after 200, no DataLoader workers) and the Transformer's fields.

    Attributes:
        lr_patience_steps: the plateau schedule also waits for at least this many optimiser steps
            (``training.loop.plateau_patience``), so that a small store's short epochs do not cut
            the rate on the validation loss's noise; None: epochs only.
        weight_decay: AdamW's decoupled weight decay (0: Adam without decay). Paper 001 §4.2 "employs
            L2 normalization" against over-fitting in both branches and gives no value; ACTOR, whose
            settings the motion branch follows, trains with ``torch.optim.AdamW`` at PyTorch's
            default decay, 0.01, which both models take (runs from before the field: 0).
        d_model, heads, layers, feedforward, dropout: the Transformers.
    """

    lr_factor: float = default("lr_factor", 0.1)
    lr_patience: int = default("lr_patience", 30)
    early_stop_patience: int = default("early_stop_patience", 200)
    workers: int = default("workers", 0)
    lr_patience_steps: int | None = field(default=None, metadata={"min": 1, "max": 10000000})
    weight_decay: float = field(default=0.01, metadata={"min": 0.0, "max": 1.0})
    d_model: int = field(default=256, metadata={"min": 8, "max": 4096})
    heads: int = field(default=4, metadata={"min": 1, "max": 64})
    layers: int = field(default=8, metadata={"min": 1, "max": 64})
    feedforward: int = field(default=1024, metadata={"min": 8, "max": 16384})
    dropout: float = field(default=0.1, metadata={"min": 0.0, "max": 0.9})

    def __post_init__(self):
        if self.d_model % self.heads:
            from datagen.errors import ConfigError

            raise ConfigError(f"d_model ({self.d_model}) must be a multiple of heads ({self.heads})")
