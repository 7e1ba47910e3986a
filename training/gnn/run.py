"""Train, evaluate and predict with paper 000's GNN from a dataset store (what the CLI calls).

- :func:`train_gnn`: a run directory from a store and a :class:`~training.gnn.config.GNNConfig`.
- :func:`evaluate_gnn`: the tables of paper 000 §5.2 on a split: mean per-vertex error (mm) of
  the coarse and the detailed prediction per body and over the split, and again per category of
  :func:`seen_in_training` (Table 1: garments and poses seen in training on unseen bodies; Table 2:
  unseen garments, bodies and poses), beside two trivial baselines (Δ = 0, the body surface at the
  anchor; and the skinned garment), the RMSE of the prediction and of both baselines per vertex and
  per coordinate (named), and the share of predicted vertices inside the posed body.
- :func:`predict_sample`: every frame of one sample predicted, with the per-vertex error.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable

import numpy as np
import torch

from datagen.errors import InputError
from datagen.lifetime import die_with_parent_worker
from datagen.store import open_store
from training.gnn.config import GNNConfig
from training.gnn.data import FrameDataset
from training.checkpoint import load_module as load_checkpoint
from training.checkpoint import run_store
from training.loop import (apply_threads, fit, prepare_run, resolve_device, run_checkpoint, seed_everything,
                           store_identity, write_summary)

KIND = "gnn"


def train_gnn(data: str | Path, out: str | Path, config: GNNConfig, *, device: str = "auto", resume: bool = False,
              force: bool = False) -> dict[str, Any]:
    """Train paper 000's GNN on ``data``'s train split, choosing the checkpoint on its val split."""
    from training.gnn.data import GNNDataModule
    from training.gnn.module import GNNModule

    resolve_device(device)
    apply_threads(config)
    store = open_store(data)
    frames = GNNDataModule(store, config)
    frames.setup()
    meta = {"kind": KIND, "config": config.as_dict(), "store": store_identity(store)}
    out = prepare_run(out, resume=resume, force=force, meta=meta)
    seed_everything(config.seed)
    module = GNNModule.from_data(config, frames)
    t0 = time.perf_counter()
    result = fit(module, frames, config, out, device=device, resume=resume)
    result |= {"seconds": time.perf_counter() - t0, **frames.summary(),
               "parameters": sum(p.numel() for p in module.parameters())}
    write_summary(out, result)
    return result


def load_module(run: str | Path, *, checkpoint: str = "best"):
    """The trained module of a run directory (``best`` or ``last`` checkpoint), on the CPU, in eval mode."""
    from training.gnn.module import GNNModule

    meta, path = run_checkpoint(run, KIND, "paper 000's GNN", checkpoint=checkpoint)
    module = load_checkpoint(GNNModule, path, "paper 000's GNN")
    return module, meta, path


@torch.no_grad()
def evaluate_gnn(run: str | Path, *, data: str | Path | None = None, split: str = "test",
                 max_frames: int | None = None, device: str = "auto", collisions: bool = True,
                 progress: Callable[[int, int], None] | None = None) -> dict[str, Any]:
    """Paper 000's tables on ``split`` (see the module docstring); JSON-able. ``progress(done,
    total)`` is called with the frames evaluated after every batch."""
    from torch_geometric.loader import DataLoader
    from torch_geometric.utils import scatter

    module, meta, ckpt = load_module(run)
    store = run_store(meta, run, data)
    accelerator = resolve_device(device)
    dev = torch.device("cuda" if accelerator == "gpu" else "cpu")
    module.to(dev)
    ds = FrameDataset(store, split, max_frames=max_frames, seed=0)
    names = store.names["body_names"]
    seen = seen_in_training(store)
    # per table row (a body, or "all") the running mean of every measure over its frames (torchmetrics'
    # MeanMetric, in float64) and its frame count
    rows: dict[str, FrameMeans] = {}
    by_seen: dict[str, dict[str, FrameMeans]] = {}
    inside_total, vertex_total = 0, 0
    # the posed body, refitted frame by frame on the evaluation's device (before, each frame built a
    # new mesh on the CPU and queried it on one thread: 17 ms for 991 points on this 2-core CPU, per
    # frame, while a GPU predicts a frame in a few ms)
    body_mesh = None
    if collisions:
        from datagen.geometry.queries import MovingMesh

        warp_device = f"cuda:{torch.cuda.current_device()}" if dev.type == "cuda" else "cpu"
        body_mesh = MovingMesh(store.body_model()["faces"], device=warp_device)
    t_model, n_frames = 0.0, 0
    # the run's DataLoader workers read and derive the frames (spawned: each opens the store itself)
    workers = int(meta["config"].get("workers", 0))
    loader = DataLoader(ds, batch_size=4, shuffle=False, num_workers=workers,
                        multiprocessing_context="spawn" if workers else None,
                        worker_init_fn=die_with_parent_worker if workers else None)
    for batch in loader:
        batch = batch.to(dev)
        t = time.perf_counter()
        coarse, detail = module.predict_frames(batch)
        if dev.type == "cuda":
            torch.cuda.synchronize()
        t_model += time.perf_counter() - t
        on_truth = module.detail_on_truth(batch)
        n_frames += batch.num_graphs
        skinned = batch.skin + batch.trans[batch.batch]
        errs = {"coarse": (coarse - batch.coarse).norm(dim=-1), "detail": (detail - batch.detail).norm(dim=-1),
                "coarse_to_detail": (coarse - batch.detail).norm(dim=-1),
                "zero_coarse": (batch.anchor - batch.coarse).norm(dim=-1),
                "zero_detail": (batch.anchor - batch.detail).norm(dim=-1),
                "skinned_detail": (skinned - batch.detail).norm(dim=-1),
                # the detail step alone, as trained: from the coarse target, with and without W_detail
                "truth_coarse_to_detail": (batch.coarse - batch.detail).norm(dim=-1)}
        if on_truth is not None:
            errs["truth_detail"] = (on_truth - batch.detail).norm(dim=-1)
        errs = {k: 1000 * v for k, v in errs.items()}  # mm
        for k in RMSE_OF:  # squared distances (mm²), whose frame means give the RMSEs (summary)
            errs[f"sq_{k}"] = errs[k] ** 2
        # every frame's mean of every measure at once, one copy to the host per batch (not one per
        # frame and measure, each a wait for the device)
        per_frame = scatter(torch.stack(list(errs.values()), 1), batch.batch, dim=0,
                            dim_size=batch.num_graphs, reduce="mean").cpu().double()
        groups: dict[tuple[str | None, str], list[int]] = {}  # the batch's frames of each table row
        for k in range(batch.num_graphs):
            body, category = names[int(batch.body[k])], seen[int(batch.sample[k])]
            for row in ((None, body), (None, "all"), (category, body), (category, "all")):
                groups.setdefault(row, []).append(k)
        for (category, key), ks in groups.items():  # one update per row and batch
            table = rows if category is None else by_seen.setdefault(category, {})
            table.setdefault(key, FrameMeans(list(errs))).update(per_frame[ks])
        if collisions:  # one read (and derivation) of the posed bodies per sample, one copy of the batch
            graph = batch.batch.cpu().numpy()
            points = detail.cpu().numpy()
            samples, frames = batch.sample.cpu().numpy(), batch.frame.cpu().numpy()
            for i in np.unique(samples):
                ks = np.flatnonzero(samples == i)
                bodies = store.frames(int(i), frames[ks].tolist(), names=["body_vertices"])["body_vertices"]
                for k, body_v in zip(ks, bodies, strict=True):
                    inside_total += body_mesh.pose(body_v).inside_count(points[graph == k])
                    vertex_total += int((graph == k).sum())
        if progress is not None:
            progress(n_frames, len(ds))

    def summary(r: FrameMeans) -> dict[str, float]:
        out = r.compute()
        for k in RMSE_OF:  # the root of the mean squared distance: per vertex (Euclidean) and per coordinate
            sq = out.pop(f"sq_{k}")
            out[f"{k}_rmse_per_vertex"], out[f"{k}_rmse_per_coordinate"] = sq ** 0.5, (sq / 3) ** 0.5
        return out

    table = {key: summary(r) for key, r in rows.items()}
    out = {"run": str(run), "checkpoint": str(ckpt), "split": split, "store": str(store.path), "frames": len(ds),
           "ablation": meta["config"]["ablation"], "table": table,
           "by_seen": {c: {key: summary(r) for key, r in t.items()} for c, t in sorted(by_seen.items())},
           "inside_body_share": inside_total / vertex_total if vertex_total else None,
           "model_ms_per_frame": 1000 * t_model / max(n_frames, 1), "device": dev.type,
           "parameters": sum(p.numel() for p in module.parameters()),
           "model_mb": sum(p.numel() * p.element_size() for p in module.parameters()) / 1e6}
    return out


RMSE_OF = ("detail", "zero_detail", "skinned_detail")
"""The measures whose RMSE the tables add to their means (the prediction and the two baselines against
the simulated garment): per vertex (the root of the frame's mean squared Euclidean distance, mean
over frames) and per coordinate (that over √3)."""


class FrameMeans:
    """One row of the evaluation's tables: the mean of each measure over its frames (torchmetrics'
    ``MeanMetric`` each, in float64, which also syncs across processes) and the frames counted."""

    def __init__(self, measures: list[str]):
        from torchmetrics.aggregation import MeanMetric

        self.measures = measures
        self.means = [MeanMetric().set_dtype(torch.float64) for _ in measures]
        self.frames = 0

    def update(self, values: torch.Tensor) -> None:
        """Add frames' means [frames, measures]."""
        for j, mean in enumerate(self.means):
            mean.update(values[:, j])
        self.frames += len(values)

    def compute(self) -> dict[str, float]:
        return {m: float(mean.compute()) for m, mean in zip(self.measures, self.means, strict=True)} | {
            "frames": self.frames}


