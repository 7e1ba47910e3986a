"""The training configuration every model kind extends: one frozen, keyword-only dataclass of the
fields the shared loop (``training.loop``) reads, read by drape's strict loader (``datagen.config``,
which checks each field's limits from its metadata).

A model kind's config subclasses :class:`BaseConfig`, adds its own fields and may change a shared
field's default with :func:`default` (its limits stay those declared here). ``drape train KIND
--config FILE`` reads one; every run directory keeps the resolved config (``run.json``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar

C = TypeVar("C", bound="BaseConfig")

PRECISIONS = ("auto", "32", "bf16-mixed", "16-mixed")


@dataclass(frozen=True, kw_only=True)
class BaseConfig:
    """How a model is trained by the shared loop.

    Attributes:
        seed: seeds torch, numpy, Python and the DataLoader workers (a run is reproducible from it).
        epochs: most epochs (early stopping may end sooner).
        batch_size: samples per optimiser step, over all processes.
        lr: Adam's learning rate.
        lr_factor, lr_patience: the rate is multiplied by ``lr_factor`` when the validation error has
            not fallen for ``lr_patience`` epochs.
        early_stop_patience: stop when the validation error has not fallen for this many epochs.
        workers: DataLoader worker processes per training process.
        precision: Lightning's precision; ``auto``: bf16 mixed on a GPU, 32-bit on the CPU.
        max_minutes: stop training after this much wall time (None: no limit); the last finished
            epoch's checkpoints stay.
        threads: torch's CPU threads in the training process (``torch.set_num_threads``; None:
            torch's default, one per core). On a small shared machine set it with ``workers`` so
            that threads plus worker processes do not exceed the cores (the ``configs/*_cpu.yaml``
            files: 2 threads, no workers). An execution setting: a resumed run may change it.
    """

    LEGACY: ClassVar[dict[str, Any]] = {}
    """Values of fields that runs written before the field existed were trained with (used by
    :meth:`from_dict` when a stored config lacks the field)."""

    seed: int = 0
    epochs: int = field(default=40, metadata={"min": 1, "max": 1000000})
    batch_size: int = field(default=8, metadata={"min": 1, "max": 4096})
    lr: float = field(default=1e-3, metadata={"min": 1e-7, "max": 1.0})
    lr_factor: float = field(default=0.5, metadata={"min": 0.01, "max": 1.0})
    lr_patience: int = field(default=4, metadata={"min": 1, "max": 100000})
    early_stop_patience: int = field(default=10, metadata={"min": 1, "max": 100000})
    workers: int = field(default=2, metadata={"min": 0, "max": 64})
    precision: str = field(default="auto", metadata={"choices": PRECISIONS})
    max_minutes: float | None = field(default=None, metadata={"min": 0.1})
    threads: int | None = field(default=None, metadata={"min": 1, "max": 1024})

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls: type[C], data: dict[str, Any]) -> C:
        """The config a run stored (``run.json``, a checkpoint's hyper-parameters): unknown keys are
        refused by the strict loader; a field the stored dict lacks takes :attr:`LEGACY`'s value, else
        its default."""
        from datagen.config import load_config

        names = {f.name for f in dataclasses.fields(cls)}
        return load_config(cls, {**{k: v for k, v in cls.LEGACY.items() if k in names}, **data})


def default(name: str, value: Any, base: type[BaseConfig] = BaseConfig) -> Any:
    """A subclass's new default for ``base``'s field ``name``, keeping its limits (metadata)::

        epochs: int = default("epochs", 5000)
    """
    f = base.__dataclass_fields__[name]
    return field(default=value, metadata=f.metadata)
