"""The one training loop of every drape model: PyTorch Lightning's ``Trainer``, configured once.

Why Lightning: it already does what a demanding user expects of a loop, tested by many: checkpoints
that hold the optimiser, scheduler and RNG states and resume mid-run (``ckpt_path="last"``), early
stopping, mixed precision, DDP (it reads ``torchrun``'s environment), progress bars, and TensorBoard
and CSV logs; drape adds only the run directory, the seed and the device checks. (The GPU hosts
ship ``pytorch_lightning``, the package this imports.)

A run directory::

    RUN/
      run.json                 model kind, resolved training config, the store it trained on
      checkpoints/last.ckpt    the full state for resuming, written at an epoch's end at most once a
                               minute (LAST_CHECKPOINT_SECONDS) and at the run's last epoch; best.ckpt
                               the weights of the lowest validation error
      logs/tensorboard/        TensorBoard event files
      logs/csv/attempt-K/metrics.csv   the same scalars as CSV, one file per start (a resumed run
                               appends an attempt; :func:`read_metrics` joins them)
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import time
from pathlib import Path
from typing import Any

import torch

from datagen.errors import InputError
from training.config import TrainConfig

log = logging.getLogger(__name__)

RUN_FILE = "run.json"


LAST_CHECKPOINT_SECONDS = 60.0
"""The resume checkpoint is written at most this often (and always at the run's last epoch): paper
001's models take 12 optimiser steps an epoch on a coarse store, and writing their 150 MB of weights
and Adam moments after each such epoch cost more than the steps (eight runs on one GPU wrote about
1 GB/s). A killed run loses at most this much training."""

RESUME_MAY_CHANGE = ("epochs", "max_minutes")
"""Config keys a resumed run may change: it may be given more epochs or more time."""


def resolve_device(device: str) -> str:
    """Lightning's accelerator for ``device`` (cpu, cuda, auto), refusing a GPU that is not there."""
    if device == "auto":
        return "gpu" if torch.cuda.is_available() else "cpu"
    if device.startswith("cuda"):
        if not torch.cuda.is_available():
            raise InputError(f"--device {device} asked for a GPU but torch sees none here (torch "
                             f"{torch.__version__}); use --device cpu")
        return "gpu"
    if device != "cpu":
        raise InputError(f"--device must be cpu, cuda or auto, not {device!r}")
    return "cpu"


def prepare_run(out: str | Path, *, resume: bool, force: bool, meta: dict[str, Any]) -> Path:
    """Create the run directory (or check the one there for ``resume``); never overwrite silently."""
    out = Path(out)
    run_file = out / RUN_FILE
    meta = json.loads(json.dumps(meta))  # as the file holds it (tuples become lists)
    if int(os.environ.get("RANK", "0")) > 0:  # torchrun: rank 0 checks and creates; the others wait for it
        import time

        for _ in range(600):
            if run_file.is_file() and json.loads(run_file.read_text()) == meta:
                return out
            time.sleep(0.1)
        raise InputError(f"rank {os.environ['RANK']}: rank 0 did not prepare {out} within a minute")
    if resume:
        if not run_file.is_file():
            raise InputError(f"--resume: {out} is not a drape run directory (no {RUN_FILE}); start a run there "
                             "without --resume")
        stored = json.loads(run_file.read_text())

        def fixed(m: dict) -> dict:  # what a resumed run must share; it may run longer (epochs, minutes)
            config = {k: v for k, v in (m.get("config") or {}).items() if k not in RESUME_MAY_CHANGE}
            return {**m, "config": config}

        different = [k for k in ("kind", "config", "store") if fixed(stored).get(k) != fixed(meta).get(k)]
        if different:
            raise InputError(f"--resume: {out} was trained with another {', '.join(different)} "
                             f"(stored {', '.join(f'{k}={stored.get(k)!r:.80}' for k in different)}); resume with "
                             f"the same command (only {' and '.join(RESUME_MAY_CHANGE)} may change), or give a new "
                             "--out")
        if stored != meta:
            (out / RUN_FILE).write_text(json.dumps(meta, indent=2))
        return out
    if out.exists() and any(out.iterdir()):
        if not force:
            raise InputError(f"{out} exists and is not empty; give --resume to continue its run, --force to replace "
                             "it, or a new --out")
        if not (out / RUN_FILE).is_file():
            raise InputError(f"--force would delete {out}, which is not a drape run directory (no {RUN_FILE}); "
                             "remove it yourself or choose another --out")
        shutil.rmtree(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / RUN_FILE).write_text(json.dumps(meta, indent=2))
    return out


def batch_samples(batch) -> int:
    """How many samples a batch holds: graphs of a PyG batch, the leading size of a dict's (or a
    tuple's) first tensor, else its length."""
    graphs = getattr(batch, "num_graphs", None)
    if graphs:
        return int(graphs)
    first = next(iter(batch.values()), None) if isinstance(batch, dict) else (
        batch[0] if isinstance(batch, (list, tuple)) and batch else None)
    if first is not None and hasattr(first, "shape") and len(first.shape):
        return int(first.shape[0])
    return len(batch)


def _throughput_callback():
    """A Lightning callback measuring training samples per second (all processes together) per
    epoch, validation excluded; logged as ``train/samples_per_s``."""
    import pytorch_lightning as pl

    class Throughput(pl.Callback):
        def __init__(self):
            self.rates: list[float] = []
            self._t0 = 0.0
            self._samples = 0

        def on_train_epoch_start(self, trainer, pl_module):
            self._t0, self._samples = time.perf_counter(), 0

        def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx):
            self._samples += batch_samples(batch) * trainer.world_size

        def on_train_epoch_end(self, trainer, pl_module):
            seconds = time.perf_counter() - self._t0
            if self._samples and seconds > 0:
                self.rates.append(self._samples / seconds)
                pl_module.log("train/samples_per_s", self.rates[-1], on_epoch=True, on_step=False)

    return Throughput()