SEEN = {(True, True): "garments and poses seen in training", (False, False): "unseen garments and poses",
        (True, False): "seen garments, unseen poses", (False, True): "unseen garments, seen poses"}
"""The categories of :func:`seen_in_training`: Table 1 of paper 000 is the first (on unseen bodies),
Table 2 the second."""


def seen_in_training(store) -> dict[int, str]:
    """Sample -> its :data:`SEEN` category: whether its garment (type and seed; the instance on
    another body counts as seen) and its motion (label and seed) are among the train split's."""
    idx = store.index
    garment = [store.garment(g) for g in range(store.garment_count)]
    gtype, gseed = (np.array([int(a[k]) for a in garment]) for k in ("type", "seed"))
    motions = store.motions()
    mkey = list(zip(motions["label"].tolist(), motions["seed"].tolist(), strict=True))
    train = store.split("train")
    garments = {(gtype[g], gseed[g]) for g in idx["garment"][train]}
    poses = {mkey[m] for m in idx["motion"][train]}
    return {int(i): SEEN[((gtype[g], gseed[g]) in garments, mkey[m] in poses)]
            for i, (g, m) in enumerate(zip(idx["garment"], idx["motion"], strict=True))}


def format_evaluation(e: dict[str, Any]) -> str:
    """Tables 1 and 2 of paper 000 as drape measures them."""
    lines = [f"{e['split']} split of {e['store']}: {e['frames']} frames, model {e['ablation']} "
             f"({e['parameters']:,} parameters, {e['model_mb']:.1f} MB), {e['model_ms_per_frame']:.1f} ms per frame "
             f"on {e['device']}",
             "",
             "mean per-vertex error (mm): coarse = the coarse prediction against the coarse target, coarse→detail",
             "and detail = the coarse and the detailed prediction against the simulated garment; baselines: the",
             "body surface at the anchor (Δ = 0) against the coarse and the simulated garment, and the skinned garment;",
             "the detail step alone, as it is trained: the coarse target against the simulated garment without",
             "(target→detail) and with W_detail on the coarse target's features (on target)"]

    def block(title: str, table: dict) -> None:
        lines.extend(["", f"{title:<36}coarse coarse→detail  detail | Δ=0 coarse  Δ=0 detail  skinned | "
                          "target→detail  on target"])
        for key, r in table.items():
            on_target = f"{r['truth_detail']:>11.2f}" if "truth_detail" in r else f"{'-':>11}"
            lines.append(f"  {key:<32}{r['coarse']:>8.2f}{r['coarse_to_detail']:>14.2f}{r['detail']:>8.2f} | "
                         f"{r['zero_coarse']:>10.2f}{r['zero_detail']:>12.2f}{r['skinned_detail']:>9.2f} | "
                         f"{r['truth_coarse_to_detail']:>13.2f}{on_target}   ({r['frames']} frames)")

    block("per body, every frame", e["table"])
    for category, table in e.get("by_seen", {}).items():
        block(category, table)
    rmse_rows = [(key, r) for key, r in e["table"].items() if "detail_rmse_per_vertex" in r]
    if rmse_rows:
        lines.extend(["", "RMSE (mm), per vertex (Euclidean) / per coordinate (√3 smaller), against the simulated garment:",
                      f"  {'':<32}{'detail':>16}{'Δ=0 detail':>16}{'skinned':>16}"])
        for key, r in rmse_rows:
            lines.append(f"  {key:<32}" + "".join(f"{r[k + '_rmse_per_vertex']:>8.2f} /{r[k + '_rmse_per_coordinate']:>6.2f}"
                                                  for k in RMSE_OF))
    if e.get("inside_body_share") is not None:
        lines.append(f"\npredicted detail vertices inside the posed body: {100 * e['inside_body_share']:.2f} %")
    return "\n".join(lines)


