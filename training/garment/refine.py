"""Paper 001's self-supervised collision handling (§3.4, eq. 4) for the garment regressor.

- :mod:`training.garment.contact`: closest body points and normals, eq. 4's loss, the push-out.
- :func:`refine_garment`: motions sampled from the motion generator's latent space, the regressor's
  garments for them (greedy decoding), sequences with heavy interpenetration (more than
  ``drop_share`` of the vertices inside) dropped, then the regressor fine-tuned on the rest with
  the collision loss plus a term that keeps each frame near what the regressor predicted before
  (without it, the loss is zero for a garment blown up away from the body; the paper does not
  say what anchors its fine-tuning), at the regressor's final learning rate (§4.2). No ground
  truth is used. The refined model is written as a new run directory.

As the paper says, a garment vertex whose closest body vertex lies on the far side of a limb (deep
penetration) is pushed the wrong way; such sequences are what ``drop_share`` removes.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import torch

from datagen.errors import InputError
from training.garment.contact import body_contact, collision_loss, inside_share


def refine_garment(garment_run: str | Path, motion_run: str | Path, out: str | Path, *, samples: int = 64,
                   steps: int = 200, seed: int = 0, drop_share: float = 0.2, keep_weight: float = 1.0,
                   margin: float = 0.002, lr: float | None = None, device: str = "auto", force: bool = False,
                   latent: str = "posterior") -> dict[str, Any]:
    """Fine-tune a garment regressor with eq. 4 on sampled motions (see the module docstring) and
    write it as the run ``out``; returns the share of vertices inside the body before and after on
    a second, held-out set of sampled motions, and the fine-tuning losses."""
    from datagen.geometry.rotations import axis_angle_to_matrix
    from training.garment.run import load_garment
    from training.loop import RUN_FILE, resolve_device
    from training.paper001.body import BodyLayer
    from training.paper001.frames import frames_to_features
    from training.motion.run import load_motion, sample_sequences, train_label_counts

    if samples < 2 or steps < 1:
        raise InputError(f"--samples must be 2 or more and --steps 1 or more, got {samples} and {steps}")
    out = Path(out)
    if out.exists() and any(out.iterdir()):
        if not force:
            raise InputError(f"{out} exists and is not empty; give --force to replace it, or a new --out")
        if not (out / RUN_FILE).is_file():
            raise InputError(f"--force would delete {out}, which is not a drape run directory; choose another --out")
    module, meta, ckpt, store = load_garment(garment_run)
    motion = load_motion(motion_run)  # once: every sampled sequence uses it
    motion_meta = motion[1]
    dev = torch.device("cuda" if resolve_device(device) == "gpu" else "cpu")
    module.to(dev).eval()
    template = store.garment(int(meta["template"]))
    body = BodyLayer(store.body_model(), 1).to(dev)
    betas = torch.as_tensor(store.betas()[int(template["body"])], dtype=torch.float32, device=dev)
    faces = torch.as_tensor(np.asarray(store.body_model()["faces"], dtype=np.int64), device=dev)
    rng = np.random.default_rng(seed)
    labels = motion_meta["labels"]
    # the labels the generator learned (its training motions', whether their scenes passed or failed)
    choices = [labels[k] for k, c in enumerate(train_label_counts(store, len(labels))) if c > 0] or labels

    def sample_set(n: int, base_seed: int):
        sets = []
        for k in range(n):
            poses, trans, _ = sample_sequences(motion, str(rng.choice(choices)), 1, base_seed + k, device=device,
                                               latent=latent)
            p = torch.as_tensor(poses[0], dtype=torch.float32, device=dev)
            t = torch.as_tensor(trans[0], dtype=torch.float32, device=dev)
            rot = axis_angle_to_matrix(p)
            x = frames_to_features(rot[None], t[None])
            b = body(rot, t, betas[None].expand(len(rot), -1))
            sets.append((x, module.base({"pose": p[None], "trans": t[None]})[0], b))
        return sets

    def garment_of(x, base):
        return module.garment(module.model.generate(x), base[None])[0]

    def share(sets) -> float:
        values = []
        with torch.no_grad():
            for x, base, b in sets:
                g = garment_of(x, base)
                values.append(inside_share(g, *body_contact(g, b, faces)))
        return float(np.mean(values))

    train_sets = sample_set(samples, 10_000 * (seed + 1))
    held_out = sample_set(max(2, samples // 4), 10_000 * (seed + 1) + 5_000)
    before = share(held_out)
    kept, dropped = [], 0
    with torch.no_grad():
        for x, base, b in train_sets:
            g = garment_of(x, base)
            closest, normal = body_contact(g, b, faces)
            if inside_share(g, closest, normal) > drop_share:
                dropped += 1
                continue
            kept.append((x, base, b, (g - base) * module.scale))
    if not kept:
        raise InputError(f"every sampled sequence has more than {drop_share:.0%} of its garment inside the body; the "
                         "regressor needs more training before refinement")
    lr = lr if lr is not None else float(meta["config"]["lr"]) * float(meta["config"]["lr_factor"])
    params = [p for p in module.model.parameters() if p.requires_grad]
    opt = torch.optim.Adam(params, lr=lr)
    module.train()
    losses = []
    g_rng = torch.Generator().manual_seed(seed)
    for _ in range(steps):
        x, base, b, target = kept[int(torch.randint(len(kept), (1,), generator=g_rng))]
        raw = module.model(x, target.reshape(1, len(base), -1))
        g = module.garment(raw, base[None])[0]
        pred = raw.float()[0].reshape(target.shape)
        closest, normal = body_contact(g.detach(), b, faces)
        loss = collision_loss(g, closest, normal, margin) * module.scale + keep_weight * torch.nn.functional.mse_loss(
            pred, target)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.detach().item())
    module.eval()
    after = share(held_out)
    if out.exists():
        shutil.rmtree(out)
    (out / "checkpoints").mkdir(parents=True)
    run_meta = {**meta, "refined_from": str(Path(garment_run).resolve()), "refined_with": str(Path(motion_run).resolve())}
    (out / RUN_FILE).write_text(json.dumps(run_meta, indent=2))
    checkpoint = torch.load(ckpt, map_location="cpu", weights_only=False)
    checkpoint["state_dict"] = {k: v.cpu() for k, v in module.state_dict().items()}
    torch.save(checkpoint, out / "checkpoints" / "best.ckpt")
    result = {"inside_share_before": before, "inside_share_after": after, "sampled": samples, "dropped": dropped,
              "held_out": len(held_out), "steps": steps, "lr": lr, "loss_first": losses[0], "loss_last": losses[-1],
              "losses": losses[::max(1, len(losses) // 20)]}
    (out / "refine_summary.json").write_text(json.dumps(result, indent=2))
    return result
