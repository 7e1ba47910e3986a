"""Paper 000's dataset: one recorded frame of a store as a torch_geometric graph.

Everything comes through the store's reader (:func:`datagen.store.open_store`), which decodes the
stored positions and derives the features (:mod:`datagen.features`). A dataset pickles
without open handles, so DataLoader workers (``spawn`` or ``fork``) reopen the store lazily.

:class:`FrameDataset`: a torch_geometric ``Data`` per (sample, frame): the body graph's node
features ``x_coarse`` = [n^{b'}, p^{b'}, α₁] (R^7, §4.3), the garment graph's ``x_detail`` =
[n, p, x] (R^30, §4.4, from the ground-truth coarse mesh as the paper trains; both assembled by
:mod:`training.gnn.features`, the garment's by the function inference calls), the garment's
edges (both directions) and triangles (``face`` [3, F], torch_geometric's convention, so
batches offset them), the targets ``y_coarse`` = coarse − anchor (eq. 5) and ``y_detail`` =
detail − coarse (eq. 9), the attributes (α, β, θ) of the parser, and what evaluation needs
(anchor, coarse, detail, trans, ids). torch_geometric's ``DataLoader`` batches garments of
different vertex counts. :class:`GNNDataModule` serves its train and validation splits.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from datagen.errors import InputError
from datagen.geometry.topology import unique_edges
from datagen.store import DatasetStore, open_store
from training.datamodule import EpochSampler, StoreDataModule
from training.gnn.config import GNNConfig
from training.gnn.features import body_node_features, node_features

FRAME_NAMES = ["detail", "coarse", "anchor", "anchor_normal", "anchor_skin", "skin", "pose", "trans", "joints"]
"""What a paper-000 frame reads from the store (stored and derived); the garment graph's features
are computed from the coarse mesh by :func:`training.gnn.features.node_features`, as inference does."""


def _edges(faces: np.ndarray) -> torch.Tensor:
    """Undirected mesh edges as a [2, 2E] index (both directions), from triangles."""
    e = unique_edges(faces)
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
        face = faces.T.contiguous()
        return Data(
            x_coarse=body_node_features(f["anchor_normal"], f["anchor_skin"], alpha),
            x_detail=node_features(f["coarse"], face, f["skin"], f["joints"][None]),
            edge_index=edges, num_nodes=V,
            y_coarse=f["coarse"] - f["anchor"], y_detail=f["detail"] - f["coarse"],
            anchor=f["anchor"], coarse=f["coarse"], detail=f["detail"], skin=f["skin"],
            attributes=torch.cat([alpha, betas, f["pose"].reshape(-1)])[None],
            trans=f["trans"][None], joints=f["joints"][None], face=face, garment=torch.tensor([g]), sample=torch.tensor([i]),
            frame=torch.tensor([t]), body=torch.tensor([int(self.store.index["body"][i])]))


class GNNDataModule(StoreDataModule):
    """Paper 000's frames of a store for ``drape train gnn``: the train split (``max_train_frames``
    drawn once with the run's seed; an epoch of ``epoch_frames`` drawn afresh each epoch) and the
    validation frames (``max_val_frames`` drawn with seed 0 whatever the seed, so that runs'
    validation errors compare)."""

    config: GNNConfig

    def build(self) -> None:
        c = self.config
        self.train_set = FrameDataset(self.store, "train", max_frames=c.max_train_frames, seed=c.seed)
        self.val_set = FrameDataset(self.store, "val", max_frames=c.max_val_frames, seed=0)

    @property
    def attribute_features(self) -> int:
        """Length of the parser's input (α, β, θ) of this store."""
        self.setup()
        return int(self.train_set[0].attributes.shape[1])

    def train_dataloader(self):
        c, ds = self.config, self.train_set
        sampler = None
        if c.epoch_frames is not None and c.epoch_frames < len(ds):
            # a fresh draw of epoch_frames frames each epoch, a function of (seed, epoch)
            sampler = EpochSampler(len(ds), c.seed, num_samples=c.epoch_frames)
        return self.loader(ds, shuffle=True, sampler=sampler, graphs=True)

    def val_dataloader(self):
        return self.loader(self.val_set, graphs=True)

    def summary(self) -> dict:
        return {"train_frames": len(self.train_set), "val_frames": len(self.val_set)}
