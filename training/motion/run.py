"""Train, evaluate and sample paper 001's motion generator from a store's 60-frame segments.

- :func:`train_motion`: the labelled segments (``label >= 0``: unlabelled mocap is skipped) of the
  train split's motions, from the store's motion tables (every motion of the config, whether its
  scenes passed or failed), the checkpoint chosen on the validation split's loss, through the
  shared loop.
- :func:`evaluate_motion`: Table 3's reconstruction figures on a split's unseen segments (the
  posterior mean decoded): RMSE of the pose parameters (axis-angle, rad) and of the body vertices
  (m), the Hausdorff distance between predicted and true vertex sets (m, mean over frames), STED
  on the whole body mesh (:mod:`training.paper001.sted`, mean over segments), beside
  a trivial baseline (every frame the label's mean pose over the training segments, the true
  translation), a static oracle (every frame the test segment's own mean pose, the true
  translation: what a model that has learned each sequence's pose but none of its motion scores)
  and a copy (the nearest training segment of the label: how far the split's motions lie from the
  training set). Both RMSEs are named: per coordinate and per joint / vertex (Euclidean). Segments
  of labels the run never trained on are counted, not scored; Table 4 needs two segments.
- :func:`sample_motions`: new motions of a label, as the motion library's ``.npz``.
- :func:`label_latents`: where samples come from. ``prior`` is the paper's Z ~ N(0, I);
  ``posterior`` a Gaussian per label fitted to the training segments' posteriors (mean of μ; variance
  of μ plus mean σ², per dimension), a density estimate made after training (Ghosh et al. 2020,
  "From variational to deterministic autoencoders"): with λ_KL = 1e-5 the posteriors need not fill
  N(0, I), and samples from the prior then land where the decoder was never trained.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from datagen.errors import InputError
from datagen.store import open_store
from training.checkpoint import load_module, run_store
from training.loop import (apply_threads, fit, prepare_run, resolve_device, run_checkpoint, seed_everything,
                           store_identity, write_summary)
from training.motion.config import MotionConfig
from training.motion.data import MotionDataModule, labelled_segments
from training.paper001.data import MotionSegmentDataset

KIND = "motion"
LATENTS = ("posterior", "prior")


def train_motion(data: str | Path, out: str | Path, config: MotionConfig, *, device: str = "auto",
                 resume: bool = False, force: bool = False) -> dict[str, Any]:
    """Train the motion generator on ``data``'s train split, choosing the checkpoint on its val split."""
    from training.motion.module import MotionModule

    resolve_device(device)
    apply_threads(config)
    store = open_store(data)
    segments = MotionDataModule(store, config)
    segments.setup()
    labels = segments.labels
    unseen = [name for name, c in zip(labels, train_label_counts(store, len(labels))) if c == 0]
    meta = {"kind": KIND, "config": config.as_dict(), "labels": labels, "store": store_identity(store),
            **{k: v for k, v in segments.run_meta().items() if k != "labels"}}
    out = prepare_run(out, resume=resume, force=force, meta=meta)
    seed_everything(config.seed)
    module = MotionModule.from_data(config, segments)
    t0 = time.perf_counter()
    result = fit(module, segments, config, out, device=device, resume=resume, monitor="val/loss")
    result |= {"seconds": time.perf_counter() - t0, **segments.summary(),
               "parameters": sum(p.numel() for p in module.model.parameters()),
               "labels_without_training_segments": unseen}
    write_summary(out, result)
    return result


def load_motion(run: str | Path, *, checkpoint: str = "best", data: str | Path | None = None):
    """(module on the CPU in eval mode, run metadata, checkpoint path) of a motion run."""
    from training.motion.module import MotionModule

    meta, path = run_checkpoint(run, KIND, "paper 001's motion generator", checkpoint=checkpoint)
    store = run_store(meta, run, data)
    module = load_module(MotionModule, path, "paper 001's motion generator", body=store.body_model(), betas=store.betas())
    return module, meta, path, store


