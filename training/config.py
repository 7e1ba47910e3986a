"""Training configuration: one frozen dataclass read by drape's strict loader (``datagen.config``).

A config file (TOML or YAML) has these fields at the top level; ``drape train gnn --config FILE``
reads it, and every run directory keeps the resolved config (``config.json``) it was trained with.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

ABLATIONS = ("full", "no_decomposition", "output_limit", "no_parser", "concat_parser", "single_step", "no_pooling")
"""The variants of paper 000's model (§5.3; ``full`` is the paper's model): see ``training.gnn.model``."""


@dataclass(frozen=True, kw_only=True)
class TrainConfig:
    """How a model is trained.

    Attributes:
        seed: seeds torch, numpy, Python and the DataLoader workers (a run is reproducible from it).
        epochs: most epochs (early stopping may end sooner).
        batch_size: graphs (frames) per optimiser step, over all processes.
        lr: Adam's learning rate (paper 000 gives none; chosen on the validation split).
        lr_factor, lr_patience: the rate is multiplied by ``lr_factor`` when the validation error has
            not fallen for ``lr_patience`` epochs.
        early_stop_patience: stop when the validation error has not fallen for this many epochs.
        workers: DataLoader worker processes per training process (they read and derive features).
        precision: Lightning's precision; ``auto``: bf16 mixed on a GPU, 32-bit on the CPU.
        ablation: the model variant (paper 000 §5.3; ``full`` is the paper's model).
        target_scale: the regression targets (metres) are multiplied by this in the loss (100: cm).
        max_train_frames: frames drawn (seeded, once) from the train split; None: all.
        max_val_frames: frames drawn from the validation split for the per-epoch error (the GNN draws
            them with seed 0 whatever the run's seed, so that runs compare on the same frames).
        epoch_frames: frames an epoch trains on, drawn afresh (seeded) from the train split every
            epoch; None: an epoch is the whole split. On a large store it makes the validation error
            (the curves, early stopping, the plateau schedule, the best checkpoint) come more often
            than once a pass, and a time limit lose at most one short epoch.
        max_minutes: stop training after this much wall time (None: no limit); the last finished
            epoch's checkpoints stay.
    """

    seed: int = 0
    epochs: int = field(default=40, metadata={"min": 1, "max": 100000})
    batch_size: int = field(default=8, metadata={"min": 1, "max": 4096})
    lr: float = field(default=1e-3, metadata={"min": 1e-7, "max": 1.0})
    lr_factor: float = field(default=0.5, metadata={"min": 0.01, "max": 1.0})
    lr_patience: int = field(default=4, metadata={"min": 1, "max": 1000})
    early_stop_patience: int = field(default=10, metadata={"min": 1, "max": 1000})
    workers: int = field(default=2, metadata={"min": 0, "max": 64})
    precision: str = field(default="auto", metadata={"choices": ("auto", "32", "bf16-mixed", "16-mixed")})
    ablation: str = field(default="full", metadata={"choices": ABLATIONS})
    target_scale: float = field(default=100.0, metadata={"min": 1e-3, "max": 1e6})
    max_train_frames: int | None = field(default=None, metadata={"min": 1})
    max_val_frames: int | None = field(default=256, metadata={"min": 1})
    epoch_frames: int | None = field(default=None, metadata={"min": 1})
    max_minutes: float | None = field(default=None, metadata={"min": 0.1})

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)
