"""Does paper 001's motion CVAE learn motion (not just each sequence's mean pose) at a constant rate?

    python benchmarks/motion_dynamics_probe.py D_MODEL LAYERS FEEDFORWARD EPOCHS EVERY [LR]
    (docs/training.md: 128 4 512 1500 25, on 2 CPU cores)

A CPU probe outside drape's trainer: the procedural motions of paper-motion's train split (17 labels x
seeds 0-3, 240 frames, 4 segments of 60) built from the motion library, a reduced MotionCVAE, the pose
loss + 1e-5 KL at a constant rate, batch 20. Every EVERY epochs it prints the reconstruction MSE (of
the posterior mean; each sequence's own static mean pose scores 0.00496 on these features) and the
mean frame-to-frame change of the 6D rotation features of reconstructions and of per-label posterior
samples as a share of the real motions'."""
import sys, time, math
import numpy as np, torch
from datagen.motion.library import make_motion
from datagen.motion.labels import LABELS
from datagen.geometry.rotations import axis_angle_to_matrix
from training.motion.model import MotionCVAE, frames_to_features
from training.motion.recognition import motion_speed
from training.motion.run import label_gaussians

torch.manual_seed(0); np.random.seed(0)
d, layers, ff = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
epochs, every = int(sys.argv[4]), int(sys.argv[5])
lr = float(sys.argv[6]) if len(sys.argv) > 6 else 1e-4
xs, ys = [], []
for li, lab in enumerate(LABELS):
    for seed in range(4):
        m = make_motion(lab, seed, frames=240)
        p = torch.as_tensor(m.poses, dtype=torch.float32); t = torch.as_tensor(m.trans, dtype=torch.float32)
        for k in range(4):
            sl = slice(60 * k, 60 * k + 60)
            xs.append(frames_to_features(axis_angle_to_matrix(p[sl])[None], t[sl][None])[0]); ys.append(li)
X = torch.stack(xs); Y = torch.tensor(ys)
print("segments", len(X), "labels", len(LABELS), flush=True)
real_speed = motion_speed(X)
model = MotionCVAE(len(LABELS), d_model=d, heads=4, layers=layers, feedforward=ff, dropout=0.1, label_hidden=128)
opt = torch.optim.Adam(model.parameters(), lr=lr)
steps = 0; t0 = time.time()
for ep in range(1, epochs + 1):
    model.train()
    perm = torch.randperm(len(X))
    for b in range(0, len(X), 20):
        idx = perm[b:b + 20]
        out, mu, logvar = model(X[idx], Y[idx])
        kl = -0.5 * torch.mean(torch.sum(1 + logvar - mu.pow(2) - logvar.exp(), dim=1))
        loss = torch.nn.functional.mse_loss(out, X[idx]) + 1e-5 * kl
        opt.zero_grad(); loss.backward(); torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0); opt.step(); steps += 1
    if ep % every == 0 or ep == 1:
        model.eval()
        with torch.no_grad():
            mu, logvar = model.encode(X, Y)
            rec = model.decode(mu, Y, 60)
            rs = motion_speed(rec)
            fit = label_gaussians(mu, logvar, Y, len(LABELS))
            g = torch.Generator().manual_seed(0)
            lab = torch.arange(len(LABELS)).repeat(4)
            smp = model.sample(lab, 60, generator=g, latent=(torch.as_tensor(fit["mean"]), torch.as_tensor(fit["std"])))
            ss = motion_speed(smp)
            mse = torch.nn.functional.mse_loss(rec, X).item()
        print(f"epoch {ep:5d} step {steps:6d} {time.time() - t0:6.0f}s loss {loss.item():.5f} rec mse {mse:.5f} "
              f"kl {kl.item():7.1f} speed: reconstruction {rs / real_speed:.2f}x, samples {ss / real_speed:.2f}x of real", flush=True)
