"""Workers die with their parent (issue 65): a process that calls ``die_with_parent`` is killed by the
kernel when its parent is killed with SIGKILL, for a plain spawned process, a DataLoader worker and the
workers of a real ``drape generate`` (slow); and a damaged store found inside a DataLoader worker
reaches the main process as the one-line refusal."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import torch

PARENT = r"""
import multiprocessing, sys, time
from datagen.lifetime import die_with_parent

def child():
    die_with_parent()
    time.sleep(600)

if __name__ == "__main__":
    p = multiprocessing.get_context("spawn").Process(target=child)
    p.start()
    time.sleep(1.5)  # the child has armed its signal
    print(p.pid, flush=True)
    time.sleep(600)
"""

LOADER = r"""
import os, sys, time, torch
from training.datamodule import worker_init

class Slow(torch.utils.data.Dataset):
    def __len__(self): return 10**6
    def __getitem__(self, i):
        open(os.path.join(sys.argv[1], str(os.getpid())), "w").close()  # armed: worker_init has run
        time.sleep(600)

if __name__ == "__main__":
    loader = torch.utils.data.DataLoader(Slow(), num_workers=2, worker_init_fn=worker_init,
                                         multiprocessing_context="spawn")
    it = iter(loader)
    while len(os.listdir(sys.argv[1])) < 2:
        time.sleep(0.1)
    print(" ".join(str(w.pid) for w in it._workers), flush=True)
    next(it)
"""


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(")")[-1].split()[0] != "Z"  # a zombie is dead, waiting to be reaped
    except FileNotFoundError:
        return False


def _session(pid: int) -> list[int]:
    out = subprocess.run(["ps", "-eo", "pid=,sid="], capture_output=True, text=True).stdout
    return [int(p) for p, s in (line.split() for line in out.splitlines()) if s == str(pid) and p != str(pid)]


def _kill_parent_and_check(script: str, tmp_path: Path) -> None:
    f = tmp_path / "parent.py"
    f.write_text(script)
    env = {**os.environ, "PYTHONPATH": os.getcwd(), "OMP_NUM_THREADS": "1"}
    marks = tmp_path / "marks"
    marks.mkdir()
    p = subprocess.Popen([sys.executable, str(f), str(marks)], stdout=subprocess.PIPE, text=True, env=env,
                         start_new_session=True)
    try:
        children = [int(x) for x in p.stdout.readline().split()]
        assert children and all(_alive(c) for c in children)
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
        deadline = time.time() + 5
        while time.time() < deadline and any(_alive(c) for c in children):
            time.sleep(0.05)
        left = [c for c in children if _alive(c)]
        assert not left, f"orphans left after kill -9 of their parent: {left}"
    finally:
        for c in _session(p.pid):
            os.kill(c, signal.SIGKILL)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_a_spawned_worker_dies_with_its_parent(tmp_path):
    _kill_parent_and_check(PARENT, tmp_path)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_dataloader_workers_die_with_their_parent(tmp_path):
    _kill_parent_and_check(LOADER, tmp_path)


class StoreFrames(torch.utils.data.Dataset):
    """The detail positions of a store's samples, read in the worker."""

    def __init__(self, store):
        self.store = store

    def __len__(self) -> int:
        return 2

    def __getitem__(self, i):
        return torch.as_tensor(self.store.sample(i)["detail"])


def _as_list(batch):
    return batch


def test_a_damaged_store_found_in_a_dataloader_worker_is_one_line(tmp_path):
    from datagen.store import open_store
    from datagen.store.integrity import DamagedStoreError
    from tests.store.conftest import build

    store = tmp_path / "s"
    build(store)
    f = store / "vertex_frames" / "detail" / "c" / "0" / "0"
    f.write_bytes(f.read_bytes()[: f.stat().st_size // 2])
    loader = torch.utils.data.DataLoader(StoreFrames(open_store(store)), num_workers=1, multiprocessing_context="spawn",
                                         collate_fn=_as_list)
    with pytest.raises(DamagedStoreError) as err:
        next(iter(loader))
    message = str(err.value)
    assert message.startswith("the store is damaged at vertex_frames/detail (shard c/0/0"), message
    assert "\n" not in message and "Traceback" not in message and err.value.exit_status == 1


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_kill_9_of_drape_generate_leaves_no_worker(tmp_path):
    """A real ``drape generate`` with a worker pool, killed (SIGKILL) once its workers run: none is left,
    and the same command finishes the store."""
    import json

    from tests.generate.test_generate import MICRO

    cfg = tmp_path / "micro.json"
    cfg.write_text(json.dumps(MICRO))
    cmd = [sys.executable, "-m", "datagen.cli", "generate", str(cfg), "--out", str(tmp_path / "s.zarr"), "--workers", "1"]
    env = {**os.environ, "PYTHONPATH": os.getcwd(), "OMP_NUM_THREADS": "1", "CUDA_VISIBLE_DEVICES": ""}
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.time() + 300
        while time.time() < deadline and p.poll() is None and len(_session(p.pid)) < 2:
            time.sleep(0.2)  # the resource tracker and the pool's worker
        assert p.poll() is None, "generate ended before its workers started"
        time.sleep(2)
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
        # an armed worker ends at once; one still importing its modules ends itself at its start-up line
        deadline = time.time() + 120
        while time.time() < deadline and _session(p.pid):
            time.sleep(0.1)
        assert _session(p.pid) == [], "processes of drape generate left 120 s after its kill -9"
    finally:
        for c in _session(p.pid):
            os.kill(c, signal.SIGKILL)
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    shutil.rmtree(tmp_path / "s.zarr")
