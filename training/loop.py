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
      train_summary.json       what the run ended with (best value, epochs, throughput, data sizes)
      logs/tensorboard/        TensorBoard event files
      logs/csv/attempt-K/metrics.csv   the same scalars as CSV, one file per start (a resumed run
                               appends an attempt; :func:`read_metrics` joins them)
"""

from __future__ import annotations

import json
import logging
import shutil
import time
from pathlib import Path
from typing import Any

import torch

from datagen.errors import InputError
from training.config import BaseConfig

log = logging.getLogger(__name__)

RUN_FILE = "run.json"


LAST_CHECKPOINT_SECONDS = 60.0
"""The resume checkpoint is written at most this often (and always at the run's last epoch): paper
001's models take 12 optimiser steps an epoch on a coarse store, and writing their 150 MB of weights
and Adam moments after each such epoch cost more than the steps (eight runs on one GPU wrote about
1 GB/s). A killed run loses at most this much training."""

RESUME_MAY_CHANGE = ("epochs", "max_minutes", "threads")
"""Config keys a resumed run may change: it may be given more epochs or more time, or run on
another number of CPU threads."""


def apply_threads(config: BaseConfig) -> None:
    """``torch.set_num_threads(config.threads)`` where the config sets it (None: torch's default)."""
    threads = getattr(config, "threads", None)
    if threads:
        torch.set_num_threads(int(threads))


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


def cluster() -> tuple[int, int, int]:
    """(global rank, world size, processes on this node) as Lightning's cluster environment reads
    them (``TorchElasticEnvironment``: the variables ``torchrun`` sets); (0, 1, 1) for one process."""
    import os

    from lightning_fabric.plugins.environments import TorchElasticEnvironment

    if not TorchElasticEnvironment.detect():
        return 0, 1, 1
    env = TorchElasticEnvironment()
    # Lightning checks that devices x nodes is torchrun's world; torchrun's per-node count is the devices
    return env.global_rank(), env.world_size(), int(os.environ.get("LOCAL_WORLD_SIZE", env.world_size()))


def store_identity(store) -> dict[str, Any]:
    """What ``run.json`` records of the store a run trained on (a resumed run must train on the same)."""
    return {"path": str(Path(store.path).resolve()), "seed": store.seed, "code_version": store.attrs.get("code_version"),
            "schema_version": store.attrs.get("schema_version")}


def prepare_run(out: str | Path, *, resume: bool, force: bool, meta: dict[str, Any]) -> Path:
    """Create the run directory (or check the one there for ``resume``); never overwrite silently.

    Under DDP only rank 0 checks and writes it; the other processes go on to the Trainer, whose
    process group waits for rank 0 (and torchrun ends them all when rank 0 refuses the directory)."""
    out = Path(out)
    run_file = out / RUN_FILE
    meta = json.loads(json.dumps(meta))  # as the file holds it (tuples become lists)
    if cluster()[0] > 0:
        return out
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
                             f"the same command (only {', '.join(RESUME_MAY_CHANGE[:-1])} and {RESUME_MAY_CHANGE[-1]} may change), or give a new "
                             "--out")
        _check_resumable(out)
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


THROUGHPUT_KEY = "train/device/samples_per_sec"
"""The training throughput Lightning's ``ThroughputMonitor`` logs (samples per second of one process
over its last THROUGHPUT_WINDOW batches, validation excluded; ``train/samples_per_sec``: all
processes together, under DDP)."""

THROUGHPUT_WINDOW = 4
"""Batches the logged throughput averages over (paper 001's models take 12 steps an epoch on a
coarse store; the tests' micro runs 4)."""


def _latest_checkpoint(dirpath: Path, seconds: float):
    """A ``ModelCheckpoint`` named ``last`` that saves at an epoch's end when ``seconds`` have passed
    since its last save, when the run stops (max epochs, time limit, early stopping), and at the
    first epoch.

    Not ``ModelCheckpoint(train_time_interval=...)``: that one checks the clock after every batch
    and never at the run's end (its time trigger excludes the epoch trigger), so a finished run's
    last.ckpt could be a minute old and a killed run would resume mid-epoch, where a resumed run
    is no longer the same function of the seed as an uninterrupted one."""
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


def _epoch_seed(seed: int):
    """A callback that seeds torch, numpy and Python at every training epoch's start from (seed,
    epoch): dropout, sampled latents and whatever else draws from the global generators in epoch k
    then draw the same numbers whether the run got there uninterrupted or resumed from epoch k's
    checkpoint (the samplers are seeded per epoch too: :class:`training.datamodule.EpochSampler`)."""
    import pytorch_lightning as pl

    class EpochSeed(pl.Callback):
        def on_train_epoch_start(self, trainer, pl_module):
            pl.seed_everything(seed * 100003 + trainer.current_epoch + trainer.global_rank * 7919, workers=True,
                               verbose=False)

    return EpochSeed()


def _check_resumable(out: Path) -> Path:
    """The resume checkpoint of run directory ``out``, or an InputError saying why there is none."""
    last = out / "checkpoints" / "last.ckpt"
    if not last.is_file():
        raise InputError(f"--resume: {out} has no checkpoints/last.ckpt (the run stopped before its first epoch "
                         f"ended, or the file was removed): there is nothing to resume; start the run again with "
                         f"--force")
    from training.checkpoint import read_checkpoint

    read_checkpoint(last)  # a damaged one is refused before the run directory is touched
    return last


def fit(module, data, config: BaseConfig, out: Path, *, device: str = "auto", resume: bool = False,
        monitor: str = "val/detail_mm", distributed_sampler: bool = True) -> dict[str, Any]:
    """Train ``module`` on ``data`` (a ``LightningDataModule``) with Lightning; returns the best
    validation value, the checkpoint paths and the training throughput per epoch.
    ``distributed_sampler=False`` when the data module's own sampler shares batches out between
    DDP processes (Lightning otherwise puts a ``DistributedSampler`` in)."""
    import pytorch_lightning as pl
    from pytorch_lightning.callbacks import EarlyStopping, LearningRateMonitor, ModelCheckpoint, ThroughputMonitor
    from pytorch_lightning.loggers import CSVLogger, TensorBoardLogger

    try:
        import tensorboard  # noqa: F401
    except ImportError:
        try:
            import tensorboardX  # noqa: F401
        except ImportError:
            raise InputError("the TensorBoard logs need tensorboard (or tensorboardX): pip install tensorboard") from None
    accelerator = resolve_device(device)
    _, world, local = cluster()
    precision = config.precision if config.precision != "auto" else ("bf16-mixed" if accelerator == "gpu" else "32")
    best = ModelCheckpoint(dirpath=out / "checkpoints", filename="best", monitor=monitor, mode="min",
                           enable_version_counter=False, save_weights_only=True)
    # at an epoch's end, whatever the score, at most once a minute and at the end (Lightning's
    # save_last writes only when a best one is written)
    latest = _latest_checkpoint(out / "checkpoints", LAST_CHECKPOINT_SECONDS)
    resume_from = str(_check_resumable(out)) if resume else None
    if resume_from is not None:  # it fits the model this config builds: checked before Lightning restores it
        from training.checkpoint import check_resume

        check_resume(resume_from, module)
    attempt = len(list((out / "logs" / "csv").glob("attempt-*")))
    trainer = pl.Trainer(
        max_epochs=config.epochs, accelerator=accelerator, devices=local, num_nodes=max(1, world // local),
        strategy="ddp" if world > 1 else "auto", precision=precision,
        callbacks=[_epoch_seed(config.seed), best, latest, EarlyStopping(monitor=monitor, mode="min", patience=config.early_stop_patience),
                   LearningRateMonitor(logging_interval="epoch"),
                   ThroughputMonitor(batch_size_fn=batch_samples, window_size=THROUGHPUT_WINDOW)],
        logger=[TensorBoardLogger(out / "logs", name="tensorboard", version=""),
                CSVLogger(out / "logs", name="csv", version=f"attempt-{attempt}")],
        max_time=None if config.max_minutes is None else {"minutes": config.max_minutes},
        log_every_n_steps=1, deterministic=False, enable_model_summary=False, use_distributed_sampler=distributed_sampler,
        gradient_clip_val=1.0)
    import warnings

    with warnings.catch_warnings():  # ThroughputMonitor asks for FLOPs, which drape does not count
        warnings.filterwarnings("ignore", message=".*flops_per_batch.*")
        try:
            trainer.fit(module, datamodule=data, ckpt_path=resume_from)
        except SystemExit:
            # Lightning answers Ctrl-C by a graceful shutdown that ends in sys.exit(1): let the CLI say
            # how to resume, as it does for every other interrupted command
            if trainer.interrupted:
                raise KeyboardInterrupt from None
            raise
        if trainer.interrupted:  # Lightning's graceful shutdown may also return from fit
            raise KeyboardInterrupt
    score = best.best_model_score
    rates = read_metrics(out, THROUGHPUT_KEY, attempts=[attempt]) if trainer.is_global_zero else {}
    result = {"best": None if score is None else float(score), "best_checkpoint": best.best_model_path,
              "last_checkpoint": str(out / "checkpoints" / "last.ckpt"), "epochs": trainer.current_epoch,
              "world_size": trainer.world_size,
              "train_samples_per_second": [r * trainer.world_size for r in rates.values()]}
    last = trainer.callback_metrics.get(monitor)
    if last is not None and not bool(torch.isfinite(last.detach().float()).all()):
        # early stopping ends a run whose monitored value is NaN or infinite: say so, not "trained N epochs"
        epoch = max(trainer.current_epoch - 1, 0)  # the last epoch run, counted from 0 as the logs count
        result["diverged"] = {"epoch": epoch, "metric": monitor, "value": float(last)}
        log.warning("training diverged: %s is %s at epoch %d", monitor, float(last), epoch)
    return result


def plateau_optimizer(module, params, config, monitor: str, *, patience_steps: int | None = None) -> dict:
    """``configure_optimizers``'s answer for every drape model: Adam at ``config.lr`` on ``params``
    (AdamW, decoupled weight decay, where the config has a ``weight_decay`` above 0: paper 001's
    models), and the rate times ``config.lr_factor`` when ``monitor`` has not fallen for
    ``config.lr_patience`` epochs (or more where epochs are short: :func:`plateau_patience` with
    ``patience_steps``)."""
    decay = float(getattr(config, "weight_decay", 0.0) or 0.0)
    opt = (torch.optim.AdamW(params, lr=config.lr, weight_decay=decay) if decay > 0
           else torch.optim.Adam(params, lr=config.lr))
    patience = plateau_patience(module, config.lr_patience, patience_steps)
    sched = torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=config.lr_factor, patience=patience)
    return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "monitor": monitor}}


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


def write_summary(out: Path, result: dict[str, Any]) -> None:
    """``train_summary.json`` of a run (rank 0 writes it)."""
    if cluster()[0] == 0:
        (Path(out) / "train_summary.json").write_text(json.dumps(result, indent=2))


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


def read_metrics(run: str | Path, key: str, *, attempts: list[int] | None = None) -> dict[int, float]:
    """Epoch -> the last logged value of ``key`` over every attempt of a run (a later attempt wins),
    or over the ``attempts`` given (numbers, from 0)."""
    import csv

    out: dict[int, float] = {}
    found = sorted((Path(run) / "logs" / "csv").glob("attempt-*"), key=lambda p: int(p.name.split("-")[1]))
    for attempt in found:
        if attempts is not None and int(attempt.name.split("-")[1]) not in attempts:
            continue
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