def _latest_checkpoint(dirpath: Path, seconds: float):
    """A ``ModelCheckpoint`` named ``last`` that saves at an epoch's end when ``seconds`` have passed
    since its last save, when the run stops (max epochs, time limit, early stopping), and at the
    first epoch."""
    from pytorch_lightning.callbacks import ModelCheckpoint

    class Latest(ModelCheckpoint):
        def __init__(self):
            # saved at the training epoch's end, after that epoch's validation (and early stopping's
            # decision, which ``should_stop`` carries) rather than at validation's end
            super().__init__(dirpath=dirpath, filename="last", enable_version_counter=False,
                             save_on_train_epoch_end=True)
            self._saved_at: float | None = None

        def on_train_epoch_end(self, trainer, pl_module):
            now = time.monotonic()
            final = trainer.should_stop or trainer.current_epoch + 1 >= (trainer.max_epochs or 0)
            if self._saved_at is not None and now - self._saved_at < seconds and not final:
                return
            self._saved_at = now
            super().on_train_epoch_end(trainer, pl_module)

    return Latest()


def fit(module, train_loader, val_loader, config: TrainConfig, out: Path, *, device: str = "auto",
        resume: bool = False, monitor: str = "val/detail_mm", distributed_sampler: bool = True) -> dict[str, Any]:
    """Train ``module`` with Lightning; returns the best validation value and the checkpoint paths.
    ``distributed_sampler=False`` when the loader's own sampler shares batches out between DDP
    processes (Lightning otherwise puts a ``DistributedSampler`` in)."""
    import pytorch_lightning as pl
    from pytorch_lightning.callbacks import EarlyStopping, LearningRateMonitor, ModelCheckpoint
    from pytorch_lightning.loggers import CSVLogger, TensorBoardLogger

    try:
        import tensorboard  # noqa: F401
    except ImportError:
        try:
            import tensorboardX  # noqa: F401
        except ImportError:
            raise InputError("the TensorBoard logs need tensorboard (or tensorboardX): pip install tensorboard") from None
    accelerator = resolve_device(device)
    world = int(os.environ.get("WORLD_SIZE", "1"))  # torchrun: one process per device
    precision = config.precision if config.precision != "auto" else ("bf16-mixed" if accelerator == "gpu" else "32")
    best = ModelCheckpoint(dirpath=out / "checkpoints", filename="best", monitor=monitor, mode="min",
                           enable_version_counter=False, save_weights_only=True)
    # at an epoch's end, whatever the score, at most once a minute and at the end (Lightning's
    # save_last writes only when a best one is written)
    latest = _latest_checkpoint(out / "checkpoints", LAST_CHECKPOINT_SECONDS)
    throughput = _throughput_callback()
    trainer = pl.Trainer(
        max_epochs=config.epochs, accelerator=accelerator,
        devices=int(os.environ.get("LOCAL_WORLD_SIZE", "1")) if world > 1 else 1,
        num_nodes=max(1, world // int(os.environ.get("LOCAL_WORLD_SIZE", str(world)))) if world > 1 else 1,
        strategy="ddp" if world > 1 else "auto", precision=precision,
        callbacks=[best, latest, EarlyStopping(monitor=monitor, mode="min", patience=config.early_stop_patience),
                   LearningRateMonitor(logging_interval="epoch"), throughput],
        logger=[TensorBoardLogger(out / "logs", name="tensorboard", version=""),
                CSVLogger(out / "logs", name="csv", version=f"attempt-{len(list((out / 'logs' / 'csv').glob('attempt-*')))}")],
        max_time=None if config.max_minutes is None else {"minutes": config.max_minutes},
        log_every_n_steps=1, deterministic=False, enable_model_summary=False, use_distributed_sampler=distributed_sampler,
        gradient_clip_val=1.0)
    trainer.fit(module, train_loader, val_loader,
                ckpt_path=str(out / "checkpoints" / "last.ckpt") if resume and (out / "checkpoints" / "last.ckpt").is_file()
                else None)
    score = best.best_model_score
    result = {"best": None if score is None else float(score), "best_checkpoint": best.best_model_path,
              "last_checkpoint": str(out / "checkpoints" / "last.ckpt"), "epochs": trainer.current_epoch,
              "world_size": trainer.world_size, "train_samples_per_second": throughput.rates}
    last = trainer.callback_metrics.get(monitor)
    if last is not None and not bool(torch.isfinite(last.detach().float()).all()):
        # early stopping ends a run whose monitored value is NaN or infinite: say so, not "trained N epochs"
        epoch = max(trainer.current_epoch - 1, 0)  # the last epoch run, counted from 0 as the logs count
        result["diverged"] = {"epoch": epoch, "metric": monitor, "value": float(last)}
        log.warning("training diverged: %s is %s at epoch %d", monitor, float(last), epoch)
    return result


def plateau_patience(module, epochs: int, steps: int | None) -> int:
    """Epochs without a better validation loss before the plateau schedule cuts the rate: ``epochs``,
    or more where an epoch is short, so that at least ``steps`` optimiser steps pass. Paper 001's
    "30 epochs" are epochs of its ~1,800 segments (108,705 frames): ~2,700 steps of 20; on a store of
    240 segments 30 epochs are 360 steps, and the validation loss's noise then cut the rate to 1e-6
    within 250 epochs (docs/training.md). ``module``'s trainer gives the steps per epoch."""
    trainer = getattr(module, "_trainer", None)
    if not steps or trainer is None:
        return epochs
    try:
        total, max_epochs = trainer.estimated_stepping_batches, trainer.max_epochs
    except Exception:  # no dataloader to count (e.g. a module used outside fit)
        return epochs
    if not max_epochs or max_epochs < 1 or not (0 < total < float("inf")):
        return epochs
    per_epoch = max(1.0, total / max_epochs)
    return max(int(epochs), int(-(-steps // per_epoch)))


def divergence_note(result: dict[str, Any], precision: str) -> str | None:
    """One line for a run whose monitored validation value became NaN or infinite, else None."""
    d = result.get("diverged")
    if not d:
        return None
    return (f"warning: training diverged: {d['metric']} became {d['value']} at epoch {d['epoch']} and early stopping "
            f"ended the run; {result['best_checkpoint'] or 'no checkpoint'} is the best epoch before that. Lower lr in "
            f"the config" + (", or train with precision: \"32\"" if precision != "32" else "") + ", and --force a new run")


def run_meta(run: str | Path) -> dict | None:
    """The run.json of a run directory, or None where ``run`` is not one."""
    path = Path(run) / RUN_FILE
    return json.loads(path.read_text()) if path.is_file() else None


def run_checkpoint(run: str | Path, kind: str, model: str, *, checkpoint: str = "best") -> tuple[dict, Path]:
    """(run.json, checkpoint path) of a run directory of model ``kind``, the ``checkpoint``
    (``best``, else ``last``); one-line errors for a directory that is not a run, a run of another
    model (``model`` names the expected one) and a run without a checkpoint."""
    run = Path(run)
    meta = run_meta(run)
    if meta is None:
        raise InputError(f"{run} is not a drape run directory (no {RUN_FILE}); give the --out of `drape train`")
    if meta.get("kind") != kind:
        raise InputError(f"{run} holds a {meta.get('kind')!r} model, not {model} ({kind!r})")
    path = run / "checkpoints" / f"{checkpoint}.ckpt"
    if not path.is_file():
        path = run / "checkpoints" / "last.ckpt"
    if not path.is_file():
        raise InputError(f"{run} has no checkpoint yet (checkpoints/best.ckpt or last.ckpt); train it first")
    return meta, path


def read_metrics(run: str | Path, key: str) -> dict[int, float]:
    """Epoch -> the last logged value of ``key`` over every attempt of a run (a later attempt wins)."""
    import csv

    out: dict[int, float] = {}
    attempts = sorted((Path(run) / "logs" / "csv").glob("attempt-*"), key=lambda p: int(p.name.split("-")[1]))
    for attempt in attempts:
        f = attempt / "metrics.csv"
        if not f.is_file():
            continue
        with f.open() as fh:
            for row in csv.DictReader(fh):
                if row.get(key) not in (None, ""):
                    out[int(row["epoch"])] = float(row[key])
    return dict(sorted(out.items()))


def seed_everything(seed: int) -> None:
    import pytorch_lightning as pl

    pl.seed_everything(seed, workers=True, verbose=False)
