"""A resumed training is the run it resumes (issue 67). For every model kind, a run stopped after one
epoch (the GNN: killed with SIGKILL in the middle of an epoch after its first checkpoint) and resumed
with `--resume` to three, each part a `drape train` process of its own as a user's would be, gives
the same per-epoch losses to the last digit and bitwise the same weights as one run of three epochs.

On one CPU thread (OMP_NUM_THREADS=1 here): with several, torch's CPU kernels add in an order that
varies from run to run, so even two uninterrupted runs differ in the loss's last digit (measured:
13.4368353 against 13.4368362 at the GNN's second epoch); a GPU's non-deterministic kernels the same.
`--resume` with nothing to resume is refused with the reason; Ctrl-C says how to resume."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import torch

from datagen.errors import InputError

pytestmark = pytest.mark.slow

GNN = {"batch_size": 4, "workers": 0, "max_train_frames": 16, "max_val_frames": 6, "lr": 1e-3, "epoch_frames": 12}
MOTION = {"batch_size": 4, "lr": 1e-3, "d_model": 32, "heads": 2, "layers": 2, "feedforward": 64, "label_hidden": 16,
          "vertex_stride": 40, "precision": "32", "workers": 0}
GARMENT = {"batch_size": 2, "batch_growth": 1, "growth_every": 2, "max_batch_size": 4, "lr": 1e-3, "d_model": 32,
           "heads": 2, "feedforward": 64, "bos_hidden": [32, 64], "bos_epochs": 5, "precision": "32", "workers": 0}


ONE_THREAD = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _command(kind: str, store, out, epochs: int, resume: bool) -> list[str]:
    config = {**{"gnn": GNN, "motion": MOTION, "garment": GARMENT}[kind], "epochs": epochs}
    cfg = Path(str(out) + f"-{epochs}.json")
    cfg.write_text(json.dumps(config))
    return [sys.executable, "-m", "datagen.cli", "train", kind, "--data", str(store), "--out", str(out), "--config",
            str(cfg), "--device", "cpu", *(["--resume"] if resume else [])]


def _train(kind: str, store, out, epochs: int, *, resume: bool = False) -> None:
    """``drape train KIND`` in a process of its own (a resumed run is a new process, as a user's is)."""
    r = subprocess.run(_command(kind, store, out, epochs, resume), capture_output=True, text=True, env=ONE_THREAD)
    assert r.returncode == 0, r.stderr[-3000:]


def _losses(run) -> dict[int, float]:
    from training.loop import read_metrics

    return read_metrics(run, "train/loss_epoch")


def _weights(run) -> dict[str, torch.Tensor]:
    return torch.load(run / "checkpoints" / "last.ckpt", map_location="cpu", weights_only=False)["state_dict"]


def _kill_after_first_checkpoint(store, out, epochs: int) -> int:
    """Start a GNN run, SIGKILL it once its first checkpoint is written and its second epoch is under
    way; returns the epochs it finished."""
    proc = subprocess.Popen(_command("gnn", store, out, epochs, False), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=ONE_THREAD)
    t0 = time.time()
    while time.time() - t0 < 600 and proc.poll() is None and not (out / "checkpoints" / "last.ckpt").is_file():
        time.sleep(0.05)
    time.sleep(0.5)  # into the second epoch
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    return len(_losses(out))


@pytest.mark.parametrize("kind", ["gnn", "motion", "garment"])
def test_a_stopped_run_resumed_is_the_uninterrupted_run(kind, train_store, motion_store, tmp_path):
    store = motion_store if kind == "garment" else train_store
    _train(kind, store, tmp_path / "whole", 3)
    if kind == "gnn":
        done = _kill_after_first_checkpoint(store, tmp_path / "part", 3)
        assert 1 <= done < 3, done
    else:
        _train(kind, store, tmp_path / "part", 1)
    _train(kind, store, tmp_path / "part", 3, resume=True)
    whole, resumed = _losses(tmp_path / "whole"), _losses(tmp_path / "part")
    print(f"\n{kind}: uninterrupted {whole}\n{kind}: resumed       {resumed}")
    assert sorted(whole) == [0, 1, 2] and resumed == whole
    a, b = _weights(tmp_path / "whole"), _weights(tmp_path / "part")
    assert a.keys() == b.keys()
    different = [k for k in a if not torch.equal(a[k], b[k])]
    assert not different, f"{len(different)} of {len(a)} tensors differ, e.g. {different[:3]}"


def test_resume_with_nothing_to_resume_is_refused(train_store, tmp_path):
    from training.gnn.config import GNNConfig
    from training.gnn.run import train_gnn

    run = tmp_path / "run"
    train_gnn(train_store, run, GNNConfig(**GNN, epochs=1), device="cpu")
    (run / "checkpoints" / "last.ckpt").unlink()
    with pytest.raises(InputError, match="no checkpoints/last.ckpt.*nothing to resume"):
        train_gnn(train_store, run, GNNConfig(**GNN, epochs=2), device="cpu", resume=True)


def test_ctrl_c_of_drape_train_says_how_to_resume(train_store, tmp_path):
    """Lightning answers SIGINT by a graceful shutdown ending in sys.exit(1); drape turns it into its own
    answer to Ctrl-C: exit 130 and the command that resumes the run."""
    run = tmp_path / "run"
    cfg = tmp_path / "long.json"
    cfg.write_text(json.dumps({**GNN, "epochs": 50}))
    proc = subprocess.Popen([sys.executable, "-m", "datagen.cli", "train", "gnn", "--data", str(train_store), "--out",
                             str(run), "--config", str(cfg), "--device", "cpu"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            # as from a terminal: a test run in the background inherits SIGINT ignored
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    t0 = time.time()
    while time.time() - t0 < 300 and proc.poll() is None and not (run / "checkpoints" / "last.ckpt").is_file():
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-2000:]
    assert "interrupted" in err and "--resume" in err and "Traceback" not in err, err[-2000:]
