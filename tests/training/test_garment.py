"""Paper 001's garment regressor: a small model trained on a micro store shaped like
``paper-motion`` (one skirt on one body in every split, only the motions differ): the BOS MLP's
pretraining and the training loss fall, the batch grows as §4.2 says, greedy decoding gives every
frame, evaluation gives Tables 6/7/9's figures beside the skinned template, and bad input is
answered in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from datagen.errors import ConfigError, InputError
from training.garment.config import GarmentConfig

pytestmark = pytest.mark.slow

SMALL = {"epochs": 6, "batch_size": 2, "batch_growth": 1, "growth_every": 2, "max_batch_size": 4, "lr": 1e-3,
         "d_model": 32, "heads": 2, "feedforward": 64, "bos_hidden": [32, 64], "bos_epochs": 30, "precision": "32",
         "workers": 0}


@pytest.fixture(scope="module")
def garment_run(motion_store, tmp_path_factory):
    from training.garment.run import train_garment

    run = tmp_path_factory.mktemp("runs") / "skirt"
    return run, train_garment(motion_store, run, GarmentConfig(**SMALL), device="cpu")


def test_decoder_is_causal_and_greedy_decoding_gives_every_frame():
    from training.garment.model import GarmentRegressor

    torch.manual_seed(0)
    m = GarmentRegressor(10, d_model=16, heads=2, feedforward=32, bos_hidden=(8, 8)).eval()
    assert len(m.pose_encoder.layers) == len(m.garment_decoder.layers) == 2  # M = 2 (§4.2)
    poses, garment = torch.randn(2, 5, 147), torch.randn(2, 5, 30)
    out = m(poses, garment)
    changed = garment.clone()
    changed[:, 3:] += 1.0  # frames 3.. do not reach the outputs of frames 0..3 (their inputs end at frame 2)
    assert torch.allclose(m(poses, changed)[:, :4], out[:, :4], atol=1e-5)
    gen = m.generate(poses)
    assert gen.shape == (2, 5, 30) and torch.isfinite(gen).all()
    assert torch.equal(GarmentRegressor(10, d_model=16, heads=2, bos="zero").bos_frame(poses), torch.zeros(2, 30))


def _prefix_greedy(m, poses):
    """Greedy decoding of the growing prefix (the definition the static-shape decoding must equal)."""
    memory = m.encode(poses)
    frames = [m.bos_frame(poses)[:, None]]
    for _ in range(poses.shape[1]):
        frames.append(m._decode(torch.cat(frames, dim=1), memory)[:, -1:])
    return torch.cat(frames[1:], dim=1)


def test_static_shape_greedy_decoding_equals_decoding_the_growing_prefix():
    from training.garment.model import GarmentRegressor

    torch.manual_seed(1)
    m = GarmentRegressor(40, d_model=32, heads=2, feedforward=64, bos_hidden=(16, 16)).eval()
    poses = torch.randn(3, 9, 147)
    with torch.no_grad():
        ref = _prefix_greedy(m, poses)
    out = m.generate(poses)
    assert out.shape == ref.shape == (3, 9, 120)
    assert torch.allclose(out, ref, atol=1e-5), (out - ref).abs().max()


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA device: CUDA graphs exist only there")
def test_greedy_decoding_replayed_as_a_cuda_graph_equals_plain_decoding():
    from training.garment.model import GarmentRegressor

    torch.manual_seed(2)
    m = GarmentRegressor(40, d_model=32, heads=2, feedforward=64, bos_hidden=(16, 16)).cuda().eval()
    for seed in (0, 1):  # the second input replays the graph captured for the first
        poses = torch.randn(2, 7, 147, generator=torch.Generator().manual_seed(seed)).cuda()
        plain = m.generate(poses)
        graphed = m.generate(poses, graph=True)
        assert torch.allclose(graphed, plain, atol=1e-5), (graphed - plain).abs().max()


def test_batches_grow_as_the_paper_says():
    from training.garment.data import GrowingBatchSampler

    s = GrowingBatchSampler(100, 10, 5, 200, 25, seed=0)
    sizes = {}
    for epoch in (0, 199, 200, 400, 600, 1999):
        s.set_epoch(epoch)
        batches = list(s)
        sizes[epoch] = len(batches[0])
        assert sorted(sum(batches, [])) == list(range(100))
    assert sizes == {0: 10, 199: 10, 200: 15, 400: 20, 600: 25, 1999: 25}


def test_training_loss_falls_and_evaluation_gives_the_tables(garment_run, capsys):
    from datagen.cli import main
    from training.garment.run import evaluate_garment
    from training.loop import read_metrics

    run, result = garment_run
    losses = list(read_metrics(run, "train/loss_epoch").values())
    print(f"\nregressor train loss per epoch: {[round(x, 3) for x in losses]}; BOS pretraining "
          f"{[round(x, 2) for x in result['bos_pretrain_loss']]}")
    assert len(losses) == SMALL["epochs"] and losses[-1] < losses[0]
    assert result["bos_pretrain_loss"][-1] < result["bos_pretrain_loss"][0]
    e = evaluate_garment(run, split="test", device="cpu")
    assert e["garment"] == "skirt" and e["frames"] == e["segments"] * 3
    for row in (e["model"], e["skinned_baseline"], e["copy_baseline"]):
        assert all(np.isfinite(v) for v in row.values()) and -1 <= row["normal_cosine"] <= 1
        assert 0 <= row["inside_share"] <= 1
        # both RMSEs, named: per vertex (Euclidean) is √3 times per coordinate
        assert row["vertex_rmse_per_vertex"] == pytest.approx(3 ** 0.5 * row["vertex_rmse_per_coordinate"])
    assert 0 <= e["simulated_inside_share"] <= 1
    assert main(["evaluate", str(run), "--split", "test", "--device", "cpu"]) == 0
    printed = capsys.readouterr().out
    assert "skinned template" in printed and "nearest training segment (copy)" in printed and "per vertex" in printed
    assert json.loads((run / "run.json").read_text())["kind"] == "garment"


def test_bad_input_gets_one_clear_line(motion_store, tmp_path, capsys):
    from datagen.cli import main
    from training.garment.run import load_garment, train_garment

    with pytest.raises(InputError, match="unknown garment type 'gown'; this store has"):
        train_garment(motion_store, tmp_path / "r", GarmentConfig(**{**SMALL, "garment": "gown"}), device="cpu")
    with pytest.raises(InputError, match="has no segments of a tshirt"):
        train_garment(motion_store, tmp_path / "r", GarmentConfig(**{**SMALL, "garment": "tshirt"}), device="cpu")
    with pytest.raises(ConfigError, match="max_batch_size"):
        GarmentConfig(batch_size=10, max_batch_size=5)
    other = tmp_path / "motion-run"
    other.mkdir()
    (other / "run.json").write_text(json.dumps({"kind": "motion"}))
    with pytest.raises(InputError, match="holds a 'motion' model, not paper 001's garment regressor"):
        load_garment(other)
    assert main(["train", "garment", "--data", str(tmp_path), "--out", str(tmp_path / "x")]) == 2
    assert "not a drape dataset store" in capsys.readouterr().err
    assert not (tmp_path / "r").exists() and not (tmp_path / "x").exists()


def test_a_sampled_motion_is_dressed_into_one_valid_usd(motion_store, garment_run, tmp_path, capsys):
    """Paper 001's application end to end on the CPU: a generator trained briefly on the same store,
    a new walk from it, the regressor's skirt on it, one USD that usd-core validates, a GIF; and
    the same from a motion file."""
    pytest.importorskip("pxr", reason="USD output needs usd-core: pip install 'drape[usd]'")
    from datagen.cli import main
    from datagen.motion.motion import Motion
    from training.motion.config import MotionConfig
    from training.motion.run import train_motion

    run, _ = garment_run
    motion_run = tmp_path / "motion"
    train_motion(motion_store, motion_run, MotionConfig(epochs=2, batch_size=2, d_model=16, heads=2, layers=1,
                                                        feedforward=32, label_hidden=8, vertex_stride=50,
                                                        precision="32"), device="cpu")
    out, gif = tmp_path / "anim.usda", tmp_path / "clip.gif"
    assert main(["sample", "clothed", "--garment-model", str(run), "--motion-model", str(motion_run), "--label", "walk",
                 "--seed", "0", "--out", str(out), "--video", str(gif)]) == 0
    printed = capsys.readouterr().out
    assert "usd-core's validator: ok" in printed and out.is_file() and gif.is_file()
    text = out.read_text()
    assert text.count("point3f[] points.timeSamples") >= 2  # body and garment, animated
    runs = tmp_path / "runs"  # the form: a folder of runs and a garment type
    runs.mkdir()
    (runs / "motion").symlink_to(motion_run)
    (runs / "skirt").symlink_to(run)
    out3 = tmp_path / "folder.usda"
    assert main(["sample", "clothed", str(runs), "--garment", "skirt", "--label", "walk", "--seed", "0",
                 "--out", str(out3)]) == 0 and out3.is_file()
    assert main(["sample", "clothed", str(runs), "--garment", "tshirt", "--label", "walk", "--out",
                 str(tmp_path / "y.usda")]) == 2
    assert "no regressor for 'tshirt'; it has regressors for skirt (skirt)" in capsys.readouterr().err
    assert not (tmp_path / "y.usda").exists()
    files = tmp_path / "gen"
    assert main(["sample", "motion", str(motion_run), "--label", "walk", "--count", "1", "--out", str(files)]) == 0
    motion_file = next(files.glob("*.npz"))
    out2 = tmp_path / "from-file.usda"
    assert main(["sample", "clothed", "--garment-model", str(run), "--motion", str(motion_file), "--out",
                 str(out2)]) == 0 and out2.is_file()
    assert Motion.load_npz(motion_file).frame_count == 3
    assert main(["sample", "clothed", "--garment-model", str(run), "--out", str(tmp_path / "x.usda")]) == 2
    assert "give a label" in capsys.readouterr().err


def test_contact_signs_loss_and_push_out_on_a_sphere():
    """A sphere of radius 1 as the body: points inside have negative signed distance, eq. 4's loss
    is their depth, and the push-out puts every point at the margin or beyond."""
    import trimesh

    from training.garment.contact import body_contact, collision_loss, inside_share, push_out, signed_distance

    sphere = trimesh.creation.icosphere(subdivisions=3)
    body = torch.as_tensor(sphere.vertices, dtype=torch.float32)[None]
    faces = torch.as_tensor(sphere.faces, dtype=torch.int64)
    dirs = torch.nn.functional.normalize(torch.randn(1, 200, 3, generator=torch.Generator().manual_seed(0)), dim=-1)
    radii = torch.linspace(0.8, 1.2, 200)[None, :, None]
    pts = dirs * radii
    closest, normal = body_contact(pts, body, faces)
    d = signed_distance(pts, closest, normal)
    assert torch.allclose(d, radii[..., 0] - 1.0, atol=0.02)  # the sphere's signed distance, to the mesh's error
    assert abs(inside_share(pts, closest, normal) - 0.5) < 0.03
    assert abs(collision_loss(pts, closest, normal).item() - torch.relu(1.0 - radii).mean().item()) < 0.01
    out = push_out(pts, closest, normal, margin=0.01)
    c2, n2 = body_contact(out, body, faces)
    assert signed_distance(out, c2, n2).min() > 0.0 and inside_share(out, c2, n2) == 0.0


def test_refinement_writes_a_run_and_reports_interpenetration(motion_store, garment_run, tmp_path, capsys):
    from datagen.cli import main
    from training.garment.run import evaluate_garment
    from training.motion.config import MotionConfig
    from training.motion.run import train_motion

    run, _ = garment_run
    motion_run = tmp_path / "motion"
    train_motion(motion_store, motion_run, MotionConfig(epochs=1, batch_size=2, d_model=16, heads=2, layers=1,
                                                        feedforward=32, label_hidden=8, vertex_stride=50,
                                                        precision="32"), device="cpu")
    out = tmp_path / "refined"
    # a one-epoch generator's motions are arbitrary: the prior's seeds here give garments that pass the
    # 20 % gate (the per-label posterior, the default, is tested in test_motion.py)
    assert main(["train", "refine", "--garment-model", str(run), "--motion-model", str(motion_run), "--out", str(out),
                 "--samples", "4", "--steps", "5", "--device", "cpu", "--latent", "prior"]) == 0
    printed = capsys.readouterr().out
    assert "inside the body on" in printed and (out / "checkpoints" / "best.ckpt").is_file()
    summary = json.loads((out / "refine_summary.json").read_text())
    assert 0 <= summary["inside_share_before"] <= 1 and 0 <= summary["inside_share_after"] <= 1
    assert json.loads((out / "run.json").read_text())["refined_from"] == str(run.resolve())
    e = evaluate_garment(out, split="test", device="cpu")  # the refined run is a regressor run like any other
    assert np.isfinite(e["model"]["vertex_rmse_per_vertex"])
    assert main(["train", "refine", "--garment-model", str(run), "--motion-model", str(motion_run), "--out", str(out),
                 "--samples", "4", "--steps", "5"]) == 2
    assert "exists and is not empty" in capsys.readouterr().err


def test_growing_batches_are_shared_out_between_ddp_processes():
    from training.garment.data import GrowingBatchSampler

    full = GrowingBatchSampler(11, 4, 0, 10, 4, seed=3)
    ranks = [GrowingBatchSampler(11, 4, 0, 10, 4, seed=3, rank=r, world=2) for r in range(2)]
    batches = list(full)
    shares = [list(r) for r in ranks]
    assert len(shares[0]) == len(shares[1]) == len(ranks[0]) == 3  # the last global batch (3 items) still splits
    for k, b in enumerate(batches):
        assert sorted(shares[0][k] + shares[1][k]) == sorted(b)


def test_ddp_on_two_cpu_processes_follows_one_process(motion_store, tmp_path):
    """torchrun with 2 gloo processes against one process, the same global batch (4 segments)."""
    import os
    import subprocess
    import sys

    from training.loop import read_metrics

    cfg = tmp_path / "g.json"
    cfg.write_text(json.dumps({**SMALL, "batch_size": 4, "max_batch_size": 4, "batch_growth": 0, "epochs": 3}))
    base = ["train", "garment", "--data", str(motion_store), "--config", str(cfg), "--device", "cpu"]
    one = subprocess.run([sys.executable, "-m", "datagen.cli", *base, "--out", str(tmp_path / "one")],
                         capture_output=True, text=True)
    assert one.returncode == 0, one.stderr[-2000:]
    two = subprocess.run([sys.executable, "-m", "torch.distributed.run", "--nproc-per-node", "2", "-m", "datagen.cli",
                          *base, "--out", str(tmp_path / "two")], capture_output=True, text=True,
                         env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert two.returncode == 0, two.stderr[-3000:]
    a = list(read_metrics(tmp_path / "one", "train/loss_epoch").values())
    b = list(read_metrics(tmp_path / "two", "train/loss_epoch").values())
    print(f"\none process: {[round(x, 3) for x in a]}\ntwo processes: {[round(x, 3) for x in b]}")
    assert len(a) == len(b) == 3 and b[-1] < b[0]
    np.testing.assert_allclose(b, a, rtol=0.1)


def test_chunked_point_queries_match_the_direct_ones(monkeypatch):
    import training.metrics as tm

    monkeypatch.setattr(tm, "ROWS", 7)  # several blocks per frame
    g = torch.Generator().manual_seed(2)
    a, b = torch.randn(3, 20, 3, generator=g), torch.randn(3, 33, 3, generator=g)
    d = torch.cdist(a, b)
    assert torch.equal(tm.nearest(a, b), d.argmin(dim=2))
    direct = torch.maximum(d.min(dim=2).values.max(dim=1).values, d.min(dim=1).values.max(dim=1).values)
    assert torch.allclose(tm.hausdorff(a, b), direct)


def test_training_attention_keeps_cuda_on_the_math_kernel():
    """On CUDA the teacher-forced step enables only SDPA's math kernel (the memory-efficient one's
    backward can give NaN gradients from a finite loss); on the CPU nothing is changed."""
    import torch

    from training.garment.model import training_attention

    before = (torch.backends.cuda.mem_efficient_sdp_enabled(), torch.backends.cuda.flash_sdp_enabled())
    with training_attention("cpu"):
        assert (torch.backends.cuda.mem_efficient_sdp_enabled(), torch.backends.cuda.flash_sdp_enabled()) == before
    with training_attention("cuda:0"):
        assert torch.backends.cuda.math_sdp_enabled()
        assert not torch.backends.cuda.mem_efficient_sdp_enabled() and not torch.backends.cuda.flash_sdp_enabled()
    assert (torch.backends.cuda.mem_efficient_sdp_enabled(), torch.backends.cuda.flash_sdp_enabled()) == before


def test_frames_relative_to_the_skinned_template(motion_store, tmp_path):
    """``relative_to: skinned``: the regressor learns the garment minus the template skinned to the
    pose. A model whose output layer is zero then predicts exactly the skinned template: in the
    evaluation (its row equals the baseline's) and when dressing a new motion file."""
    from datagen.features import derive
    from datagen.motion.motion import Motion
    from datagen.store import open_store
    from training.garment.run import dress_motion, evaluate_garment, load_garment, train_garment
    from training.loop import read_metrics

    run = tmp_path / "skinned"
    train_garment(motion_store, run, GarmentConfig(**(SMALL | {"epochs": 3, "bos": "zero", "relative_to": "skinned"})),
                  device="cpu")
    losses = list(read_metrics(run, "train/loss_epoch").values())
    assert len(losses) == 3 and all(np.isfinite(losses))
    e = evaluate_garment(run, split="test", device="cpu")
    assert e["relative_to"] == "skinned" and np.isfinite(e["model"]["vertex_rmse_per_vertex"])
    # training derives the skinned template from the batch's poses (on the training device); it is the
    # store's derived ``skin``, which evaluation reads
    from training.paper001.data import SegmentDataset

    module, meta, _, store0 = load_garment(run)
    batch = next(iter(torch.utils.data.DataLoader(SegmentDataset(store0, "train", names=("pose", "trans", "skin")),
                                                  batch_size=2)))
    torch.testing.assert_close(module.skinned(batch["pose"]), batch["skin"].float(), atol=2e-6, rtol=0)
    ckpt = run / "checkpoints" / "best.ckpt"
    state = torch.load(ckpt, map_location="cpu", weights_only=False)
    for k in ("model.garment_out.weight", "model.garment_out.bias"):
        state["state_dict"][k] = torch.zeros_like(state["state_dict"][k])
    torch.save(state, ckpt)
    e = evaluate_garment(run, split="test", device="cpu")
    for k in ("vertex_rmse_per_coordinate", "vertex_rmse_per_vertex", "hausdorff", "sted", "inside_share"):
        assert e["model"][k] == pytest.approx(e["skinned_baseline"][k], rel=1e-5, abs=1e-7), k
    store = open_store(motion_store)
    m = store.motions()
    motion = Motion(poses=np.asarray(m["pose"][0][:5]), trans=np.asarray(m["trans"][0][:5]), fps=30.0, label=0,
                    label_name="walk")
    motion.save_npz(tmp_path / "walk.npz")
    out = dress_motion(run, motion_file=tmp_path / "walk.npz", push_out_margin=None)
    _, meta, _, _ = load_garment(run)
    skin = derive(store.binding(int(meta["template"])), ["skin"], pose=motion.poses, trans=motion.trans)["skin"]
    np.testing.assert_allclose(out["garment_vertices"], skin + motion.trans[:, None], atol=2e-5)
    # paper 001's own frame (relative to the translation) stays a switch, and its runs evaluate as before
    paper = tmp_path / "paper-frame"
    train_garment(motion_store, paper, GarmentConfig(**(SMALL | {"epochs": 2, "relative_to": "translation"})),
                  device="cpu")
    e = evaluate_garment(paper, split="test", device="cpu")
    assert e["relative_to"] == "translation" and all(np.isfinite(v) for v in e["model"].values())


def test_clothed_runs_are_found_in_a_folder_of_runs(tmp_path):
    """`drape sample clothed RUNS --garment T` (the issue's form): the regressor for T (its refined
    run where there is one) and the folder's generator; every miss or ambiguity is one line that
    lists what the folder holds."""
    from training.garment.run import clothed_runs

    def run(name, **meta):
        d = tmp_path / "runs" / name
        d.mkdir(parents=True)
        (d / "run.json").write_text(json.dumps(meta))
        return d

    motion = run("motion", kind="motion")
    skirt = run("skirt_s1", kind="garment", config={"garment": "skirt"})
    pants = run("pants_s3", kind="garment", config={"garment": "pants"})
    folder = tmp_path / "runs"
    assert clothed_runs(folder, "skirt") == (skirt, motion)
    assert clothed_runs(folder, "pants", need_motion=False) == (pants, None)
    with pytest.raises(InputError, match=r"no regressor for 'dress'; it has regressors for pants \(pants_s3\), "
                                         r"skirt \(skirt_s1\)"):
        clothed_runs(folder, "dress")
    with pytest.raises(InputError, match="give --garment: .* has regressors for pants"):
        clothed_runs(folder, None)
    refined = run("skirt_s1_refined", kind="garment", config={"garment": "skirt"}, refined_from=str(skirt))
    assert clothed_runs(folder, "skirt")[0] == refined  # the refined run is preferred
    run("skirt_s3_refined", kind="garment", config={"garment": "skirt"}, refined_from=str(skirt))
    with pytest.raises(InputError, match="several regressors for skirt .*name one with --garment-model"):
        clothed_runs(folder, "skirt")
    assert clothed_runs(folder, "skirt", garment_run=skirt) == (skirt, motion)
    with pytest.raises(InputError, match="--garment pants: .* is a regressor for skirt"):
        clothed_runs(None, "pants", garment_run=skirt)
    run("motion_b", kind="motion")
    with pytest.raises(InputError, match=r"several motion-generator runs \(motion, motion_b\); name one"):
        clothed_runs(folder, "pants")
    with pytest.raises(InputError, match="is itself a run"):
        clothed_runs(skirt, "skirt")
    with pytest.raises(InputError, match="not a folder of runs"):
        clothed_runs(tmp_path / "nowhere", "skirt")
    with pytest.raises(InputError, match="name the runs"):
        clothed_runs(None, "skirt")
