"""``drape generate`` end to end on a micro config (coarse garments, a few frames): the store
validates, tensorstore reads it, a finished run does nothing, a changed config is refused, a run
killed with SIGKILL resumes to the same store, and the Ray executor makes the same store as the
local one. Marked slow: each generation simulates five scenes on the CPU (about a minute)."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from datagen.config import load_config
from datagen.errors import ConfigError, InputError, SimulationError
from datagen.generate.config import PRESETS, DatasetConfig, resolve_config
from datagen.generate.run import generate
from datagen.store import open_store, validate

pytestmark = pytest.mark.slow

MICRO = {
    "seed": 0, "frames": 6, "segment_length": 3, "garment_edge_length": 0.07,
    "simulation": {"settle_rest": 2, "lead_in": 0.1, "settle_pose": 1, "ramp": 0.1,
                   "solver": {"substeps": 3, "iterations": 3, "detection_interval": 2}},
    "train": {"garments": ["tshirt:0", "pants:0"], "bodies": ["regular", "seed:1"], "motions": ["walk:0"]},
    "test": {"garments": ["skirt:1"], "bodies": ["thin"], "motions": ["wave:1"]},
}


def micro(**changes) -> DatasetConfig:
    return load_config(DatasetConfig, {**MICRO, **changes})


def arrays_of(path: Path) -> dict[str, np.ndarray]:
    import zarr

    root = zarr.open_group(str(path), mode="r")
    out = {}
    for name, arr in root.arrays():
        out[name] = arr[...]
    for name, group in root.groups():
        for sub, arr in group.arrays():
            out[f"{name}/{sub}"] = arr[...]
    return out


def assert_same_store(a: Path, b: Path, *, skip=("samples/seconds",)) -> None:
    xa, xb = arrays_of(a), arrays_of(b)
    assert sorted(xa) == sorted(xb)
    for k in xa:
        if k not in skip:
            np.testing.assert_array_equal(xa[k], xb[k], err_msg=k)


@pytest.fixture(scope="module")
def local_store(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("gen") / "micro.zarr"
    summary = generate(micro(), out)
    assert summary["simulated"] == 5
    return out


def test_store_validates_and_holds_every_sample(local_store):
    assert validate(local_store) == []
    s = open_store(local_store)
    assert len(s.split("train")) == 4 and len(s.split("test")) == 1
    ok = [i for i in range(5) if s.scalars(i)["failure"] == 0]
    print(f"\nmicro store: {len(ok)} of 5 samples ok; failures "
          f"{[s.scalars(i)['failure'] for i in range(5)]}")
    for i in ok:
        x = s.sample(i, names=["detail", "coarse", "joints", "trans", "anchor", "anchor_skin", "joint_distance",
                               "body_vertices"])
        T, V = x["detail"].shape[:2]
        assert T == 6 and x["coarse"].shape == (T, V, 3) and x["joint_distance"].shape == (T, V, 24)
        assert x["body_vertices"].shape == (T, s.body_model()["v_template"].shape[0], 3)
        assert np.isfinite(x["detail"]).all()
        # derived on read, as schema 3 stored them: anchor_skin = anchor - trans, distances to the joints
        np.testing.assert_allclose(x["anchor_skin"], x["anchor"] - x["trans"][:, None], atol=1e-6)
        np.testing.assert_allclose(x["joint_distance"][:, :, 0],
                                   np.linalg.norm(x["coarse"] - x["joints"][:, None, 0], axis=-1), atol=1e-5)
        g = s.garment(int(s.scalars(i)["garment"]))
        assert len(g["rest_vertices"]) == V
    # four training pairs for three factors: fitted, but flagged and recorded
    d = s.attrs["fit_diagnostics"]
    assert s.attrs["fit_attribute"] is True and d["pairs"] == 4 and d["factors"] == 3
    assert any("only 4 training garment-body pairs" in w for w in d["warnings"]), d
    assert len(d["alpha_seed_spread"]) == 3


def test_a_store_without_the_fit_attribute(tmp_path):
    """paper 001's kind of store: one garment on one body in training, no fit attribute (α NaN, D = 0),
    which with a fit would be refused before anything is made."""
    one = {"garments": ["skirt:0"], "bodies": ["regular"], "motions": ["walk:0"]}
    with pytest.raises(ConfigError, match="needs more than 3 garment-body pairs in the train split, which has 1"):
        micro(train=one, test={**one, "motions": ["wave:1"]}, split_disjoint=["motions"])
    out = tmp_path / "motion.zarr"
    assert not out.exists()
    config = micro(train=one, test={**one, "motions": ["wave:1"]}, fit_attribute=False, split_disjoint=["motions"])
    generate(config, out)
    assert validate(out) == []
    s = open_store(out)
    assert s.attrs["fit_attribute"] is False and s.attrs["fit_diagnostics"] == {}
    assert np.isnan(s.garment(0)["alpha"]).all() and s.fit_model()["components"].shape == (3, 0)


def test_tensorstore_reads_every_array(local_store):
    ts = pytest.importorskip("tensorstore", reason="tensorstore is in the dev extra")
    for name, value in arrays_of(local_store).items():
        spec = {"driver": "zarr3", "kvstore": {"driver": "file", "path": str(local_store / name)}}
        np.testing.assert_array_equal(ts.open(spec).result().read().result(), value, err_msg=name)


def test_finished_store_is_left_alone_and_other_config_refused(local_store):
    """A finished store run again (with another batch size too: it only groups scenes for the
    device) does nothing; another config is refused; the store records the config without the
    batch size and the code version that made it."""
    from datagen.generate.identity import code_version
    from datagen.store.layout import read_root_attributes

    before = {p: p.stat().st_mtime_ns for p in local_store.rglob("*") if p.is_file()}
    assert generate(micro(), local_store)["simulated"] == 0
    assert generate(micro(simulation={**MICRO["simulation"], "batch_size": 1}), local_store)["simulated"] == 0
    attrs = read_root_attributes(local_store)
    assert attrs["code_version"] == code_version() and len(code_version()) == 16
    assert "batch_size" not in attrs["config"]["simulation"] and attrs["config"]["simulation"]["solver"]["steps"]["substeps"] == 3
    with pytest.raises(InputError, match="frames"):
        generate(micro(frames=7), local_store)
    after = {p: p.stat().st_mtime_ns for p in local_store.rglob("*") if p.is_file()}
    assert before == after


def test_a_rerun_removes_what_an_interrupted_cleanup_left(local_store, tmp_path):
    """Ctrl-C after pack marked the store complete but before staging/ was removed: the same command
    run again removes the leftovers and changes nothing else."""
    from datagen.store.layout import STAGING

    store = tmp_path / "copy.zarr"
    shutil.copytree(local_store, store)
    (store / STAGING / "sample-000000001").mkdir(parents=True)
    (store / STAGING / "sample-000000001" / "detail.npy").write_bytes(b"x" * 1000)
    assert generate(micro(), store)["simulated"] == 0
    assert not (store / STAGING).exists() and validate(store) == []
    assert_same_store(local_store, store, skip=())


def test_kill_and_resume_gives_the_same_store(local_store, tmp_path):
    """Kill -9 the generator after its first staged sample, run it again: the same store. Scenes
    are simulated one per batch here, in one process (so samples are staged one by one): the arrays
    also equal the store simulated in one batch of five with worker processes staging (the default)."""
    import json

    one_by_one = {**MICRO, "simulation": {**MICRO["simulation"], "batch_size": 1}}
    cfg = tmp_path / "micro.json"
    cfg.write_text(json.dumps(one_by_one))
    out = tmp_path / "killed.zarr"
    code = ("import json,sys; from datagen.config import load_config; from datagen.generate.config import "
            "DatasetConfig; from datagen.generate.run import generate; "
            "generate(load_config(DatasetConfig, json.load(open(sys.argv[1]))), sys.argv[2], workers=0)")
    proc = subprocess.Popen([sys.executable, "-c", code, str(cfg), str(out)], env=dict(os.environ),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    staged = out / "staging"
    t0 = time.time()
    while time.time() - t0 < 600:
        if staged.exists() and any(p.name.startswith("sample-") for p in staged.iterdir()):
            break
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_staged = len([p for p in staged.iterdir() if p.name.startswith("sample-")]) if staged.exists() else 0
    summary = generate(load_config(DatasetConfig, one_by_one), out)
    print(f"\nkilled after {n_staged} staged sample(s); the resumed run simulated {summary['simulated']} of 5")
    assert 1 <= n_staged < 5 and summary["simulated"] == 5 - n_staged
    assert validate(out) == []
    assert_same_store(local_store, out)


def test_a_time_limit_stops_between_batches_and_the_same_command_finishes_the_store(local_store, tmp_path, capsys):
    """``drape generate --time-limit``: batches of two scenes and a limit shorter than one batch.
    The first batch always runs, then the run stops with exit status 75 and says how many scenes are
    left; its samples stay staged; the same command finishes the store, equal to the one made in
    one go."""
    import json

    from datagen.cli import main
    from datagen.cli.generate import INCOMPLETE

    cfg = tmp_path / "micro.json"
    cfg.write_text(json.dumps({**MICRO, "simulation": {**MICRO["simulation"], "batch_size": 2}}))
    out = tmp_path / "limited.zarr"
    assert main(["generate", str(cfg), "--out", str(out), "--workers", "0", "--time-limit", "0.0001"]) == INCOMPLETE
    said = capsys.readouterr().out
    assert "3 of 5 scenes are left (2 batch(es))" in said and "run the same command again" in said
    staged = [p for p in (out / "staging").iterdir() if p.name.startswith("sample-")]
    assert len(staged) == 2
    assert main(["generate", str(cfg), "--out", str(out), "--workers", "0"]) == 0
    assert "simulated 3 of 5 scenes" in capsys.readouterr().out
    assert validate(out) == []
    assert_same_store(local_store, out)
    with pytest.raises(InputError, match="positive number of minutes"):
        generate(micro(), tmp_path / "x.zarr", time_limit=0)
    with pytest.raises(InputError, match="local executor"):
        generate(micro(), tmp_path / "y.zarr", executor="ray", time_limit=5)
    assert not (tmp_path / "x.zarr").exists() and not (tmp_path / "y.zarr").exists()


def test_a_store_whose_every_scene_failed_is_finished_and_says_so(tmp_path, capsys):
    """A stretch limit no cloth meets (0.1 %): every scene fails at its first frame and is frozen
    there; the store is still finished and valid (the failures, their reasons and frames), and the
    command says that nothing was stored instead of dividing by a rate of zero (it did)."""
    import json

    from datagen.cli import main

    cfg = tmp_path / "failing.json"
    cfg.write_text(json.dumps({**MICRO, "simulation": {**MICRO["simulation"], "thresholds": {"stretch": 0.001}}}))
    out = tmp_path / "failing.zarr"
    assert main(["generate", str(cfg), "--out", str(out), "--workers", "0"]) == 0
    assert "every scene failed, so no garment-frame was stored" in capsys.readouterr().out
    assert validate(out) == []
    store = open_store(out)
    assert np.all(store.index["failure"] > 0) and np.all(store.index["failure_frame"] == 0)


def test_a_batch_too_large_for_the_device_stops_the_run_with_what_to_do_and_keeps_what_was_staged(tmp_path,
                                                                                                   monkeypatch):
    """One scene per batch; the device has room for the first batch only (its free memory is
    patched to 1 MiB after that): the run stops with an error that gives the figures and names
    simulation.batch_size, the first sample stays staged and the rest are missing, ready to resume."""
    import datagen.sim.device as dv
    from datagen.generate.plan import Plan, open_writer

    import sys

    import datagen.sim.scene as sc

    batches, simulate = [], sc.simulate

    def counted(*args, **kwargs):  # the scene batches count (the templates' settle at rest simulates too)
        if sys._getframe(1).f_globals["__name__"] == "datagen.generate.samples":
            batches.append(1)
        return simulate(*args, **kwargs)

    def free(device):
        return None if len(batches) <= 1 else 2**20

    monkeypatch.setattr(sc, "simulate", counted)
    monkeypatch.setattr(dv, "device_free_bytes", free)
    config = load_config(DatasetConfig, {**MICRO, "simulation": {**MICRO["simulation"], "batch_size": 1}})
    out = tmp_path / "small-device.zarr"
    with pytest.raises(SimulationError) as exc:
        generate(config, out)
    assert "needs about" in str(exc.value) and "MiB free" in str(exc.value)
    assert "simulation.batch_size" in str(exc.value)
    writer = open_writer(Plan(config), out)
    assert len(writer.missing(range(5))) == 4 and not writer.is_complete


def test_ray_executor_makes_the_same_store(local_store, tmp_path):
    """Two CPU tasks, each simulating a share of the five scenes in its own process."""
    pytest.importorskip("ray", reason="the Ray executor needs the ray extra: pip install 'drape[ray]'")
    out = tmp_path / "ray.zarr"
    summary = generate(micro(), out, executor="ray", workers=2)
    assert summary["simulated"] == 5 and summary["cpus"] == 2
    assert sorted(t["samples"] for t in summary["tasks"]) == [2, 3]
    assert len({t["pid"] for t in summary["tasks"]}) == 2 and all(t["gpus"] == [] for t in summary["tasks"])
    assert validate(out) == []
    assert_same_store(local_store, out)


def test_several_devices_make_the_same_store(local_store, tmp_path):
    """The local executor on two devices (``--device cpu,cpu``): two simulating processes, each a
    share of the five scenes, staging side by side; then one pack."""
    out = tmp_path / "two.zarr"
    seen = []
    summary = generate(micro(), out, device="cpu,cpu", workers=0, progress=lambda *a: seen.append(a))
    assert summary["simulated"] == 5 and summary["complete"]
    assert sorted(t["samples"] for t in summary["tasks"]) == [2, 3]
    assert len({t["pid"] for t in summary["tasks"]}) == 2 and {t["device"] for t in summary["tasks"]} == {"cpu"}
    assert summary["garment_frames"] == sum(t["garment_frames"] for t in summary["tasks"])
    assert [a for a in seen if a[0] == 1][-1] == (1, 5, 5, 0)  # devices report as they finish
    assert validate(out) == []
    assert_same_store(local_store, out)


def test_ray_refuses_cuda_without_gpus_before_writing(tmp_path):
    pytest.importorskip("ray", reason="the Ray executor needs the ray extra: pip install 'drape[ray]'")
    out = tmp_path / "none.zarr"
    with pytest.raises(InputError, match="Ray cluster has no GPU"):
        generate(micro(), out, executor="ray", device="cuda", workers=1)
    assert not out.exists()


def test_ray_shares_give_every_gpu_a_batch():
    from datagen.generate.ray_executor import shares

    assert [len(s) for s in shares(list(range(56)), 64, 2)] == [28, 28]  # small on two GPUs: one batch each
    assert [len(s) for s in shares(list(range(56)), 64, 1)] == [56]
    assert [len(s) for s in shares(list(range(130)), 64, 2)] == [44, 43, 43]  # none above the batch size
    assert [len(s) for s in shares(list(range(3)), 64, 8)] == [1, 1, 1]
    assert shares([], 64, 2) == []
    for n, bs, slots in ((56, 64, 2), (130, 64, 2), (5, 2, 3), (7, 64, 4)):
        parts = shares(list(range(n)), bs, slots)
        assert sum(parts, []) == list(range(n)) and max(map(len, parts)) <= bs


def test_config_errors_say_what_is_wrong():
    with pytest.raises(ConfigError, match="unknown garment 'gown'"):
        micro(train={**MICRO["train"], "garments": ["gown:0"]})
    with pytest.raises(ConfigError, match="both train.bodies and test.bodies"):
        micro(test={**MICRO["test"], "bodies": ["regular"]})
    with pytest.raises(ConfigError, match="unknown preset"):
        resolve_config(preset="huge")
    with pytest.raises(ConfigError, match="substep"):
        load_config(DatasetConfig, {**MICRO, "simulation": {"substep": 3}})
    assert set(PRESETS) == {"tiny", "small", "medium", "paper-gnn", "paper-motion"}
    for name in PRESETS:
        resolve_config(preset=name)
    # paper 001 never uses α: its preset fits none (with one body per split it could not)
    assert resolve_config(preset="paper-motion").fit_attribute is False


def test_motion_files_are_a_motion_source(tmp_path):
    """``file:PATH`` motions (e.g. the motion generator's samples): the store holds them with their
    label and seed -1; a changed file is not resumed; a file too short is refused before anything
    is written."""
    from datagen.motion.library import make_motion
    from datagen.store.layout import read_root_attributes

    long = tmp_path / "walk.npz"
    make_motion("walk", seed=5, frames=40, fps=30.0).save_npz(long)
    short = tmp_path / "short.npz"
    make_motion("squat", seed=1, frames=4, fps=30.0).save_npz(short)
    one = {"garments": ["skirt:0"], "bodies": ["regular"]}
    cfg = {**MICRO, "fit_attribute": False, "split_disjoint": ["motions"],
           "train": {**one, "motions": [f"file:{long}"]}, "test": {**one, "motions": ["wave:1"]}}
    out = tmp_path / "files.zarr"
    generate(load_config(DatasetConfig, cfg), out)
    store = open_store(out)
    motions = store.motions()
    assert motions["seed"].tolist() == [-1, 1] and store.attrs["label_names"][motions["label"][0]] == "walk"
    assert "+inputs-" in read_root_attributes(out)["code_version"]
    s = store.frames(0, names=["label"])
    assert (s["label"] == motions["label"][0]).all()
    make_motion("walk", seed=6, frames=40, fps=30.0).save_npz(long)  # another file under the same name
    with pytest.raises(InputError):
        generate(load_config(DatasetConfig, cfg), out)
    bad = {**cfg, "train": {**one, "motions": [f"file:{short}"]}}
    with pytest.raises(InputError, match="has 4 frames at 30 fps; a scene of this config needs"):
        generate(load_config(DatasetConfig, bad), tmp_path / "short.zarr")
    assert not (tmp_path / "short.zarr").exists()
    with pytest.raises(ConfigError, match="does not exist"):
        load_config(DatasetConfig, {**cfg, "train": {**one, "motions": [f"file:{tmp_path / 'none.npz'}"]}})


def test_a_device_process_sees_only_its_gpu(monkeypatch):
    """Each device's process makes its GPU the only visible one (warp's default device included),
    counting among a CUDA_VISIBLE_DEVICES already set."""
    from datagen.generate.devices import pin_gpu

    monkeypatch.delenv("CUDA_VISIBLE_DEVICES", raising=False)
    assert pin_gpu("cuda:2") == "cuda:0" and os.environ["CUDA_VISIBLE_DEVICES"] == "2"
    monkeypatch.setenv("CUDA_VISIBLE_DEVICES", "4,6")
    assert pin_gpu("cuda:1") == "cuda:0" and os.environ["CUDA_VISIBLE_DEVICES"] == "6"
    monkeypatch.setenv("CUDA_VISIBLE_DEVICES", "4,6")
    assert pin_gpu("cpu") == "cpu" and os.environ["CUDA_VISIBLE_DEVICES"] == "4,6"
