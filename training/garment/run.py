"""Train and evaluate paper 001's garment regressor on one garment template of a store
(:mod:`training.garment.data`). :func:`evaluate_garment` gives Tables 6/7/9's figures on a split's unseen
segments, decoded greedily from the poses alone: RMSE of the vertices (m; per coordinate and per
vertex, named), Hausdorff distance (m, mean over frames), STED (:mod:`training.paper001.sted`), the
cosine similarity of vertex normals and the share of garment vertices inside the posed body (eq.
4's test; also of the simulated garment), beside two trivial baselines: the template skinned to the
pose (the store's derived ``skin`` plus the translation) and a copy (the simulated garment of the
training segment whose poses are nearest, an oracle retrieval: how far the split lies from the
training set).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from datagen.errors import InputError
from datagen.store import open_store
from training.garment.config import GarmentConfig
from training.garment.data import GarmentDataModule, template_segments
from training.checkpoint import load_module, run_store
from training.loop import (apply_threads, fit, prepare_run, resolve_device, run_checkpoint, seed_everything,
                           store_identity, write_summary)
from training.paper001.data import SegmentDataset

KIND = "garment"


def _pretrain_bos(module, ds: SegmentDataset, config: GarmentConfig, device) -> list[float]:
    """Fit the BOS MLP to each training sequence's last frame (§4.2); returns the loss per epoch."""
    model = module.model
    if model.bos is None or config.bos_epochs == 0:
        return []
    batch = next(iter(torch.utils.data.DataLoader(ds, batch_size=len(ds))))
    x, g = module.targets(batch)
    x, last = x.to(device), g[:, -1].to(device)
    model.bos.to(device)
    for p in model.bos.parameters():
        p.requires_grad_(True)
    opt = torch.optim.Adam(model.bos.parameters(), lr=config.lr)
    losses = []
    for _ in range(config.bos_epochs):
        loss = torch.nn.functional.mse_loss(model.bos_frame(x), last)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.detach().item())
    for p in model.bos.parameters():
        p.requires_grad_(False)
    return losses


