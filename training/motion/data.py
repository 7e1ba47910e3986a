"""The motion generator's data: the labelled segments of a store's motions and their data module."""

from __future__ import annotations

from datagen.errors import InputError
from training.datamodule import CropSampler, StoreDataModule
from training.motion.config import MotionConfig
from training.paper001.data import MotionSegmentDataset


def labelled_segments(store, split: str) -> MotionSegmentDataset:
    """The labelled segments of the split's motions, once per (motion, body), whether their scenes
    passed or failed: paper 001 trains on labelled motions (unlabelled mocap is -1), and a store
    simulates every motion under several garments (``paper-motion``: a skirt, a T-shirt and pants)
    whose segments hold the same poses; counting those would weight the motions whose garments
    passed and lose those whose garments all failed."""
    ds = MotionSegmentDataset(store, split)
    if not len(ds):
        raise InputError(f"the {split} split of {store.path} has no labelled motion segments (label >= 0); the "
                         "motion generator learns labelled motions")
    return ds


def label_names(store) -> list[str]:
    """The store's motion label names (the generator's classes)."""
    names = store.attrs.get("label_names") or []
    if not names:
        raise InputError(f"{store.path} has no label names; the motion generator needs labelled motions")
    return list(names)


class MotionDataModule(StoreDataModule):
    """The labelled segments of the train and val splits (:func:`labelled_segments`) for ``drape
    train motion``, and what the run records: the label names, the frame rate and the segment length.

    Training takes as many windows per epoch as the store has fixed windows, each a random crop of
    its (motion, body) drawn from the run's seed and the epoch (:class:`~training.datamodule.CropSampler`;
    ACTOR's cropping); validation reads the fixed windows, so its loss is comparable between epochs."""

    config: MotionConfig

    def build(self) -> None:
        self.labels = label_names(self.store)
        self.train_set = labelled_segments(self.store, "train")
        self.val_set = labelled_segments(self.store, "val")

    def train_dataloader(self):
        return self.loader(self.train_set, sampler=CropSampler(len(self.train_set), self.config.seed))

    def val_dataloader(self):
        return self.loader(self.val_set)

    def run_meta(self) -> dict:
        self.setup()
        return {"labels": self.labels, "fps": float(self.store.attrs["config"].get("fps", 30.0)),
                "frames": int(self.store.segment_length)}

    def summary(self) -> dict:
        return {"train_segments": len(self.train_set), "val_segments": len(self.val_set)}
