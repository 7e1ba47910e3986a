"""Paper 000's GNN training config (``drape train gnn``): the shared fields plus the model's own."""

from __future__ import annotations

from dataclasses import dataclass, field

from training.config import BaseConfig

ABLATIONS = ("full", "no_decomposition", "output_limit", "no_parser", "concat_parser", "single_step", "no_pooling")
"""The variants of paper 000's model (§5.3; ``full`` is the paper's model): see ``training.gnn.model``."""


@dataclass(frozen=True, kw_only=True)
class GNNConfig(BaseConfig):
    """How paper 000's GNN is trained (:class:`~training.config.BaseConfig`'s fields, and these).

    ``batch_size`` counts graphs (frames); ``lr`` is chosen on the validation split (paper 000 gives none).

    Attributes:
        ablation: the model variant (paper 000 §5.3; ``full`` is the paper's model).
        target_scale: the regression targets (metres) are multiplied by this in the loss (100: cm).
        max_train_frames: frames drawn (seeded, once) from the train split; None: all.
        max_val_frames: frames drawn from the validation split for the per-epoch error (drawn with
            seed 0 whatever the run's seed, so that runs compare on the same frames).
        epoch_frames: frames an epoch trains on, drawn afresh (seeded) from the train split every
            epoch; None: an epoch is the whole split. On a large store it makes the validation error
            (the curves, early stopping, the plateau schedule, the best checkpoint) come more often
            than once a pass, and a time limit lose at most one short epoch.
    """

    ablation: str = field(default="full", metadata={"choices": ABLATIONS})
    target_scale: float = field(default=100.0, metadata={"min": 1e-3, "max": 1e6})
    max_train_frames: int | None = field(default=None, metadata={"min": 1})
    max_val_frames: int | None = field(default=256, metadata={"min": 1})
    epoch_frames: int | None = field(default=None, metadata={"min": 1})