def train_garment(data: str | Path, out: str | Path, config: GarmentConfig, *, device: str = "auto",
                  resume: bool = False, force: bool = False) -> dict[str, Any]:
    """Train the regressor for ``config.garment``'s template on ``data``."""
    from training.garment.module import GarmentModule

    accelerator = resolve_device(device)
    apply_threads(config)
    store = open_store(data)
    segments = GarmentDataModule(store, config)
    segments.setup()
    meta = {"kind": KIND, "config": config.as_dict(), **segments.run_meta(), "store": store_identity(store)}
    out = prepare_run(out, resume=resume, force=force, meta=meta)
    seed_everything(config.seed)
    module = GarmentModule.from_data(config, segments)
    dev = torch.device("cuda" if accelerator == "gpu" else "cpu")
    bos_losses = [] if resume else _pretrain_bos(module, segments.train_set, config, dev)
    module.to("cpu")
    t0 = time.perf_counter()
    result = fit(module, segments, config, out, device=device, resume=resume, monitor="val/loss",
                 distributed_sampler=False)  # the growing sampler shares each global batch out itself
    result |= {"seconds": time.perf_counter() - t0, **segments.summary(),
               "bos_pretrain_loss": bos_losses[::max(1, len(bos_losses) // 10)],
               "parameters": sum(p.numel() for p in module.model.parameters())}
    write_summary(out, result)
    return result


def load_garment(run: str | Path, *, checkpoint: str = "best", data: str | Path | None = None):
    """(module on the CPU in eval mode, run metadata, checkpoint path, store) of a regressor run."""
    from training.garment.module import GarmentModule

    meta, path = run_checkpoint(run, KIND, "paper 001's garment regressor", checkpoint=checkpoint)
    store = run_store(meta, run, data)
    faces = store.garment(int(meta["template"]))["faces"]
    module = load_module(GarmentModule, path, "paper 001's garment regressor", faces=faces)
    module.binding = store.binding(int(meta["template"]))
    return module, meta, path, store


def _normals(v: torch.Tensor, faces: torch.Tensor) -> torch.Tensor:
    from datagen.geometry.topology import vertex_normals

    return vertex_normals(v, faces)


def _inside_share(garment: torch.Tensor, posed: torch.Tensor, body_faces: torch.Tensor) -> float:
    """The share of garment vertices [B, T, V, 3] inside posed bodies [B*T, Nb, 3] (eq. 4's test)."""
    from training.garment.contact import body_contact, inside_share

    q = garment.reshape(len(posed), -1, 3)
    return inside_share(q, *body_contact(q, posed, body_faces))


@torch.no_grad()
def evaluate_garment(run: str | Path, *, data: str | Path | None = None, split: str = "test",
                     device: str = "auto") -> dict[str, Any]:
    """Tables 6/7/9's figures on ``split`` for the model and the skinned template; JSON-able."""
    from training.garment.module import template_edges
    from training.metrics import hausdorff, rmse
    from training.paper001.sted import sted

    module, meta, ckpt, store = load_garment(run, data=data)
    dev = torch.device("cuda" if resolve_device(device) == "gpu" else "cpu")
    module.to(dev)
    g = int(meta["template"])
    template = store.garment(g)
    faces = torch.as_tensor(np.asarray(template["faces"], dtype=np.int64), device=dev)
    edges = torch.as_tensor(template_edges(template["faces"]), device=dev)
    ds = template_segments(store, split, g, names=("pose", "trans", "label", "detail", "skin"))
    from datagen.geometry.rotations import axis_angle_to_matrix
    from training.paper001.body import BodyLayer
    from training.paper001.frames import pose_features

    body_model = store.body_model()
    body = BodyLayer(body_model, 1).to(dev)  # the posed body, for the share of vertices inside it
    betas = torch.as_tensor(store.betas()[int(template["body"])], dtype=torch.float32, device=dev)
    body_faces = torch.as_tensor(np.asarray(body_model["faces"], dtype=np.int64), device=dev)
    whos = ("model", "skinned", "copy")
    sums = {f"{who}_{k}": 0.0 for who in whos for k in ("sq", "hausdorff", "sted", "cosine", "inside")}
    sums["simulated_inside"] = 0.0
    counts = {"vertices": 0, "frames": 0, "segments": 0}
    # the copy baseline: every training segment of the template, its poses' features and its garment
    from training.paper001.baselines import nearest_training_segments

    train = next(iter(torch.utils.data.DataLoader(template_segments(store, "train", g), batch_size=100_000)))
    x_train, _ = pose_features(train)
    train_garment = (train["detail"].float() - train["trans"].float()[:, :, None]).to(dev)  # translation's frame
    x_train = x_train.to(dev)
    for batch in torch.utils.data.DataLoader(ds, batch_size=4, shuffle=False):
        batch = {k: v.to(dev) for k, v in batch.items()}
        x, _ = pose_features(batch)  # the model's input only: the figures compare positions, not targets
        trans = batch["trans"].float()[:, :, None]  # every figure in the translation's frame, as before
        true = batch["detail"].float() - trans
        pred = module.garment(module.model.generate(x, graph=True), module.base(batch)) - trans
        B, T = true.shape[:2]
        skinned = batch["skin"].float()
        same = torch.zeros(B, dtype=torch.long, device=dev)  # one template: retrieval over all its segments
        copied = train_garment[nearest_training_segments(x, same, x_train, torch.zeros(len(x_train), dtype=torch.long,
                                                                                        device=dev))]
        n_true = _normals(true.reshape(B * T, -1, 3), faces)
        # the body posed without the translation, as the figures are; inside shares weighted by frames
        posed = body(axis_angle_to_matrix(batch["pose"].float()).reshape(B * T, -1, 3, 3),
                     trans.new_zeros(B * T, 3), betas[None].expand(B * T, -1))
        sums["simulated_inside"] += _inside_share(true, posed, body_faces) * B * T
        for who, p in (("model", pred), ("skinned", skinned), ("copy", copied)):
            sums[f"{who}_inside"] += _inside_share(p, posed, body_faces) * B * T
            sums[f"{who}_sq"] += float(((p - true) ** 2).sum())
            sums[f"{who}_hausdorff"] += float(hausdorff(p.reshape(B * T, -1, 3), true.reshape(B * T, -1, 3)).sum())
            sums[f"{who}_sted"] += float(sted(p, true, edges)["sted"].sum())
            cos = (_normals(p.reshape(B * T, -1, 3), faces) * n_true).sum(-1)
            sums[f"{who}_cosine"] += float(cos.mean(-1).sum())
        counts["vertices"] += true.numel() // 3
        counts["frames"] += B * T
        counts["segments"] += B
    rows = {}
    for who in whos:
        rows[who] = {**rmse(sums[f"{who}_sq"], counts["vertices"], "vertex", "vertex"),
                     "hausdorff": sums[f"{who}_hausdorff"] / counts["frames"],
                     "sted": sums[f"{who}_sted"] / counts["segments"],
                     "normal_cosine": sums[f"{who}_cosine"] / counts["frames"],
                     "inside_share": sums[f"{who}_inside"] / counts["frames"]}
    garment = store.attrs["garment_type_names"][int(template["type"])]
    return {"kind": KIND, "split": split, "checkpoint": str(ckpt), "garment": garment, "template": g,
            "segments": counts["segments"], "frames": counts["frames"], "bos": meta["config"]["bos"],
            "relative_to": module.relative_to,
            "model": rows["model"], "skinned_baseline": rows["skinned"], "copy_baseline": rows["copy"],
            "simulated_inside_share": sums["simulated_inside"] / counts["frames"]}


def format_garment_evaluation(e: dict) -> str:
    frame = {"translation": "the translation", "skinned": "the skinned template"}[e.get("relative_to", "translation")]
    lines = [f"{e['garment']} (template {e['template']}, BOS {e['bos']}, frames relative to {frame}), "
             f"{e['split']} split: {e['segments']} segments, {e['frames']} frames; decoded greedily from the poses", "",
             f"{'':34s} {'vertex RMSE x1e-2 m':>20s} {'per vertex':>11s} {'Hausdorff x1e-1 m':>18s} "
             f"{'STED x1e-2':>11s} {'normal cosine':>14s} {'inside body %':>14s}"]
    named = [("model", e["model"]), ("skinned template", e["skinned_baseline"])]
    if e.get("copy_baseline"):
        named.append(("nearest training segment (copy)", e["copy_baseline"]))
    for name, r in named:
        inside = f"{100 * r['inside_share']:14.2f}" if "inside_share" in r else f"{'-':>14s}"
        lines.append(f"{name:34s} {100 * r['vertex_rmse_per_coordinate']:20.3f} {100 * r['vertex_rmse_per_vertex']:11.3f} "
                     f"{10 * r['hausdorff']:18.3f} {100 * r['sted']:11.3f} {r['normal_cosine']:14.4f} {inside}")
    if "simulated_inside_share" in e:
        lines.append(f"{'simulated garment':34s} {'':20s} {'':11s} {'':18s} {'':11s} {'':14s} "
                     f"{100 * e['simulated_inside_share']:14.2f}")
    lines.append("(vertex RMSE per coordinate, and per vertex: the Euclidean one, √3 x the first)")
    lines.append("(inside body: the share of garment vertices whose closest posed-body vertex's normal points away "
                 "from them, paper 001's test for eq. 4)")
    return "\n".join(lines)


def _garment_of(meta: dict) -> str:
    """The garment type a regressor run was trained on (its config's; runs from before the field: skirt)."""
    return str(meta.get("config", {}).get("garment", "skirt"))


def clothed_runs(folder: str | Path | None, garment: str | None, *, garment_run: str | Path | None = None,
                 motion_run: str | Path | None = None, need_motion: bool = True) -> tuple[Path, Path | None]:
    """The (regressor, generator) runs ``drape sample clothed`` uses: given explicitly, or found in
    ``folder``, a folder of runs (the generator and one or more regressors per garment type, as the
    GPU scripts leave them). In a folder, the regressor for ``garment`` is its refined run where
    there is exactly one, else its only run; the generator is the folder's only motion run. Each
    ambiguity and each miss is one line that names what the folder holds."""
    from training.loop import run_meta

    if folder is None and garment_run is None:
        raise InputError("name the runs: a folder of runs (drape sample clothed RUNS --garment skirt ...) or "
                         "--garment-model RUN")
    found: dict[str, list[tuple[Path, dict]]] = {"garment": [], "motion": []}
    if folder is not None:
        folder = Path(folder)
        if not folder.is_dir():
            raise InputError(f"{folder} is not a folder of runs (no such directory)")
        if (own := run_meta(folder)) is not None:
            raise InputError(f"{folder} is itself a run ({own.get('kind')}), not a folder of runs: give the folder "
                             "that holds the generator and the regressors, or --garment-model RUN and --motion-model RUN")
        for sub in sorted(folder.iterdir()):
            meta = run_meta(sub)
            if meta is not None and meta.get("kind") in found:
                found[meta["kind"]].append((sub, meta))
    if garment_run is None:
        by_type: dict[str, list[tuple[Path, dict]]] = {}
        for sub, meta in found["garment"]:
            by_type.setdefault(_garment_of(meta), []).append((sub, meta))
        trained = ", ".join(f"{g} ({', '.join(p.name for p, _ in runs)})" for g, runs in sorted(by_type.items()))
        if not by_type:
            raise InputError(f"{folder} holds no garment-regressor run; train one with drape train garment, or "
                             "give --garment-model RUN")
        if garment is None:
            if len(by_type) > 1:
                raise InputError(f"give --garment: {folder} has regressors for {trained}")
            garment = next(iter(by_type))
        if garment not in by_type:
            raise InputError(f"{folder} has no regressor for {garment!r}; it has regressors for {trained}")
        runs = by_type[garment]
        refined = [p for p, meta in runs if meta.get("refined_from")]
        if len(refined) == 1:
            garment_run = refined[0]
        elif len(runs) == 1:
            garment_run = runs[0][0]
        else:
            raise InputError(f"{folder} has several regressors for {garment} ({', '.join(p.name for p, _ in runs)}); "
                             "name one with --garment-model RUN")
    elif garment is not None:
        meta = run_meta(garment_run) or {}
        if meta.get("kind") == KIND and _garment_of(meta) != garment:
            raise InputError(f"--garment {garment}: {garment_run} is a regressor for {_garment_of(meta)}")
    if motion_run is None and need_motion and folder is not None:
        motions = [p for p, _ in found["motion"]]
        if len(motions) != 1:
            raise InputError(f"{folder} holds {'no' if not motions else 'several'} motion-generator runs"
                             f"{'' if not motions else ' (' + ', '.join(p.name for p in motions) + ')'}; "
                             "name one with --motion-model RUN")
        motion_run = motions[0]
    return Path(garment_run), (Path(motion_run) if motion_run is not None else None)


@torch.no_grad()
def dress_motion(garment_run: str | Path, *, motion_run: str | Path | None = None, label: str | None = None,
                 motion_file: str | Path | None = None, seed: int = 0, device: str = "cpu",
                 push_out_margin: float | None = 0.002, latent: str = "posterior") -> dict[str, Any]:
    """Paper 001's application: a motion (new, from the generator ``motion_run`` for ``label`` and
    ``seed``; or a motion library ``.npz`` such as an imported AMASS or BVH file), the garment
    predicted for it by the regressor, and the body posed on the template's body shape.

    Returns:
        ``body_vertices`` [T, B, 3], ``body_faces``, ``garment_vertices`` [T, V, 3], ``garment_faces``,
        ``fps``, ``poses`` [T, 24, 3], ``trans`` [T, 3], ``label``, ``garment`` (type), ``seconds``
        (the regressor's time), ``inside_share_predicted`` and ``inside_share`` (garment vertices
        inside the body before and after the push-out post-process, which moves them out along the
        body normal to ``push_out_margin`` metres; None: no post-process).
    """
    from training.garment.contact import body_contact, inside_share, push_out
    from datagen.geometry.rotations import axis_angle_to_matrix
    from training.paper001.body import BodyLayer
    from training.paper001.frames import frames_to_features

    if (motion_file is None) == (label is None):
        raise InputError("give a label (with a motion-generator run) or a motion file, not both")
    module, meta, _, store = load_garment(garment_run)
    dev = torch.device("cuda" if resolve_device(device) == "gpu" else "cpu")
    module.to(dev)
    if motion_file is not None:
        from datagen.motion.motion import Motion

        path = Path(motion_file)
        if not path.is_file():
            raise InputError(f"motion file {path} does not exist")
        m = Motion.load_npz(path)
        poses, trans, fps, label = m.poses, m.trans, float(m.fps), m.label_name
    else:
        if motion_run is None:
            raise InputError("a label needs a motion-generator run (--motion-model RUN) to sample from")
        from training.motion.run import sample_sequences

        poses, trans, fps = sample_sequences(motion_run, label, 1, seed, device=device, latent=latent)
        poses, trans = poses[0], trans[0]
    poses_t = torch.as_tensor(np.asarray(poses), dtype=torch.float32, device=dev)
    trans_t = torch.as_tensor(np.asarray(trans), dtype=torch.float32, device=dev)
    rot = axis_angle_to_matrix(poses_t)
    x = frames_to_features(rot[None], trans_t[None])
    g = int(meta["template"])
    base = module.base({"pose": poses_t[None], "trans": trans_t[None]})[0]
    t0 = time.perf_counter()
    garment = module.garment(module.model.generate(x, graph=True), base[None])[0]
    seconds = time.perf_counter() - t0
    template = store.garment(g)
    body = BodyLayer(store.body_model(), 1).to(dev)
    betas = torch.as_tensor(store.betas()[int(template["body"])], dtype=torch.float32, device=dev)
    body_vertices = body(rot, trans_t, betas[None].expand(len(rot), -1))
    body_faces = torch.as_tensor(np.asarray(store.body_model()["faces"], dtype=np.int64), device=dev)
    closest, normal = body_contact(garment, body_vertices, body_faces)
    predicted_inside = inside_share(garment, closest, normal)
    if push_out_margin is not None:
        garment = push_out(garment, closest, normal, push_out_margin)
    garment_type = store.attrs["garment_type_names"][int(template["type"])]
    return {"body_vertices": body_vertices.cpu().numpy(), "body_faces": np.asarray(store.body_model()["faces"]),
            "garment_vertices": garment.cpu().numpy(), "garment_faces": np.asarray(template["faces"]),
            "fps": fps, "poses": np.asarray(poses), "trans": np.asarray(trans), "label": label,
            "garment": garment_type, "seconds": seconds, "inside_share_predicted": predicted_inside,
            "inside_share": inside_share(garment, *body_contact(garment, body_vertices, body_faces))}
