"""torch datasets over a dataset store: one recorded frame (paper 000) or one segment (paper 001).

Everything comes through the store's reader (:func:`datagen.store.open_store`), which decodes the
stored positions and derives the features (:mod:`datagen.geometry.features`); nothing here
recomputes them. A dataset pickles without open handles, so DataLoader workers (``spawn`` or
``fork``) reopen the store lazily.

- :class:`FrameDataset`: a torch_geometric ``Data`` per (sample, frame): the body graph's node
  features ``x_coarse`` = [n^{b'}, p^{b'}, α₁] (R^7, §4.3), the garment graph's ``x_detail`` =
  [n, p, x] (R^30, §4.4, from the ground-truth coarse mesh as the paper trains), the garment's
  edges (both directions) and triangles (``face`` [3, F], torch_geometric's convention, so
  batches offset them), the targets ``y_coarse`` = coarse − anchor (eq. 5) and ``y_detail`` =
  detail − coarse (eq. 9), the attributes (α, β, θ) of the parser, and what evaluation needs
  (anchor, coarse, detail, trans, ids). torch_geometric's ``DataLoader`` batches garments of
  different vertex counts.
- :class:`SegmentDataset`: a dict of tensors per segment of ``segment_length`` frames of a passed
  sample (paper 001's garment regressor: poses and the garment's vertices).
- :class:`MotionSegmentDataset`: a dict of tensors per segment of a motion of the split, from the
  store's motion tables, whether that motion's scenes passed or failed (paper 001's motion
  generator: poses only).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from datagen.errors import InputError
from datagen.store import DatasetStore, open_store

FRAME_NAMES = ["detail", "coarse", "anchor", "anchor_normal", "anchor_skin", "coarse_normal", "skin",
               "joint_distance", "pose", "trans", "joints"]
"""What a paper-000 frame reads from the store (stored and derived)."""


def _edges(faces: np.ndarray) -> torch.Tensor:
    """Undirected mesh edges as a [2, 2E] index (both directions), from triangles."""
    f = np.asarray(faces, dtype=np.int64)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    return torch.from_numpy(np.concatenate([e, e[:, ::-1]]).T.copy())


def frames_of(store: DatasetStore, split: str, *, max_frames: int | None = None, seed: int = 0) -> np.ndarray:
    """(sample, frame) rows of every recorded frame of the split's samples that did not fail;
    ``max_frames`` picks that many evenly at random (seeded), in order."""
    rows = [(int(i), t) for i in store.split(split, include_failed=False) for t in range(store.frame_count(int(i)))]
    if not rows:
        raise InputError(f"the {split} split of {store.path} has no recorded frames (no sample of it passed); "
                         "choose another split or make a store with more samples")
    out = np.asarray(rows, dtype=np.int64)
    if max_frames is not None and len(out) > max_frames:
        pick = np.sort(np.random.default_rng(seed).choice(len(out), size=max_frames, replace=False))
        out = out[pick]
    return out


class FrameDataset(torch.utils.data.Dataset):
    """Paper 000's per-frame graphs of one split (see the module docstring)."""

    def __init__(self, store: str | Path | DatasetStore, split: str, *, max_frames: int | None = None,
                 seed: int = 0):
        self.store = store if isinstance(store, DatasetStore) else open_store(store)
        if not self.store.attrs.get("fit_attribute", False):
            raise InputError(f"store {self.store.path} has no fit attribute α (its config has fit_attribute = "
                             "false), which paper 000's model reads; make a store with fit_attribute = true")
        self.split = split
        self.rows = frames_of(self.store, split, max_frames=max_frames, seed=seed)
        self._static: dict[int, tuple] = {}

    def __len__(self) -> int:
        return len(self.rows)

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_static"] = {}
        return state

    def _garment(self, g: int) -> tuple:
        if g not in self._static:
            garment = self.store.garment(g)
            betas = self.store.betas()[int(garment["body"])]
            self._static[g] = (_edges(garment["faces"]), torch.as_tensor(garment["alpha"], dtype=torch.float32),
                               torch.as_tensor(betas, dtype=torch.float32),
                               torch.as_tensor(garment["faces"], dtype=torch.int64))
        return self._static[g]

    def __getitem__(self, k: int):
        from torch_geometric.data import Data

        i, t = (int(v) for v in self.rows[k])
        g = int(self.store.index["garment"][i])
        edges, alpha, betas, faces = self._garment(g)
        f = {n: torch.from_numpy(np.ascontiguousarray(a[0])) for n, a in
             self.store.frames(i, t, names=FRAME_NAMES).items()}
        V = f["detail"].shape[0]
        return Data(
            x_coarse=torch.cat([f["anchor_normal"], f["anchor_skin"], alpha[:1].expand(V, 1)], dim=1),
            x_detail=torch.cat([f["coarse_normal"], f["skin"], f["joint_distance"]], dim=1),
            edge_index=edges, num_nodes=V,
            y_coarse=f["coarse"] - f["anchor"], y_detail=f["detail"] - f["coarse"],
            anchor=f["anchor"], coarse=f["coarse"], detail=f["detail"], skin=f["skin"],
            attributes=torch.cat([alpha, betas, f["pose"].reshape(-1)])[None],
            trans=f["trans"][None], joints=f["joints"][None], face=faces.T.contiguous(), garment=torch.tensor([g]), sample=torch.tensor([i]),
            frame=torch.tensor([t]), body=torch.tensor([int(self.store.index["body"][i])]))


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
    [T, 3], ``label`` [T], ``motion`` and ``body`` (whose shape the vertex loss poses); with
    ``labelled`` only the motions of a label (>= 0; unlabelled mocap is -1)."""

    def __init__(self, store: str | Path | DatasetStore, split: str, *, labelled: bool = True):
        self.store = store if isinstance(store, DatasetStore) else open_store(store)
        rows = self.store.motion_segments(split)
        labels = self.store.motion_labels()[rows[:, 0]] if len(rows) else np.zeros(0, np.int64)
        self.rows = rows[labels >= 0] if labelled else rows
        self.labels = (labels[labels >= 0] if labelled else labels).astype(np.int64)

    def __len__(self) -> int:
        return len(self.rows)

    def __getitem__(self, k: int) -> dict[str, torch.Tensor]:
        s = self.store.motion_segment(*(int(v) for v in self.rows[k]))
        out = {n: torch.from_numpy(np.ascontiguousarray(s[n])) for n in ("pose", "trans", "label")}
        out["motion"] = torch.tensor(s["motion"])
        out["body"] = torch.tensor(s["body"])
        return out
