"""The base of every model kind's ``LightningDataModule``: a store, a config, and the one way drape
makes a DataLoader.

A kind's data module opens its datasets in :meth:`StoreDataModule.setup` (``setup`` may be called
early, e.g. to size the model, and again by Lightning: it builds once), returns loaders from
:meth:`StoreDataModule.loader`, and says what the run directory records (:meth:`run_meta`) and what
the training summary adds (:meth:`summary`).
"""

from __future__ import annotations

from typing import Any

import pytorch_lightning as pl
import torch

from datagen.errors import InputError
from datagen.lifetime import die_with_parent_worker as worker_init
from datagen.store import DatasetStore
from training.config import BaseConfig


class EpochSampler(torch.utils.data.Sampler):
    """``num_samples`` items (default all) of a dataset of ``n``, drawn without replacement in an order
    that is a function of (seed, epoch) alone; Lightning calls :meth:`set_epoch` before every epoch
    (under DDP through its sampler wrapper, which then shares the order out between processes).

    Not a generator that goes on from epoch to epoch (a DataLoader's ``shuffle=True``): a run resumed
    at epoch k must draw epoch k's order, not epoch 0's, to be the run it resumes."""

    def __init__(self, n: int, seed: int, num_samples: int | None = None):
        self.n, self.seed = int(n), int(seed)
        self.num_samples = self.n if num_samples is None else min(int(num_samples), self.n)
        self.epoch = 0

    def set_epoch(self, epoch: int) -> None:
        self.epoch = int(epoch)

    def __iter__(self):
        g = torch.Generator().manual_seed(self.seed * 100003 + self.epoch)
        return iter(torch.randperm(self.n, generator=g)[:self.num_samples].tolist())

    def __len__(self) -> int:
        return self.num_samples


class CropSampler(EpochSampler):
    """:class:`EpochSampler`'s order, each item with where to crop it: yields ``(index, u)`` with
    ``u`` uniform in [0, 1), drawn from the same (seed, epoch) generator after the order (so the
    order is :class:`EpochSampler`'s and a resumed run draws the crops it would have drawn). A
    dataset that takes such a pair maps ``u`` to a window start (paper 001's motion generator:
    :class:`~training.paper001.data.MotionSegmentDataset`, a random 60-frame window of the motion
    each epoch, as ACTOR crops its training sequences)."""

    def __iter__(self):
        g = torch.Generator().manual_seed(self.seed * 100003 + self.epoch)
        order = torch.randperm(self.n, generator=g)[:self.num_samples]
        where = torch.rand(len(order), generator=g, dtype=torch.float64)
        return iter(zip(order.tolist(), where.tolist(), strict=True))


class StoreDataModule(pl.LightningDataModule):
    """Datasets of one store for one config (see the module docstring)."""

    def __init__(self, store: DatasetStore, config: BaseConfig):
        super().__init__()
        self.store, self.config = store, config
        self._ready = False

    def setup(self, stage: str | None = None) -> None:
        if not self._ready:
            self.build()
            self._ready = True

    def build(self) -> None:
        """Open the datasets (once)."""
        raise NotImplementedError

    @property
    def world_size(self) -> int:
        """Training processes (Lightning's strategy: DDP under torchrun); 1 outside a Trainer."""
        trainer = self.trainer
        return int(trainer.world_size) if trainer is not None else 1

    @property
    def rank(self) -> int:
        trainer = self.trainer
        return int(trainer.global_rank) if trainer is not None else 0

    @property
    def on_gpu(self) -> bool:
        trainer = self.trainer
        return trainer is not None and isinstance(trainer.accelerator, pl.accelerators.CUDAAccelerator)

    def per_process(self, batch_size: int) -> int:
        """``batch_size`` (global, over all processes) shared out between the processes."""
        world = self.world_size
        if batch_size % world:
            raise InputError(f"batch_size {batch_size} is the global batch; it must divide by the {world} processes")
        return batch_size // world

    def loader(self, ds, *, shuffle: bool = False, batch_size: int | None = None, sampler=None,
               batch_sampler=None, graphs: bool = False, workers: int | None = None, global_batch: bool = True):
        """A DataLoader of ``ds``: ``batch_size`` (default: the config's, global) per process, shuffled
        in an order that is a function of the config's seed and the epoch (:class:`EpochSampler`,
        unless a ``sampler`` or ``batch_sampler`` is given), the config's workers (spawned: each opens the
        store itself, as tensorstore's threads do not survive a fork), pinned memory on a GPU;
        ``graphs``: torch_geometric's loader (batches graphs of different sizes); ``global_batch``
        False: ``batch_size`` is each process's."""
        if graphs:
            from torch_geometric.loader import DataLoader
        else:
            from torch.utils.data import DataLoader
        workers = self.config.workers if workers is None else workers
        g = torch.Generator()
        g.manual_seed(self.config.seed)
        batch_size = self.config.batch_size if batch_size is None else batch_size
        if shuffle and sampler is None and batch_sampler is None:
            sampler = EpochSampler(len(ds), self.config.seed)
        size = {} if batch_sampler is not None else {
            "batch_size": self.per_process(batch_size) if global_batch else batch_size, "sampler": sampler}
        return DataLoader(ds, **size, batch_sampler=batch_sampler, num_workers=workers, pin_memory=self.on_gpu,
                          persistent_workers=workers > 0, generator=g, worker_init_fn=worker_init if workers > 0 else None,
                          multiprocessing_context="spawn" if workers > 0 else None)

    def run_meta(self) -> dict[str, Any]:
        """What ``run.json`` records beyond the kind, config and store (e.g. the labels, the template)."""
        return {}

    def summary(self) -> dict[str, Any]:
        """What ``train_summary.json`` records about the data (e.g. the frames or segments trained on)."""
        return {}
