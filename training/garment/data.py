"""The garment regressor's data: one template's segments of a store, in batches that grow (§4.2).

The template is the garment instance of the config's type with the most training segments; its
segments in every split are used (a ``paper-motion`` store keeps the same garments in every split:
only the motions differ).
"""

from __future__ import annotations

import numpy as np
import torch

from datagen.errors import InputError
from training.datamodule import StoreDataModule
from training.garment.config import GarmentConfig
from training.paper001.data import SegmentDataset


def template_instance(store, garment: str) -> int:
    """The instance of garment type ``garment`` with the most training segments."""
    names = list(store.attrs.get("garment_type_names") or [])
    if garment not in names:
        raise InputError(f"unknown garment type {garment!r}; this store has: {', '.join(names)}")
    code = names.index(garment)
    types = store.group("garments")["type"]
    counts: dict[int, int] = {}
    for g in segment_garments(store, store.split_segments("train")):
        if int(types[g]) == code:
            counts[int(g)] = counts.get(int(g), 0) + 1
    if not counts:
        raise InputError(f"the train split of {store.path} has no segments of a {garment}")
    return max(counts, key=lambda g: (counts[g], -g))


def segment_garments(store, segments: np.ndarray) -> np.ndarray:
    """The garment instance of each segment, from the store's index (no frames read)."""
    return store.index["garment"][store.index["segments"][np.asarray(segments, dtype=np.int64), 0]]


def template_segments(store, split: str, g: int, names=("pose", "trans", "label", "detail")) -> SegmentDataset:
    ds = SegmentDataset(store, split, names=names)
    ds.segments = ds.segments[segment_garments(store, ds.segments) == g]
    if not len(ds):
        raise InputError(f"the {split} split of {store.path} has no segments of garment instance {g} (the template); "
                         "the regressor learns one template, so every split must hold it (paper-motion keeps the "
                         "same garments in every split: split_disjoint = [motions])")
    return ds


class GrowingBatchSampler(torch.utils.data.Sampler):
    """Shuffled batches of ``start`` items, ``step`` more every ``every`` epochs, at most ``most``
    (§4.2: 10, +5 every 200 epochs, 25); Lightning calls :meth:`set_epoch`. Under DDP (``world``
    processes) these are global batches: every process draws the same order and takes its share
    (``rank::world``) of each, and a last batch too small to give every process an item is dropped."""

    def __init__(self, n: int, start: int, step: int, every: int, most: int, seed: int, *, rank: int = 0,
                 world: int = 1):
        self.n, self.start, self.step, self.every, self.most, self.seed = n, start, step, every, most, seed
        self.rank, self.world = rank, world
        self.epoch = 0

    def set_epoch(self, epoch: int) -> None:
        self.epoch = int(epoch)

    def batch_size(self) -> int:
        return max(1, min(self.most, self.start + self.step * (self.epoch // self.every), self.n))

    def __iter__(self):
        g = torch.Generator().manual_seed(self.seed * 100003 + self.epoch)
        order = torch.randperm(self.n, generator=g).tolist()
        b = self.batch_size()
        for k in range(0, self.n, b):
            batch = order[k:k + b]
            if len(batch) >= self.world:
                yield batch[self.rank::self.world]

    def __len__(self) -> int:
        b = self.batch_size()
        return sum(1 for k in range(0, self.n, b) if min(b, self.n - k) >= self.world)


class GarmentDataModule(StoreDataModule):
    """The template's train and val segments for ``drape train garment`` (:func:`template_instance`
    of ``config.garment``): training batches from :class:`GrowingBatchSampler` (global batches that
    every DDP process shares out itself), validation in batches of ``max_batch_size``."""

    config: GarmentConfig

    def build(self) -> None:
        self.template_index = template_instance(self.store, self.config.garment)
        self.template = self.store.garment(self.template_index)
        self.train_set = template_segments(self.store, "train", self.template_index)
        self.val_set = template_segments(self.store, "val", self.template_index)

    def train_dataloader(self):
        c = self.config
        sampler = GrowingBatchSampler(len(self.train_set), c.batch_size, c.batch_growth, c.growth_every,
                                      c.max_batch_size, c.seed, rank=self.rank, world=self.world_size)
        return self.loader(self.train_set, batch_sampler=sampler)

    def val_dataloader(self):
        return self.loader(self.val_set, batch_size=min(len(self.val_set), self.config.max_batch_size),
                           global_batch=False, workers=0)

    def run_meta(self) -> dict:
        self.setup()
        return {"template": self.template_index}

    def summary(self) -> dict:
        return {"train_segments": len(self.train_set), "val_segments": len(self.val_set),
                "template": self.template_index, "template_vertices": len(self.template["rest_vertices"])}