def _split_tensors(store, split: str, device, labels: int | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """Frame features [N, T, 147] and labels [N] of a split's labelled segments (with ``labels``,
    the run's label count: only those of labels the run has training segments of,
    :func:`trained_segments`)."""
    from training.paper001.frames import pose_features

    ds = labelled_segments(store, split) if labels is None else trained_segments(store, split, labels)[0]
    xs, ys = [], []
    for batch in torch.utils.data.DataLoader(ds, batch_size=64, shuffle=False):
        xs.append(pose_features(batch)[0])
        ys.append(batch["label"][:, 0].long())
    return torch.cat(xs).to(device), torch.cat(ys).to(device)


def trained_segments(store, split: str, labels: int) -> tuple[MotionSegmentDataset, dict[int, int]]:
    """The split's labelled segments of the labels the train split has segments of, and the segments
    left out per label that it has none of ({label: segments}): a generator cannot have learned a
    label it never saw, so evaluation reports those segments instead of scoring them. A split with
    none left is refused in one line."""
    ds = labelled_segments(store, split)
    counts = train_label_counts(store, labels)
    keep = counts[ds.labels] > 0
    left_out = {int(k): int((ds.labels == k).sum()) for k in np.unique(ds.labels[~keep])}
    if not keep.any():
        names = list(store.attrs.get("label_names") or [])
        raise InputError(f"every labelled segment of the {split} split of {store.path} has a label the train split "
                         f"has no segment of ({', '.join(names[k] if k < len(names) else str(k) for k in left_out)}): "
                         "the generator never trained on them, so there is nothing to evaluate")
    ds.rows, ds.labels, ds.last_start = ds.rows[keep], ds.labels[keep], ds.last_start[keep]
    return ds, left_out


MIN_GENERATION_SEGMENTS = 2
"""Table 4 needs at least this many test segments: FID compares covariances of the features, and
one segment has none (scipy's square root then failed on NaN: issue 62)."""


def evaluate_motion(run: str | Path, *, data: str | Path | None = None, split: str = "test", device: str = "auto",
                    generation: bool = True, repetitions: int = 20, recognizer_epochs: int = 100) -> dict[str, Any]:
    """Table 3 (reconstruction, beside the still and copied baselines) and, with ``generation``,
    Table 4 (:mod:`training.motion.recognition`, beside :mod:`training.paper001.baselines`' still and
    copy generators) on ``split``'s segments of labels the run trained on (the others are counted
    in ``untrained_labels``, not scored); JSON-able. Every figure is on the whole body mesh,
    whatever ``vertex_stride`` the run trained with."""
    if generation and repetitions < 2:
        raise InputError(f"--repetitions must be 2 or more (the spread needs two), got {repetitions}")
    loaded = load_motion(run, data=data)  # once: the checkpoint and the store serve both tables
    dev = torch.device("cuda" if resolve_device(device) == "gpu" else "cpu")
    e = _reconstruction(loaded, split, dev)
    if generation and e["segments"] < MIN_GENERATION_SEGMENTS:
        e["generation_skipped"] = (f"the {split} split has {e['segments']} segment(s) of trained labels; Table 4 "
                                   f"needs at least {MIN_GENERATION_SEGMENTS} (FID compares feature covariances)")
    elif generation:
        from datagen.geometry.rotations import axis_angle_to_matrix
        from training.paper001.baselines import copy_generator, still_generator
        from training.motion.recognition import generation_metrics, train_recognizer

        module, meta, _, store = loaded
        labels = len(meta["labels"])
        x_train, y_train = _split_tensors(store, "train", dev)
        x_test, y_test = _split_tensors(store, split, dev, labels)
        torch.manual_seed(0)
        recognizer = train_recognizer(x_train, y_train, labels, epochs=recognizer_epochs, seed=0)
        frames = x_test.shape[1]

        for latent in LATENTS:
            fitted = label_latents(loaded, latent, device=dev)

            def generate(lab, g, fitted=fitted):
                return module.model.sample(lab, frames, generator=g, latent=fitted).float()

            key = "generation" if latent == "prior" else f"generation_{latent}"
            e[key] = generation_metrics(recognizer, generate, x_test, y_test, x_train, repetitions=repetitions)
            e[key] |= {"recognizer_epochs": recognizer_epochs, "latent": latent}
        mean = axis_angle_to_matrix(_mean_poses(labelled_segments(store, "train"), labels)).to(dev)
        e["generation_baselines"] = {
            name: generation_metrics(recognizer, gen, x_test, y_test, x_train, repetitions=repetitions)["generated"]
            for name, gen in (("still", still_generator(mean, frames)), ("copy", copy_generator(x_train, y_train)))}
    return e


def _checkpoint_stamp(ckpt: Path) -> str:
    st = ckpt.stat()
    return f"{ckpt.name}:{st.st_size}:{st.st_mtime_ns}"


def label_gaussians(mu: torch.Tensor, logvar: torch.Tensor, label: torch.Tensor, labels: int) -> dict[str, np.ndarray]:
    """Each label's Gaussian over posteriors (μ, log σ²) [N, d] of classes ``label`` [N]: ``mean``
    [labels, d] (mean of μ), ``std`` [labels, d] (sqrt of the variance of μ plus the mean σ², per
    dimension) and ``count`` [labels]; a label without segments gets N(0, I)."""
    mu, sig2, label = mu.double().cpu(), logvar.double().exp().cpu(), label.cpu()
    d = mu.shape[1]
    mean, std = torch.zeros(labels, d, dtype=torch.float64), torch.ones(labels, d, dtype=torch.float64)
    count = torch.bincount(label, minlength=labels)
    for k in torch.nonzero(count).flatten().tolist():
        rows = label == k
        mean[k] = mu[rows].mean(0)
        std[k] = (mu[rows].var(0, unbiased=False) + sig2[rows].mean(0)).sqrt()
    return {"mean": mean.float().numpy(), "std": std.float().numpy(), "count": count.numpy()}


@torch.no_grad()
def fit_latents(module, store, device=None) -> dict[str, np.ndarray]:
    """:func:`label_gaussians` of the training split's posteriors under ``module``'s encoder."""
    from training.paper001.frames import pose_features

    dev = device or torch.device("cpu")
    module.to(dev)
    mus, logvars, labels = [], [], []
    for batch in torch.utils.data.DataLoader(labelled_segments(store, "train"), batch_size=64, shuffle=False):
        batch = {k: v.to(dev) for k, v in batch.items()}
        x, _ = pose_features(batch)
        label = batch["label"][:, 0].long()
        mu, logvar = module.model.encode(x, label)
        mus.append(mu.float().cpu()), logvars.append(logvar.float().cpu()), labels.append(label.cpu())
    return label_gaussians(torch.cat(mus), torch.cat(logvars), torch.cat(labels), module.model.labels)


def train_label_counts(store, labels: int) -> np.ndarray:
    """Labelled training segments per label [labels], from the store's index and motion table."""
    return np.bincount(labelled_segments(store, "train").labels, minlength=labels)


def _posterior_fit(loaded, device=None) -> dict[str, np.ndarray]:
    """:func:`fit_latents` of a loaded run, cached beside its checkpoint (refitted when it changes)."""
    module, _, ckpt, store = loaded
    cache = ckpt.with_name(ckpt.name + ".latents.npz")
    stamp = _checkpoint_stamp(ckpt)
    if cache.is_file():
        with np.load(cache) as z:
            if str(z["stamp"]) == stamp:
                return {k: z[k] for k in ("mean", "std", "count")}
    fit = fit_latents(module, store, device)
    tmp = cache.with_name(cache.name + ".tmp.npz")
    try:
        np.savez(tmp, stamp=np.array(stamp), **fit)
        tmp.replace(cache)
    except OSError:  # a read-only run directory: use the fit without caching it
        tmp.unlink(missing_ok=True)
    return fit


def check_latent(latent: str) -> None:
    if latent not in LATENTS:
        raise InputError(f"--latent must be one of {', '.join(LATENTS)}, got {latent!r}")


def label_latents(loaded, latent: str, *, device=None) -> tuple[torch.Tensor, torch.Tensor] | None:
    """What ``MotionCVAE.sample`` draws Z from for ``latent`` (see the module docstring): None for
    ``prior``; for ``posterior`` the per-label fit of :func:`fit_latents`, cached beside the
    checkpoint (``<checkpoint>.latents.npz``, refitted when the checkpoint changes)."""
    check_latent(latent)
    if latent == "prior":
        return None
    fit = _posterior_fit(loaded, device)
    return torch.as_tensor(fit["mean"]), torch.as_tensor(fit["std"])


@torch.no_grad()
def _reconstruction(loaded, split: str, dev: torch.device) -> dict[str, Any]:
    """Reconstruction on ``split`` (see the module docstring) for the model and the baselines; JSON-able.

    Every vertex figure is on the whole body mesh (13,348 vertices; the run's ``vertex_stride``, a
    training setting, does not change them). RMSEs are given twice, named: per coordinate (the root
    of the mean squared coordinate error) and per joint / per vertex (the root of the mean squared
    Euclidean distance, √3 times the first); paper 001's Table 3 does not say which it reports."""
    from datagen.geometry.rotations import axis_angle_to_matrix, matrix_to_axis_angle
    from training.metrics import hausdorff, rmse
    from training.paper001.baselines import nearest_training_segments
    from training.motion.recognition import motion_speed
    from training.paper001.body import BodyLayer
    from training.paper001.frames import features_to_frames, pose_features
    from training.paper001.sted import mesh_edges, sted

    module, meta, ckpt, store = loaded
    module.to(dev)
    labels = len(meta["labels"])
    body_arrays = store.body_model()
    full = BodyLayer(body_arrays, 1).to(dev)  # every figure on the whole mesh
    edges = torch.as_tensor(mesh_edges(body_arrays["faces"]), device=dev)

    def posed(rot, trans, body):
        B, T = rot.shape[:2]
        v = full(rot.reshape(B * T, 24, 3, 3), trans.reshape(B * T, 3), module.betas[body].repeat_interleave(T, 0))
        return v.reshape(B, T, -1, 3)
    test, untrained = trained_segments(store, split, labels)
    train = labelled_segments(store, "train")
    mean_pose = _mean_poses(train, labels).to(dev)
    x_train, y_train = _split_tensors(store, "train", dev)
    train_pose = torch.stack([train[k]["pose"] for k in range(len(train))]).float().to(dev)  # [M, T, 24, 3]
    rows = ("model", "mean_pose_baseline", "own_mean_pose", "nearest_training_segment")
    sums = {r: {"pose_sq": 0.0, "vertex_sq": 0.0, "hausdorff": 0.0, "sted": 0.0} for r in rows}
    speed = {"model": [], "real": []}  # Table 4's speed of the reconstructions and of the true segments
    counts = {"joints": 0, "vertices": 0, "frames": 0, "segments": 0}
    for batch in torch.utils.data.DataLoader(test, batch_size=8, shuffle=False):
        batch = {k: v.to(dev) for k, v in batch.items()}
        x, rot = pose_features(batch)
        label = batch["label"][:, 0].long()
        mu, _ = module.model.encode(x, label)
        recon = module.model.decode(mu, label, x.shape[1]).float()
        prot, ptrans = features_to_frames(recon)
        speed["model"].append(motion_speed(recon) * len(x))
        speed["real"].append(motion_speed(x) * len(x))
        body = batch["body"].long()
        pose_true = batch["pose"].float()
        B, T = rot.shape[:2]
        label_mean = mean_pose[label][:, None].expand_as(pose_true)  # the label's mean training pose
        own_mean = pose_true.mean(1, keepdim=True).expand_as(pose_true)  # the segment's own mean pose, held
        near = nearest_training_segments(x, label, x_train, y_train)
        copied = train_pose[near]  # the nearest training segment of the label, its own translation
        candidates = {"model": (matrix_to_axis_angle(prot), prot, ptrans),
                      "mean_pose_baseline": (label_mean, axis_angle_to_matrix(label_mean), x[..., -3:]),
                      "own_mean_pose": (own_mean, axis_angle_to_matrix(own_mean), x[..., -3:]),
                      "nearest_training_segment": (copied, axis_angle_to_matrix(copied), x_train[near][..., -3:])}
        v_true = posed(rot, x[..., -3:], body)
        flat = (B * T, -1, 3)
        for name, (aa, r, tr) in candidates.items():
            v = posed(r, tr, body)
            acc = sums[name]
            acc["pose_sq"] += float(((aa - pose_true) ** 2).sum())
            acc["vertex_sq"] += float(((v - v_true) ** 2).sum())
            acc["hausdorff"] += float(hausdorff(v.reshape(flat), v_true.reshape(flat)).sum())
            acc["sted"] += float(sted(v, v_true, edges)["sted"].sum())
        counts["joints"] += pose_true.numel() // 3
        counts["vertices"] += v_true.numel() // 3
        counts["frames"] += B * T
        counts["segments"] += B
    out = {r: {**rmse(sums[r]["pose_sq"], counts["joints"], "pose", "joint"),
               **rmse(sums[r]["vertex_sq"], counts["vertices"], "vertex", "vertex"),
               "hausdorff": sums[r]["hausdorff"] / counts["frames"], "sted": sums[r]["sted"] / counts["segments"]}
           for r in rows}
    out["model"]["speed"] = sum(speed["model"]) / counts["segments"]
    out["real_speed"] = sum(speed["real"]) / counts["segments"]  # the static rows' speed is 0
    names = meta["labels"]
    return {"kind": KIND, "split": split, "checkpoint": str(ckpt), "segments": len(test),
            "frames": counts["frames"], "body_vertices": int(full.keep.numel()),
            "untrained_labels": {names[k]: n for k, n in untrained.items()}, **out}


def _mean_poses(ds: MotionSegmentDataset, labels: int) -> torch.Tensor:
    """Each label's mean axis-angle pose [labels, 24, 3] over the segments of ``ds`` (zeros if absent)."""
    sums, counts = torch.zeros(labels, 24, 3), torch.zeros(labels)
    for k in range(len(ds)):
        s = ds[k]
        lab = int(s["label"][0])
        sums[lab] += s["pose"].float().mean(0)
        counts[lab] += 1
    return sums / counts.clamp(min=1)[:, None, None]


def format_motion_evaluation(e: dict) -> str:
    lines = [f"{e['split']} split: {e['segments']} segments, {e['frames']} frames (vertex figures on all "
             f"{e.get('body_vertices', '?')} body vertices)"]
    if e.get("untrained_labels"):
        lines.append("left out, not scored: " + ", ".join(f"{n} segment(s) of {name}" for name, n in
                                                          e["untrained_labels"].items())
                     + " (labels the generator never trained on: the train split has no segment of them)")
    lines += ["", "reconstruction (paper 001 Table 3); RMSE per coordinate, and per joint / per vertex (Euclidean, "
                  "√3 x the first):",
              f"{'':34s} {'pose RMSE x1e-2':>16s} {'per joint':>10s} {'vertex RMSE x1e-2 m':>20s} {'per vertex':>11s} "
              f"{'Hausdorff x1e-1 m':>18s} {'STED x1e-2':>11s}"]
    named = [("model", "model"), ("label's mean pose (still)", "mean_pose_baseline"),
             ("segment's own mean pose (still)", "own_mean_pose"),
             ("nearest training segment (copy)", "nearest_training_segment")]
    for name, key in named:
        r = e.get(key)
        if r is None:
            continue
        lines.append(f"{name:34s} {100 * r['pose_rmse_per_coordinate']:16.3f} {100 * r['pose_rmse_per_joint']:10.3f} "
                     f"{100 * r['vertex_rmse_per_coordinate']:20.3f} {100 * r['vertex_rmse_per_vertex']:11.3f} "
                     f"{10 * r['hausdorff']:18.3f} {100 * r['sted']:11.3f}")
    m = e["model"]
    if "speed" in m and e.get("real_speed"):
        lines.append(f"speed of the reconstructions (Table 4's measure): {1000 * m['speed']:.3f}e-3 against "
                     f"{1000 * e['real_speed']:.3f}e-3 for the true segments ({m['speed'] / e['real_speed']:.2f}x); the "
                     "still rows hold their pose")
    if e.get("generation_skipped"):
        lines += ["", f"generation (Table 4) not measured: {e['generation_skipped']}"]
    g = e.get("generation")
    if g:
        lines += ["", f"generation (Table 4; {g['repetitions']} generated sets, mean ± 95 % interval; recogniser: "
                      f"GRU trained {g['recognizer_epochs']} epochs on the train split, {100 * g['recognizer_test_accuracy']:.1f} % "
                      "on the real test motions; Z from N(0, I), the paper's prior, and from each label's Gaussian "
                      "fitted to the training posteriors; beside them a still and a copying generator):",
                  f"{'':34s} {'FID':>16s} {'accuracy %':>16s} {'diversity':>16s} {'multimodality':>16s} "
                  f"{'speed (x1e-3)':>16s}"]
        rows = [("real test motions", g["real"]), ("generated, prior", g["generated"])]
        if e.get("generation_posterior"):
            rows.append(("generated, posterior", e["generation_posterior"]["generated"]))
        base = e.get("generation_baselines") or {}
        if "still" in base:
            rows.append(("still: label's mean pose", base["still"]))
        if "copy" in base:
            rows.append(("copy: a training segment", base["copy"]))
        for name, r in rows:
            cells = []
            for k in ("fid", "accuracy", "diversity", "multimodality", "speed"):
                if k not in r:  # an evaluation written before speed was measured
                    continue
                scale = {"accuracy": 100, "speed": 1000}.get(k, 1)
                cells.append(f"{scale * r[k]['mean']:9.3f}±{scale * r[k]['interval']:<6.3f}")
            lines.append(f"{name:34s} " + " ".join(f"{c:>16s}" for c in cells))
    return "\n".join(lines)


def sample_motions(run: str | Path, label: str, count: int, seed: int, out: str | Path, *,
                   device: str = "cpu", frames: int | None = None, latent: str = "posterior") -> list[Path]:
    """``count`` new motions of ``label`` from a trained generator, written into the directory ``out``
    as the motion library's ``.npz`` (readable by ``drape motion export``); returns the paths.
    ``label`` may name several labels, comma-separated, or be ``all`` (every label the run learned):
    the model is loaded once and each label's motions go into ``out/<label>/``, the same files that
    one call per label with the same seed writes. Every label is checked before anything is written."""
    from datagen.motion.motion import Motion

    if count < 1:
        raise InputError(f"--count must be 1 or more, got {count}")
    if seed < 0:
        raise InputError(f"--seed must be 0 or more, got {seed}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} is a file; give a directory for the motions")
    if not out.parent.is_dir():
        raise InputError(f"--out {out}: the folder {out.parent} does not exist; create it first")
    check_latent(latent)  # before the checkpoint is loaded
    loaded = load_motion(run)
    _, meta, ckpt, store = loaded
    many = label == "all" or "," in label
    if label == "all":
        counts = train_label_counts(store, len(meta["labels"]))
        names = [name for name, c in zip(meta["labels"], counts) if c > 0]
    else:
        names = [name.strip() for name in label.split(",") if name.strip()]
        if not names:
            raise InputError(f"--label {label!r} names no label; give one, several separated by commas, or all")
    for name in names:  # every label refused before anything is written
        check_label(loaded, name)
    paths = []
    for name in names:
        poses, trans, fps = sample_sequences(loaded, name, count, seed, device=device, frames=frames, latent=latent)
        code = meta["labels"].index(name)
        dest = out / name if many else out
        dest.mkdir(parents=True, exist_ok=True)
        for k in range(count):
            motion = Motion(poses=poses[k], trans=trans[k], fps=fps, label=code, label_name=name,
                            source={"kind": "generated", "model": KIND, "run": str(Path(run).resolve()),
                                    "checkpoint": ckpt.name, "seed": int(seed), "index": k, "latent": latent})
            path = dest / f"{name}_{seed}_{k:03d}.npz"
            motion.save_npz(path)
            paths.append(path)
    return paths


def check_label(loaded, label: str) -> None:
    """Refuse, in one line, a label the loaded run was not trained on or saw no training segment of."""
    _, meta, _, store = loaded
    labels = meta["labels"]
    counts = train_label_counts(store, len(labels))
    seen = [name for name, c in zip(labels, counts) if c > 0]
    if label not in labels:
        # the run's label set is the store's (all of them); only those with training segments were learned
        raise InputError(f"{label!r} is not a motion label of this run's store; the model learned: {', '.join(seen)}")
    if counts[labels.index(label)] == 0:
        raise InputError(f"label {label!r} had no training segments in this run (no motion of the store's train "
                         f"split has it), so the generator cannot make it; it learned: {', '.join(seen)}")


@torch.no_grad()
def sample_sequences(run, label: str, count: int, seed: int, *, device: str = "cpu",
                     frames: int | None = None, latent: str = "posterior") -> tuple[np.ndarray, np.ndarray, float]:
    """``count`` new motions of ``label`` from a run directory (or what :func:`load_motion` returned
    for it, to load the checkpoint once): poses [count, T, 24, 3] (axis-angle), translations
    [count, T, 3] starting at the origin, and the frame rate; reproducible from ``seed``. ``frames``
    (default: the segment length it was trained on) may ask for longer motions: the decoder's
    positions extend, but it has only learned the trained length. ``latent``: ``posterior`` (the
    per-label fit, default) or ``prior`` (N(0, I), the paper's), :func:`label_latents`."""
    from datagen.geometry.rotations import matrix_to_axis_angle
    from training.paper001.frames import features_to_frames

    if count < 1:
        raise InputError(f"--count must be 1 or more, got {count}")
    if seed < 0:
        raise InputError(f"--seed must be 0 or more, got {seed}")
    loaded = load_motion(run) if isinstance(run, (str, Path)) else run
    module, meta, _, _ = loaded
    labels = meta["labels"]
    check_label(loaded, label)
    if frames is not None and not 1 <= frames <= 100000:
        raise InputError(f"--frames must be between 1 and 100000, got {frames}")
    dev = torch.device("cuda" if resolve_device(device) == "gpu" else "cpu")
    fitted = label_latents(loaded, latent, device=dev)
    module.to(dev)
    g = torch.Generator().manual_seed(int(seed))
    x = module.model.sample(torch.full((count,), labels.index(label), dtype=torch.long, device=module.device),
                            frames or meta["frames"], generator=g, latent=fitted).float()
    rot, trans = features_to_frames(x)
    poses = matrix_to_axis_angle(rot).cpu().numpy().astype(np.float64)
    trans = (trans - trans[:, :1]).cpu().numpy().astype(np.float64)  # every motion starts at the origin
    return poses, trans, float(meta["fps"])
