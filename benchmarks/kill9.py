"""kill -9 of ``drape generate`` and of ``drape train`` at random moments (issue 65): after each kill, no
process of the command is left (its workers die with it), and running the command again finishes the
job: the resumed store is equal to an uninterrupted one (``compare-stores``), the resumed training
continues from its last checkpoint and ends with the same weights as an uninterrupted run.

    python -m benchmarks kill9 [--trials 10] [--what generate train] [--seed 0] [--dir DIR]

Each command runs in a session of its own, so that every process it started can be found by its
session id after the kill (an orphan keeps the session). CPU only; one BLAS thread per process
(``OMP_NUM_THREADS=1``), as the bitwise comparison of the weights needs (tests/training/test_resume.py).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tests.generate.test_generate import MICRO
from tests.training.conftest import MICRO_TRAIN

ENV = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "CUDA_VISIBLE_DEVICES": ""}
GNN = {"batch_size": 4, "workers": 1, "max_train_frames": 16, "max_val_frames": 6, "lr": 1e-3, "epoch_frames": 12}
"""A small GNN run with one DataLoader worker (a process that must die with the trainer)."""


def drape(*argv: str) -> list[str]:
    return [sys.executable, "-m", "datagen.cli", *argv]


def session_processes(sid: int) -> list[str]:
    """Processes still in session ``sid`` (pid and command line)."""
    out = subprocess.run(["ps", "-eo", "pid=,sid=,args="], capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        parts = line.split(None, 2)
        if len(parts) >= 2 and parts[1] == str(sid) and parts[0] != str(sid):
            rows.append(line.strip())
    return rows


LINGER_SECONDS = 120.0
"""How long the processes of a killed command are given to end. A worker armed with
``die_with_parent`` ends at once; one still importing its modules at the kill (not yet armed) ends
itself when its start-up line runs and finds its parent gone."""


def kill_at(cmd: list[str], seconds: float) -> tuple[bool, list[str], float]:
    """Run ``cmd``, kill -9 it after ``seconds`` (if still running); (was killed, processes of it left
    after :data:`LINGER_SECONDS`, seconds until the last one ended)."""
    p = subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        p.wait(timeout=seconds)
        return False, [], 0.0
    except subprocess.TimeoutExpired:
        pass
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    t0 = time.perf_counter()
    orphans: list[str] = []
    while time.perf_counter() - t0 < LINGER_SECONDS:
        orphans = session_processes(p.pid)
        if not orphans:
            break
        time.sleep(0.1)
    lingered = time.perf_counter() - t0
    for line in orphans:  # leave the machine clean whatever the result
        try:
            os.kill(int(line.split()[0]), signal.SIGKILL)
        except (ProcessLookupError, ValueError):
            pass
    return True, orphans, lingered


def run_ok(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=ENV, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr[-2000:]}")
    return time.perf_counter() - t0


def generate_trials(work: Path, trials: int, rng: random.Random) -> list[dict]:
    from benchmarks.compare_stores import compare

    cfg = work / "micro.json"
    cfg.write_text(json.dumps(MICRO))
    ref = work / "gen-ref.zarr"
    cold = run_ok(drape("generate", str(cfg), "--out", str(ref), "--workers", "1"))
    warm_store = work / "gen-warm.zarr"  # the garment cache is filled now: every later run takes this long
    seconds = run_ok(drape("generate", str(cfg), "--out", str(warm_store), "--workers", "1"))
    print(f"generate: uninterrupted in {cold:.0f} s (garment cache cold), {seconds:.0f} s (warm; the kills are drawn "
          f"in 1 .. {seconds:.0f} s), the two stores equal: {compare(ref, warm_store)['all_equal']}", flush=True)
    shutil.rmtree(warm_store, ignore_errors=True)
    rows = []
    for k in range(trials):
        out = work / f"gen-{k}.zarr"
        at = rng.uniform(1.0, 0.8 * seconds)  # a run may be faster than the measured one: not too near its end
        killed, orphans, lingered = kill_at(drape("generate", str(cfg), "--out", str(out), "--workers", "1"), at)
        run_ok(drape("generate", str(cfg), "--out", str(out), "--workers", "1"))  # resumes
        equal = compare(ref, out)["all_equal"]
        rows.append({"at_s": round(at, 1), "killed": killed, "orphans": orphans, "equal": equal,
                     "lingered_s": round(lingered, 1)})
        print(f"  generate trial {k}: kill -9 at {at:.1f} s ({'killed' if killed else 'had finished'}), orphans "
              f"{len(orphans)}{': ' + '; '.join(orphans) if orphans else ''} (all its processes gone {lingered:.1f} s after the kill), resumed store equal to the uninterrupted "
              f"one: {equal}", flush=True)
        shutil.rmtree(out, ignore_errors=True)
    return rows


def _weights(run: Path) -> dict:
    import torch

    return torch.load(run / "checkpoints" / "last.ckpt", map_location="cpu", weights_only=False)["state_dict"]


def train_trials(work: Path, trials: int, rng: random.Random, epochs: int) -> list[dict]:
    import torch

    from training.loop import read_metrics

    store = work / "train.zarr"
    if not (store / "zarr.json").is_file():
        cfg = work / "micro-train.json"
        cfg.write_text(json.dumps(MICRO_TRAIN))
        run_ok(drape("generate", str(cfg), "--out", str(store), "--workers", "1"))
    config = work / "gnn.json"
    config.write_text(json.dumps({**GNN, "epochs": epochs}))
    ref = work / "run-ref"
    train = ["train", "gnn", "--data", str(store), "--config", str(config), "--device", "cpu"]
    seconds = run_ok(drape(*train, "--out", str(ref)))
    reference = _weights(ref)
    print(f"train: {epochs} epochs uninterrupted in {seconds:.0f} s", flush=True)
    rows = []
    for k in range(trials):
        out = work / f"run-{k}"
        at = rng.uniform(3.0, 0.8 * seconds)
        killed, orphans, lingered = kill_at(drape(*train, "--out", str(out)), at)
        last = out / "checkpoints" / "last.ckpt"
        epoch = torch.load(last, map_location="cpu", weights_only=False)["epoch"] if last.is_file() else None
        if epoch is not None:  # resume from the last checkpoint; without one there is nothing to resume
            run_ok(drape(*train, "--out", str(out), "--resume"))
        else:
            run_ok(drape(*train, "--out", str(out), "--force"))
        attempts = sorted(int(p.name.split("-")[1]) for p in (out / "logs" / "csv").glob("attempt-*"))
        resumed_epochs = sorted(read_metrics(out, "train/loss_epoch", attempts=attempts[-1:]))
        equal = all(torch.equal(reference[n], w) for n, w in _weights(out).items()) and \
            set(reference) == set(_weights(out))
        rows.append({"at_s": round(at, 1), "killed": killed, "orphans": orphans, "lingered_s": round(lingered, 1),
                     "checkpoint_epoch": epoch,
                     "resumed_epochs": resumed_epochs, "weights_equal": equal})
        print(f"  train trial {k}: kill -9 at {at:.1f} s ({'killed' if killed else 'had finished'}), orphans "
              f"{len(orphans)}{': ' + '; '.join(orphans) if orphans else ''} (all gone {lingered:.1f} s after the kill), last checkpoint at epoch {epoch}, the "
              f"{'resumed' if epoch is not None else 'restarted'} run trained epochs {resumed_epochs}, final weights "
              f"bitwise equal to the uninterrupted run: {equal}", flush=True)
        shutil.rmtree(out, ignore_errors=True)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks kill9", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--what", nargs="+", default=["generate", "train"], choices=("generate", "train"))
    ap.add_argument("--epochs", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0, help="draws the kill moments")
    ap.add_argument("--dir", type=Path, default=None, help="work directory (default: a temporary one, removed)")
    args = ap.parse_args(argv)
    rng = random.Random(args.seed)
    work = args.dir or Path(tempfile.mkdtemp(prefix="drape-kill9-"))
    work.mkdir(parents=True, exist_ok=True)
    ok = True
    try:
        if "generate" in args.what:
            rows = generate_trials(work, args.trials, rng)
            bad = [r for r in rows if r["orphans"] or not r["equal"]]
            print(f"generate: {len(rows)} kill -9 trials ({sum(r['killed'] for r in rows)} killed mid-run), "
                  f"{sum(len(r['orphans']) for r in rows)} orphan processes, {sum(r['equal'] for r in rows)} resumed "
                  f"stores equal to the uninterrupted one", flush=True)
            ok &= not bad
        if "train" in args.what:
            rows = train_trials(work, args.trials, rng, args.epochs)
            bad = [r for r in rows if r["orphans"] or not r["weights_equal"]]
            print(f"train: {len(rows)} kill -9 trials ({sum(r['killed'] for r in rows)} killed mid-run), "
                  f"{sum(len(r['orphans']) for r in rows)} orphan processes, "
                  f"{sum(r['checkpoint_epoch'] is not None for r in rows)} resumed from their last checkpoint, "
                  f"{sum(r['weights_equal'] for r in rows)} with final weights equal to the uninterrupted run", flush=True)
            ok &= not bad
    finally:
        if args.dir is None:
            shutil.rmtree(work, ignore_errors=True)
    return 0 if ok else 1
