"""Training throughput of drape's three models: samples per second over N optimiser steps after a
warm-up, through Lightning's loop, on one small store, from one seed.

Each model is built as its ``drape train`` builds it (the kind's record in ``training.kinds``: its
config with the given batch size, its data module's training loader, its LightningModule) and
trained for ``--warmup + --steps`` optimiser steps by a Lightning ``Trainer`` (gradient clipping at
1.0 as ``training.loop.fit`` has it; no validation, no checkpoints, no logger); the clock runs from the first step after the warm-up to the last. A sample
is a frame (paper 000's GNN) or a segment (paper 001's models; frames = segments x segment length).

    python -m benchmarks train-throughput --data STORE --garment-data STORE2 [--steps 20] [--warmup 3]

STORE is a store with fit attributes and labelled motions (the GNN and the motion generator), e.g.
the training tests' micro store (``tests/training/conftest.py``'s MICRO_TRAIN); STORE2 one with a
skirt in its train and val splits (the garment regressor), e.g. ``tests/training/test_garment.py``'s
MOTION_LIKE. Prints one table.
"""

from __future__ import annotations

import argparse
import time
import warnings

GARMENT = "skirt"
"""The garment regressor's template type (``--garment-data`` must hold it in its train and val splits)."""


def _build(kind: str, store, batch_size: int, seed: int, threads: int):
    """(LightningModule, training DataLoader, frames per sample) of ``kind`` on ``store``'s train split,
    as ``drape train KIND`` builds them: the registry's config, data module and module."""
    import torch

    from training.kinds import get_kind

    torch.set_num_threads(threads)
    record = get_kind(kind)
    fields = {"batch_size": batch_size, "seed": seed, "workers": 0, "precision": "32"}
    if kind == "garment":
        fields |= {"garment": GARMENT, "max_batch_size": batch_size, "batch_growth": 0}
    config = record.config_class()(**fields)
    data = record.part("datamodule")(store, config)
    data.setup("fit")
    module = record.part("module").from_data(config, data)
    frames = 1 if kind == "gnn" else int(store.segment_length)
    return module, data.train_dataloader(), frames


def measure(kind: str, store, *, steps: int, warmup: int, batch_size: int, seed: int, threads: int) -> dict:
    """Samples and seconds of ``steps`` optimiser steps after ``warmup`` of them."""
    import pytorch_lightning as pl

    from training.loop import batch_samples

    pl.seed_everything(seed, workers=True, verbose=False)
    module, loader, frames = _build(kind, store, batch_size, seed, threads)

    class Clock(pl.Callback):
        def __init__(self):
            self.t0 = self.t1 = 0.0
            self.samples = 0

        def on_train_batch_start(self, trainer, pl_module, batch, batch_idx):
            if trainer.global_step == warmup:
                self.t0 = time.perf_counter()

        def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx):
            if trainer.global_step > warmup:
                self.samples += batch_samples(batch)
                self.t1 = time.perf_counter()

    clock = Clock()
    # no plateau schedule: nothing is validated here, and the rate does not change the speed
    configure = module.configure_optimizers
    module.configure_optimizers = lambda: _optimizer(configure())
    trainer = pl.Trainer(max_steps=warmup + steps, max_epochs=-1, accelerator="cpu", devices=1, precision="32",
                         limit_val_batches=0, num_sanity_val_steps=0, logger=False, enable_checkpointing=False,
                         enable_progress_bar=False, enable_model_summary=False, gradient_clip_val=1.0,
                         callbacks=[clock])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        trainer.fit(module, loader)
    seconds = clock.t1 - clock.t0
    return {"kind": kind, "steps": steps, "samples": clock.samples, "frames": clock.samples * frames,
            "seconds": seconds, "samples_per_s": clock.samples / seconds, "frames_per_s": clock.samples * frames / seconds,
            "parameters": sum(p.numel() for p in module.parameters())}


def _optimizer(configured):
    return configured["optimizer"] if isinstance(configured, dict) else configured


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data", required=True, help="a dataset store (fit attributes, labelled motions)")
    p.add_argument("--garment-data", default=None, help="the garment regressor's store (default: --data)")
    p.add_argument("--models", default="gnn,motion,garment", help="comma-separated kinds")
    p.add_argument("--steps", type=int, default=20, help="timed optimiser steps per model")
    p.add_argument("--warmup", type=int, default=3, help="untimed optimiser steps first")
    p.add_argument("--batch-size", type=int, default=4)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=2, help="torch's intra-op threads")
    args = p.parse_args(argv)
    import logging

    import pytorch_lightning  # noqa: F401  (its import sets its logger to INFO: quieted after it)
    import torch

    from datagen.store import open_store

    for name in ("pytorch_lightning", "lightning.pytorch", "lightning_fabric"):
        logging.getLogger(name).setLevel(logging.WARNING)

    stores = {"garment": open_store(args.garment_data or args.data)}
    rows = [measure(k.strip(), stores.get(k.strip()) or open_store(args.data), steps=args.steps, warmup=args.warmup,
                    batch_size=args.batch_size, seed=args.seed, threads=args.threads)
            for k in args.models.split(",") if k.strip()]
    print(f"training throughput on the CPU ({torch.get_num_threads()} threads, torch {torch.__version__}), "
          f"{args.data} (garment: {args.garment_data or args.data}), batch {args.batch_size}, {args.warmup} warm-up + {args.steps} timed steps, seed {args.seed}")
    print(f"{'model':<9}{'parameters':>12}{'samples/s':>11}{'frames/s':>10}{'s/step':>8}")
    for r in rows:
        print(f"{r['kind']:<9}{r['parameters']:>12,}{r['samples_per_s']:>11.2f}{r['frames_per_s']:>10.2f}"
              f"{r['seconds'] / r['steps']:>8.3f}")