@torch.no_grad()
def predict_sample(run: str | Path, data: str | Path, sample: int) -> dict[str, np.ndarray]:
    """Every frame of ``sample`` predicted: ``coarse``, ``detail`` [T, V, 3] (m), ``error`` [T, V] (m)
    against the simulated garment, with the ground truth ``truth`` and the ``garment`` index."""
    from torch_geometric.data import Batch

    module, meta, _ = load_module(run)
    store = open_store(data)
    if not 0 <= sample < store.sample_count:
        raise InputError(f"--sample {sample} is not in 0 .. {store.sample_count - 1} ({store.path})")
    ds = FrameDataset(store, store.names["split_names"][int(store.scalars(sample)["split"])])
    rows = [k for k, (i, _) in enumerate(ds.rows) if i == sample]
    if not rows:
        raise InputError(f"sample {sample} of {store.path} has no recorded frames (it failed in simulation); "
                         "choose a sample that passed (`drape info` lists the failures)")
    coarse, detail, truth = [], [], []
    for k in rows:
        b = Batch.from_data_list([ds[k]])
        c, d = module.predict_frames(b)
        coarse.append(c.numpy())
        detail.append(d.numpy())
        truth.append(b.detail.numpy())
    coarse, detail, truth = np.stack(coarse), np.stack(detail), np.stack(truth)
    return {"coarse": coarse, "detail": detail, "truth": truth, "error": np.linalg.norm(detail - truth, axis=-1),
            "garment": int(store.scalars(sample)["garment"])}
