"""Paper 001's datasets: segments of a store as dicts of tensors.

Everything comes through the store's reader (:func:`datagen.store.open_store`); a dataset pickles
without open handles, so DataLoader workers reopen the store lazily.

- :class:`SegmentDataset`: a dict of tensors per segment of ``segment_length`` frames of a passed
  sample (the garment regressor: poses and the garment's vertices).
- :class:`MotionSegmentDataset`: a dict of tensors per segment of a motion of the split, from the
  store's motion tables, whether that motion's scenes passed or failed (the motion generator:
  poses only).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from datagen.errors import InputError
from datagen.store import DatasetStore, open_store

class SegmentDataset(torch.utils.data.Dataset):
    """Segments of one split (paper 001): ``pose`` [T, 24, 3], ``trans`` [T, 3], ``label`` [T], the
    sample's ``garment``, ``body`` and ``sample`` indices, and any other frame arrays in ``names``
    (e.g. ``detail`` [T, V, 3])."""

    def __init__(self, store: str | Path | DatasetStore, split: str, *, names: Sequence[str] = ("pose", "trans",
                                                                                                 "label")):
        self.store = store if isinstance(store, DatasetStore) else open_store(store)
        self.segments = self.store.split_segments(split)
        if not len(self.segments):
            raise InputError(f"the {split} split of {self.store.path} has no segments of {self.store.segment_length} "
                             "frames")
        self.names = list(names)

    def __len__(self) -> int:
        return len(self.segments)

    def __getitem__(self, k: int) -> dict[str, torch.Tensor]:
        s = self.store.segment(int(self.segments[k]), names=self.names)
        out = {n: torch.from_numpy(np.ascontiguousarray(s[n])) for n in self.names}
        out["garment"] = torch.tensor(int(s["garment"]))
        out["body"] = torch.tensor(int(s["body"]))
        out["sample"] = torch.tensor(int(s["sample"]))
        return out


class MotionSegmentDataset(torch.utils.data.Dataset):
    """Segments of the motions of one split (paper 001's motion generator), from ``motions/pose``
    and ``motions/trans`` (:meth:`DatasetStore.motion_segments`): ``pose`` [T, 24, 3], ``trans``
    [T, 3], ``label`` [T], ``motion``, ``body`` (whose shape the vertex loss poses) and
    ``first_frame``; with ``labelled`` only the motions of a label (>= 0; unlabelled mocap is -1).

    Item ``k`` is the store's fixed window (every ``segment_length`` frames from the first: what
    validation and evaluation read). Item ``(k, u)`` with ``u`` in [0, 1) is a window of the same
    (motion, body) starting anywhere in the motion (``floor(u * (last start + 1))``): the random crop
    that training draws each epoch (:class:`~training.datamodule.CropSampler`), as ACTOR crops its
    sequences, where the fixed windows would show the model the same four cuts of each motion for
    ever."""

    def __init__(self, store: str | Path | DatasetStore, split: str, *, labelled: bool = True):
        self.store = store if isinstance(store, DatasetStore) else open_store(store)
        rows = self.store.motion_segments(split)
        labels = self.store.motion_labels()[rows[:, 0]] if len(rows) else np.zeros(0, np.int64)
        self.rows = rows[labels >= 0] if labelled else rows
        self.labels = (labels[labels >= 0] if labelled else labels).astype(np.int64)
        # the last frame a window may start at: the motion table's recorded frames less one window
        recorded = int(self.store.motions()["pose"].shape[1])
        self.last_start = np.full(len(self.rows), recorded - self.store.segment_length, np.int64)

    def __len__(self) -> int:
        return len(self.rows)

    def __getitem__(self, k) -> dict[str, torch.Tensor]:
        if isinstance(k, tuple):  # a random crop (CropSampler): the row's motion and body, anywhere in it
            k, u = int(k[0]), float(k[1])
            motion, body, _ = (int(v) for v in self.rows[k])
            first = min(int(u * (int(self.last_start[k]) + 1)), int(self.last_start[k]))
        else:
            motion, body, first = (int(v) for v in self.rows[k])
        s = self.store.motion_segment(motion, body, first)
        out = {n: torch.from_numpy(np.ascontiguousarray(s[n])) for n in ("pose", "trans", "label")}
        out["motion"] = torch.tensor(s["motion"])
        out["body"] = torch.tensor(s["body"])
        out["first_frame"] = torch.tensor(s["first_frame"])
        return out
