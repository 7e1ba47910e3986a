"""Paper 001's motion generator: a small model trained for a few epochs on the micro store's
segments (the loss falls), reconstruction evaluated beside the mean-pose baseline, motions sampled
into the motion library's format and exported to BVH, and bad input answered in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from datagen.errors import ConfigError, InputError
from training.motion.config import MotionConfig

pytestmark = pytest.mark.slow

SMALL = {"epochs": 8, "batch_size": 4, "lr": 1e-3, "d_model": 32, "heads": 2, "layers": 2, "feedforward": 64,
         "label_hidden": 16, "vertex_stride": 40, "precision": "32", "workers": 0}


@pytest.fixture(scope="module")
def motion_run(train_store, tmp_path_factory):
    from training.motion.run import train_motion

    run = tmp_path_factory.mktemp("runs") / "motion"
    result = train_motion(train_store, run, MotionConfig(**SMALL), device="cpu")
    return run, result


def test_the_model_follows_the_paper_and_samples_reproducibly():
    from training.motion.model import MotionCVAE
    from training.paper001.frames import FRAME_FEATURES, features_to_frames, frames_to_features

    m = MotionCVAE(17).eval()  # §4.2: d_model 256, 4 heads, N = 8 layers, feed-forward 1024
    assert len(m.encoder.layers) == len(m.decoder.layers) == 8 and m.d_model == 256
    assert m.encoder.layers[0].linear1.out_features == 1024 and m.encoder.layers[0].self_attn.num_heads == 4
    x = torch.randn(3, 60, FRAME_FEATURES)
    label = torch.tensor([0, 5, 16])
    out, mu, logvar = m(x, label)
    assert out.shape == x.shape and mu.shape == logvar.shape == (3, 256)
    a = m.sample(label, 60, generator=torch.Generator().manual_seed(1))
    b = m.sample(label, 60, generator=torch.Generator().manual_seed(1))
    assert torch.equal(a, b) and a.shape == (3, 60, FRAME_FEATURES)
    rot, trans = features_to_frames(a)  # 6D -> proper rotations
    eye = torch.eye(3).expand_as(rot @ rot.transpose(-1, -2))
    assert torch.allclose(rot @ rot.transpose(-1, -2), eye, atol=1e-4) and trans.shape == (3, 60, 3)
    rot2, trans2 = features_to_frames(frames_to_features(rot, trans))  # a round trip keeps the rotations
    assert torch.allclose(rot2, rot, atol=1e-5) and torch.allclose(trans2, trans - trans[:, :1], atol=1e-6)


def test_training_loss_falls_and_the_checkpoint_is_written(motion_run):
    from training.loop import read_metrics

    run, result = motion_run
    losses = list(read_metrics(run, "train/loss_epoch").values())
    print(f"\nmotion generator train loss per epoch: {[round(x, 4) for x in losses]}")
    assert len(losses) == SMALL["epochs"] and losses[-1] < losses[0]
    assert (run / "checkpoints" / "best.ckpt").is_file() and result["train_segments"] > 0
    assert json.loads((run / "run.json").read_text())["kind"] == "motion"


def test_the_plateau_schedule_waits_for_the_papers_steps_on_short_epochs(motion_run):
    """Paper 001's 30 epochs are ~2,700 steps of its dataset; on a small store the schedule waits at
    least that many steps (the trained run's scheduler state holds the patience it used)."""
    import math
    from types import SimpleNamespace

    from training.loop import plateau_patience

    run, result = motion_run
    ckpt = torch.load(run / "checkpoints" / "last.ckpt", map_location="cpu", weights_only=False)
    steps_per_epoch = math.ceil(result["train_segments"] / SMALL["batch_size"])
    assert ckpt["lr_schedulers"][0]["patience"] == max(30, math.ceil(2700 / steps_per_epoch))
    fake = SimpleNamespace(_trainer=SimpleNamespace(estimated_stepping_batches=12 * 5000, max_epochs=5000))
    assert plateau_patience(fake, 30, 2700) == 225  # 12 steps an epoch: 225 epochs
    fake._trainer.estimated_stepping_batches = 200 * 5000
    assert plateau_patience(fake, 30, 2700) == 30  # long epochs: the paper's 30
    assert plateau_patience(fake, 30, None) == 30


def test_evaluate_gives_table_3_beside_the_mean_pose_baseline(motion_run, capsys):
    from datagen.cli import main
    from training.motion.run import evaluate_motion

    run, _ = motion_run
    e = evaluate_motion(run, split="test", device="cpu", repetitions=3, recognizer_epochs=5)
    rows = (e["model"], e["mean_pose_baseline"], e["own_mean_pose"], e["nearest_training_segment"])
    for row in rows:
        assert all(np.isfinite(v) and v > 0 for v in row.values())
        # both RMSEs, named: the Euclidean one per joint / vertex is √3 times the per-coordinate one
        assert row["pose_rmse_per_joint"] == pytest.approx(3 ** 0.5 * row["pose_rmse_per_coordinate"])
        assert row["vertex_rmse_per_vertex"] == pytest.approx(3 ** 0.5 * row["vertex_rmse_per_coordinate"])
    # the segment's own mean pose is the best static pose: closer than the label's mean on every frame set
    assert e["own_mean_pose"]["pose_rmse_per_coordinate"] < e["mean_pose_baseline"]["pose_rmse_per_coordinate"]
    assert e["frames"] == e["segments"] * 3
    # the vertex figures are on the whole body, whatever vertex_stride (40 here) the run trained with
    assert e["body_vertices"] == len(open_store_of(run).body_model()["v_template"]) and e["untrained_labels"] == {}
    assert e["real_speed"] > 0  # how much the reconstructions move against the true segments
    g = e["generation"]
    assert g["repetitions"] == 3 and 0 <= g["recognizer_test_accuracy"] <= 1
    for part in ("generated", "real"):
        assert np.isfinite(g[part]["fid"]["mean"]) and g[part]["fid"]["mean"] >= -1e-6
        assert 0 <= g[part]["accuracy"]["mean"] <= 1 and g[part]["diversity"]["mean"] >= 0
    gp = e["generation_posterior"]
    assert gp["latent"] == "posterior" and g["latent"] == "prior" and gp["real"] == g["real"]
    assert np.isfinite(gp["generated"]["fid"]["mean"])
    assert g["real"]["speed"]["mean"] > 0 and gp["generated"]["speed"]["mean"] >= 0
    base = e["generation_baselines"]  # Table 4 beside a still and a copying generator
    assert base["still"]["speed"]["mean"] == pytest.approx(0, abs=1e-7) and base["copy"]["speed"]["mean"] > 0
    assert np.isfinite(base["copy"]["fid"]["mean"]) and base["still"]["multimodality"]["mean"] == pytest.approx(0, abs=1e-5)
    assert main(["evaluate", str(run), "--split", "test", "--device", "cpu", "--repetitions", "2"]) == 0
    out = capsys.readouterr().out
    assert "label's mean pose" in out and "segment's own mean pose" in out and "generated, prior" in out and "generated, posterior" in out
    assert "multimodality" in out and "speed of the reconstructions" in out
    assert "per joint" in out and "per vertex" in out and "nearest training segment (copy)" in out
    assert "copy: a training segment" in out and "still: label's mean pose" in out


def open_store_of(run):
    from datagen.store import open_store

    return open_store(json.loads((run / "run.json").read_text())["store"]["path"])


def test_evaluate_on_one_segment_gives_table_3_and_says_why_not_table_4(motion_run, monkeypatch, capsys):
    """A split with one segment (issue 62: scipy's traceback from FID's covariance) gets Table 3 and
    one line saying why Table 4 is not measured."""
    import training.motion.run as run_module
    from datagen.cli import main

    real = run_module.trained_segments

    def one(store, split, labels):
        ds, left_out = real(store, split, labels)
        ds.rows, ds.labels, ds.last_start = ds.rows[:1], ds.labels[:1], ds.last_start[:1]
        return ds, left_out

    monkeypatch.setattr(run_module, "trained_segments", one)
    run, _ = motion_run
    e = run_module.evaluate_motion(run, split="test", device="cpu", repetitions=2, recognizer_epochs=2)
    assert e["segments"] == 1 and "generation" not in e and "at least 2" in e["generation_skipped"]
    assert np.isfinite(e["model"]["pose_rmse_per_joint"])
    assert main(["evaluate", str(run), "--split", "test", "--device", "cpu", "--repetitions", "2"]) == 0
    assert "generation (Table 4) not measured" in capsys.readouterr().out


def test_evaluate_refuses_a_split_of_labels_the_generator_never_trained_on(motion_run, capsys):
    """The micro store's val split is all `wave`, which its train split has none of: not scored silently."""
    from datagen.cli import main
    from training.motion.run import trained_segments

    run, _ = motion_run
    store = open_store_of(run)
    names = list(store.attrs["label_names"])
    with pytest.raises(InputError, match="never trained on them"):
        trained_segments(store, "val", len(names))
    assert main(["evaluate", str(run), "--split", "val", "--device", "cpu", "--repetitions", "2"]) != 0
    err = capsys.readouterr().err
    assert "wave" in err and "never trained" in err and "Traceback" not in err
    kept, left_out = trained_segments(store, "test", len(names))
    assert left_out == {} and len(kept) > 0


def test_the_posterior_latent_is_each_labels_gaussian_over_the_training_posteriors(motion_run, tmp_path):
    """The per-label fit equals its definition on the training segments' (μ, σ²), is cached beside
    the checkpoint, and samples drawn from it are reproducible and differ from the prior's."""
    from training.paper001.frames import pose_features
    from training.motion.data import labelled_segments
    from training.motion.run import label_latents, load_motion, sample_sequences

    run, _ = motion_run
    loaded = load_motion(run)
    module, meta, ckpt, store = loaded
    mean, std = label_latents(loaded, "posterior")
    assert label_latents(loaded, "prior") is None
    cache = ckpt.with_name(ckpt.name + ".latents.npz")
    assert cache.is_file()
    batch = next(iter(torch.utils.data.DataLoader(labelled_segments(store, "train"), batch_size=10_000)))
    x, _ = pose_features(batch)
    label = batch["label"][:, 0].long()
    with torch.no_grad():
        mu, logvar = module.model.encode(x, label)
    for lab in range(len(meta["labels"])):
        rows = label == lab
        if not rows.any():
            assert torch.equal(mean[lab], torch.zeros_like(mean[lab])) and torch.equal(std[lab], torch.ones_like(std[lab]))
            continue
        m = mu[rows].double()
        want_std = (m.var(0, unbiased=False) + logvar[rows].double().exp().mean(0)).sqrt()
        assert torch.allclose(mean[lab].double(), m.mean(0), atol=1e-5)
        assert torch.allclose(std[lab].double(), want_std, rtol=1e-4, atol=1e-6)
    again = label_latents(loaded, "posterior")  # from the cache: the same numbers
    assert torch.equal(again[0], mean) and torch.equal(again[1], std)
    a = sample_sequences(loaded, "walk", 2, 3)[0]
    assert np.array_equal(a, sample_sequences(loaded, "walk", 2, 3)[0])
    assert not np.allclose(a, sample_sequences(loaded, "walk", 2, 3, latent="prior")[0])
    with pytest.raises(InputError, match="--latent must be one of posterior, prior"):
        sample_sequences(loaded, "walk", 2, 3, latent="uniform")


def test_generation_metrics_on_known_features():
    """FID is 0 for one set against itself and grows with a shift; diversity of two points is their
    distance; multimodality averages within labels only."""
    from training.motion.recognition import diversity, frechet_distance, multimodality

    rng = np.random.default_rng(0)
    a = rng.normal(size=(500, 4))
    assert abs(frechet_distance(a, a)) < 1e-6
    assert abs(frechet_distance(a, a + 2.0) - 16.0) < 1e-3  # |Δμ|² = 4 x 2², equal covariances
    two = np.array([[0.0, 0.0], [3.0, 4.0]])
    assert diversity(two, 1000, rng) == pytest.approx(2.5, abs=0.3)  # pairs drawn with replacement: 0 or 5
    f = np.array([[0.0], [1.0], [100.0], [101.0]])
    assert multimodality(f, np.array([0, 0, 1, 1]), 2000, rng) == pytest.approx(0.5, abs=0.1)
    from training.motion.recognition import motion_speed

    still = torch.ones(2, 60, 147)
    still[..., -3:] = torch.linspace(0, 5, 60)[None, :, None]  # the root's travel is not the joints' speed
    assert motion_speed(still) == 0.0
    ramp = still.clone()
    ramp[..., :144] += 0.01 * torch.arange(60.0)[None, :, None]
    assert motion_speed(ramp) == pytest.approx(0.01, rel=1e-4)


def test_sampled_motions_are_library_motions_that_export(motion_run, tmp_path, capsys):
    from datagen.cli import main
    from datagen.motion.motion import Motion

    run, _ = motion_run
    out = tmp_path / "gen"
    assert main(["sample", "motion", str(run), "--label", "walk", "--count", "3", "--seed", "4", "--out", str(out)]) == 0
    files = sorted(out.glob("*.npz"))
    assert len(files) == 3
    m = Motion.load_npz(files[0])
    assert m.poses.shape == (3, 24, 3) and m.label_name == "walk" and np.isfinite(m.poses).all()
    assert np.allclose(m.trans[0], 0) and m.source["kind"] == "generated"
    again = tmp_path / "again"
    assert main(["sample", "motion", str(run), "--label", "walk", "--count", "3", "--seed", "4", "--out", str(again)]) == 0
    assert np.array_equal(Motion.load_npz(again / files[0].name).poses, m.poses)  # the seed decides
    longer = tmp_path / "longer"
    assert main(["sample", "motion", str(run), "--label", "walk", "--count", "1", "--frames", "20", "--out",
                 str(longer)]) == 0
    assert Motion.load_npz(next(longer.glob("*.npz"))).frame_count == 20
    bvh = tmp_path / "g.bvh"
    assert main(["motion", "export", str(files[0]), "--format", "bvh", "--out", str(bvh)]) == 0 and bvh.is_file()
    # every learned label in one call (the model loaded once): OUT/<label>/, the files one call per label writes
    learned = [n for n in json.loads((run / "run.json").read_text())["labels"]
               if n not in motion_run[1]["labels_without_training_segments"]]
    each = tmp_path / "each"
    assert main(["sample", "motion", str(run), "--label", "all", "--count", "3", "--seed", "4", "--out", str(each)]) == 0
    assert sorted(p.name for p in each.iterdir()) == sorted(learned)
    assert np.array_equal(Motion.load_npz(each / "walk" / files[0].name).poses, m.poses)


def test_bad_input_gets_one_clear_line(motion_run, tmp_path):
    from training.motion.run import load_motion, sample_motions

    run, result = motion_run
    unseen = result["labels_without_training_segments"]  # the micro store trains on a few of the 17 labels
    assert unseen and "walk" not in unseen
    with pytest.raises(InputError, match=f"label '{unseen[0]}' had no training segments in this run.*it learned: .*walk"):
        sample_motions(run, unseen[0], 2, 0, tmp_path / "a")
    with pytest.raises(InputError, match="'moonwalk' is not a motion label of this run's store; the model learned: "
                       ".*walk") as e:
        sample_motions(run, "moonwalk", 2, 0, tmp_path / "a")
    assert unseen[0] not in str(e.value).split("learned:")[1]  # only the labels it learned, not all 17
    with pytest.raises(InputError, match="'moonwalk' is not a motion label"):  # checked before writing walk
        sample_motions(run, "walk,moonwalk", 2, 0, tmp_path / "a")
    with pytest.raises(InputError, match="names no label"):
        sample_motions(run, ",", 2, 0, tmp_path / "a")
    with pytest.raises(InputError, match="--count must be 1 or more"):
        sample_motions(run, "walk", 0, 0, tmp_path / "a")
    with pytest.raises(InputError, match="--seed must be 0 or more"):
        sample_motions(run, "walk", 2, -1, tmp_path / "a")
    other = tmp_path / "gnn-run"
    other.mkdir()
    (other / "run.json").write_text(json.dumps({"kind": "gnn"}))
    with pytest.raises(InputError, match="holds a 'gnn' model, not paper 001's motion generator"):
        load_motion(other)
    with pytest.raises(ConfigError, match="multiple of heads"):
        MotionConfig(d_model=30, heads=4)
    assert not (tmp_path / "a").exists()


def test_sted_is_zero_for_rigid_motion_and_grows_with_stretch():
    from training.paper001.sted import mesh_edges, sted

    rng = np.random.default_rng(1)
    verts = torch.as_tensor(rng.normal(size=(40, 3)), dtype=torch.float32)
    faces = np.array([[i, (i + 1) % 40, (i + 7) % 40] for i in range(40)])
    edges = torch.as_tensor(mesh_edges(faces))
    T = 5
    true = torch.stack([verts + torch.tensor([0.1 * t, 0.0, 0.0]) for t in range(T)])[None]
    rot = torch.tensor([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    rigid = true @ rot.T + 0.3  # the same motion turned and moved: same edge lengths, same steps
    assert sted(rigid, true, edges)["sted"].item() < 1e-5
    stretched = true.clone()
    stretched[..., 0] *= 1.2  # stretched along x: relative edge changes differ between edges
    s = sted(stretched, true, edges)
    assert s["spatial"].item() > 0.01 and s["temporal"].item() > 0.01
    more = true.clone()
    more[..., 0] *= 1.5
    assert sted(more, true, edges)["sted"].item() > s["sted"].item()


def test_each_body_motion_counts_once_whatever_the_garments(train_store):
    """The micro store's train split simulates walk:0 on two bodies under two garments (8 sample
    segments); the generator reads the motion tables instead: one segment per (motion, body, first
    frame), 4, every key of the split once, with the poses and translations the samples recorded."""
    from datagen.store import open_store
    from training.motion.data import labelled_segments

    store = open_store(train_store)
    every = store.split_segments("train")
    ds = labelled_segments(store, "train")
    idx, seg = store.index, store.index["segments"]

    def key(k):
        return int(idx["motion"][seg[k, 0]]), int(idx["body"][seg[k, 0]]), int(seg[k, 1])

    assert len(every) == 8 and len(ds) == 4
    assert sorted(map(tuple, ds.rows.tolist())) == sorted(set(map(key, every)))
    for k in every:  # each sample segment (under either garment) holds its motion segment's poses
        m, b, t0 = key(k)
        got = ds[[tuple(r) for r in ds.rows.tolist()].index((m, b, t0))]
        sample = store.segment(int(k), names=("pose", "trans", "label"))
        for name in ("pose", "trans", "label"):
            np.testing.assert_array_equal(got[name].numpy(), sample[name])
        assert int(got["body"]) == b


def synthetic_batch(n: int, labels: int, device) -> tuple[dict, dict]:
    """A random SMPL-format body (24 joints, 60 vertices) and a batch of ``n`` random 60-frame
    segments on it, as the store's reader gives them."""
    g = torch.Generator().manual_seed(0)
    V = 60
    parents = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
    weights = torch.rand(V, 24, generator=g)
    body = {"parents": parents, "v_template": torch.randn(V, 3, generator=g).numpy(),
            "shapedirs": (0.01 * torch.randn(V, 3, 10, generator=g)).numpy(),
            "J_regressor": torch.softmax(torch.randn(24, V, generator=g), 1).numpy(),
            "weights": (weights / weights.sum(1, keepdim=True)).numpy()}
    batch = {"pose": 0.3 * torch.randn(n, 60, 24, 3, generator=g), "trans": 0.1 * torch.randn(n, 60, 3, generator=g),
             "label": torch.randint(0, labels, (n, 1), generator=g).expand(n, 60).contiguous(),
             "body": torch.zeros(n, dtype=torch.long)}
    return body, {k: v.to(device) for k, v in batch.items()}


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA device: the training step is a CUDA graph only there")
def test_the_graphed_training_step_gives_the_eager_gradients(monkeypatch):
    """``MotionConfig.cuda_graph``: the forward and backward pass replayed from the captured graph
    writes the same gradients into the parameters as an eager backward (float32, dropout 0, the
    latent's noise set to zero so that both passes see the same numbers), for three batches in a row."""
    from training.motion.module import MotionModule

    monkeypatch.setattr(torch, "randn_like", torch.zeros_like)
    cfg = MotionConfig(**{**SMALL, "dropout": 0.0, "vertex_stride": 1}).as_dict()
    torch.manual_seed(0)
    body, _ = synthetic_batch(1, 5, "cpu")
    graphed = MotionModule(cfg, 5, body, np.zeros((1, 10))).cuda()
    eager = MotionModule(cfg, 5, body, np.zeros((1, 10))).cuda()
    eager.load_state_dict(graphed.state_dict())
    for k in range(3):
        _, batch = synthetic_batch(cfg["batch_size"], 5, "cuda")
        batch["pose"] = batch["pose"] * (1 + k)
        for m in (graphed, eager):
            for p in m.parameters():
                if p.grad is not None:
                    p.grad.zero_()
        loss_g = graphed._graph_losses(batch)["loss"]  # the replay runs the backward pass too
        loss_e = eager.losses(batch)["loss"]
        loss_e.backward()
        assert torch.allclose(loss_g, loss_e.detach(), rtol=1e-4), k
        for (name, pg), pe in zip(graphed.named_parameters(), eager.parameters()):
            assert torch.allclose(pg.grad, pe.grad, rtol=1e-3, atol=1e-6), (k, name)


def test_training_crops_each_motion_at_random_from_the_seed_and_epoch(train_store):
    """Training windows are random crops of the (motion, body) pairs (ACTOR's cropping), drawn from
    (seed, epoch) alone: the order is EpochSampler's, the same epoch gives the same crops (a resumed
    run draws what it would have), other epochs other crops, and every crop lies inside its motion."""
    from datagen.store import open_store
    from training.datamodule import CropSampler, EpochSampler
    from training.paper001.data import MotionSegmentDataset

    store = open_store(train_store)
    ds = MotionSegmentDataset(store, "train")
    L = store.segment_length
    recorded = store.motions()["pose"].shape[1]
    sampler = CropSampler(len(ds), seed=3)
    sampler.set_epoch(5)
    first = list(sampler)
    plain = EpochSampler(len(ds), 3)
    plain.set_epoch(5)
    assert [k for k, _ in first] == list(plain)  # the same order as the fixed windows' sampler
    assert list(sampler) == first  # a function of (seed, epoch)
    starts = set()
    for epoch in range(6):
        sampler.set_epoch(epoch)
        for k, u in sampler:
            item = ds[(k, u)]
            m, b, _ = (int(v) for v in ds.rows[k])
            t0 = int(item["first_frame"])
            assert int(item["motion"]) == m and int(item["body"]) == b and 0 <= t0 <= recorded - L
            fixed = store.motion_segment(m, b, t0)
            assert np.array_equal(item["pose"].numpy(), fixed["pose"])
            starts.add(t0)
    assert len(starts) > len({int(r[2]) for r in ds.rows})  # starts between the fixed windows' too
    assert int(ds[0]["first_frame"]) == int(ds.rows[0][2])  # an index alone is the fixed window


def test_the_kl_term_is_actors_sum_over_the_batch(train_store):
    """L_KL is summed over the latent dimensions and the batch (ACTOR's compute_kl_loss), the
    reconstruction terms are means: for a full batch the loss is L_P + L_V^B + λ_KL Σ_batch KL."""
    from datagen.store import open_store
    from training.motion.module import MotionModule, motion_losses
    from training.paper001.data import MotionSegmentDataset

    store = open_store(train_store)
    config = MotionConfig(**{**SMALL, "batch_size": 2, "kl_weight": 0.5})
    ds = MotionSegmentDataset(store, "train")
    module = MotionModule(config, len(store.attrs["label_names"]), store.body_model(), store.betas())
    batch = next(iter(torch.utils.data.DataLoader(ds, batch_size=2)))
    torch.manual_seed(0)
    r = motion_losses(module.model, module.body, module.betas, batch, config)
    torch.manual_seed(0)
    from training.paper001.frames import pose_features

    x, _ = pose_features(batch)
    _, mu, logvar = module.model(x, batch["label"][:, 0].long())
    actor = -0.5 * torch.sum(1 + logvar - mu.pow(2) - logvar.exp())  # ACTOR: over the batch and the dimensions
    assert float(r["kl"]) == pytest.approx(float(actor) / 2, rel=1e-5)
    assert float(r["loss"]) == pytest.approx(float(r["pose"] + r["vertex"] + 0.5 * actor), rel=1e-5)


def test_paper_001s_models_train_with_weight_decay_and_the_gnn_without():
    """Paper 001's "L2" is AdamW's decay at ACTOR's 0.01 for both of its models; the GNN keeps Adam;
    a run stored before the field existed trained without decay."""
    from training.garment.config import GarmentConfig
    from training.gnn.config import GNNConfig
    from training.loop import plateau_optimizer

    params = [torch.nn.Parameter(torch.zeros(3))]
    for config in (MotionConfig(), GarmentConfig()):
        opt = plateau_optimizer(None, params, config, "val/loss")["optimizer"]
        assert isinstance(opt, torch.optim.AdamW) and opt.defaults["weight_decay"] == 0.01
    opt = plateau_optimizer(None, params, GNNConfig(), "val/loss")["optimizer"]
    assert type(opt) is torch.optim.Adam and opt.defaults["weight_decay"] == 0
    assert MotionConfig.from_dict({}).weight_decay == 0.0 and GarmentConfig.from_dict({}).weight_decay == 0.0
