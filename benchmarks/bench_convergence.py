"""Does the solver converge at the settings the data is made with? A hanging strip of every
material preset, pinned along its top edge, no air drag, self-collision off: its elongation
against the closed-form static answer, how much it still oscillates, and the mechanical energy
balance (kinetic + elastic - work of gravity), which with a static support can only fall.

    python benchmarks/bench_convergence.py [--presets cotton,denim] [--seconds 2.5] [--variant KEY=VALUE ...]

``--variant`` sets a SolverConfig field (e.g. ``chebyshev_rho=0``, ``iterations=50``) for a side run.
Prints one row per preset and variant.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from datagen.materials import MATERIALS
from datagen.sim.metrics import elastic_energy
from datagen.sim.model import ClothModelBuilder
from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState

G = 9.81
FPS = 30


def strip(width: float = 0.05, length: float = 0.5, dx: float = 0.01):
    nx, ny = int(round(width / dx)) + 1, int(round(length / dx)) + 1
    X, Y = np.meshgrid(np.arange(nx) * dx, -np.arange(ny) * dx, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)
    f = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, c, d = i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1
            f += [[a, b, c], [a, c, d]]
    return v, np.array(f), np.flatnonzero(np.isclose(v[:, 1], 0.0)), np.flatnonzero(np.isclose(v[:, 1], -length))


def run(mat, config: SolverConfig, seconds: float, dx: float):
    v, f, top, bottom = strip(dx=dx)
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), (len(f), 1, 1))  # warp along the strip
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name=mat, pinned=top, material_frames=frames)
    model = b.finalize("cpu")
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    control = BodyControl.from_numpy(model, model.host.body_rest)
    solver = SolverVBD(model, config)
    mass = model.host.mass
    y0 = v[:, 1].copy()
    elong, energy = [], []
    for _ in range(int(seconds * FPS)):
        solver.step(s0, s1, control, 1.0 / FPS)
        s0, s1 = s1, s0
        x, vel = s0.numpy()
        x, vel = x.astype(np.float64), vel.astype(np.float64)
        ke = 0.5 * float((mass * (vel**2).sum(1)).sum())
        work = float((mass * G * (y0 - x[:, 1])).sum())
        energy.append(ke + elastic_energy(model.host, x) - work)
        elong.append(-x[bottom, 1].mean() - 0.5)
    return np.array(elong), np.array(energy), work


def stvk_elongation(k: float, rho: float, length: float) -> float:
    """Static elongation of a hanging StVK strip: 2nd Piola stress k E at the point s below the
    top carries the weight below it, ρ g (L - s) per width: k λ (λ² - 1)/2 = ρ g q."""
    from scipy.optimize import brentq

    s = np.linspace(0.0, length, 2001)
    lam = [1.0 if q == 0 else brentq(lambda L, q=q: k * L * (L * L - 1) / 2 - rho * G * q, 1.0, 3.0) for q in s]
    return float(np.trapezoid(np.array(lam) - 1.0, s))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--presets", default=",".join(MATERIALS))
    ap.add_argument("--seconds", type=float, default=2.5)
    ap.add_argument("--dx", type=float, default=0.01, help="grid spacing of the strip [m]")
    ap.add_argument("--variant", action="append", default=[], help="SolverConfig KEY=VALUE[,KEY=VALUE] (repeatable)")
    args = ap.parse_args()
    base = SolverConfig(self_collision=False, air_drag=0.0)
    variants = [("production", base)]
    for spec in args.variant:
        kw = {}
        for item in spec.split(","):
            k, _, val = item.partition("=")
            kind = type(getattr(base, k))
            kw[k] = (val.lower() in ("1", "true", "on")) if kind is bool else kind(val)
        variants.append((spec, dataclasses.replace(base, **kw)))
    window = int(0.5 * FPS)
    print(f"hanging strip 5 cm x 50 cm, {args.dx * 100:g} cm grid, top edge pinned, {args.seconds:g} s, no air drag, "
          "self-collision off; static answer: 1-D StVK with the warp stiffness less the law's Poisson coupling "
          "(k_v - k_uv²/k_u)")
    print(f"{'preset':<10} {'variant':<28} {'exact mm':>9} {'mean mm':>9} {'err %':>8} {'osc % (p-p/2)':>14} "
          f"{'E rise mJ':>10} {'work mJ':>8} {'s':>6}")
    for name in args.presets.split(","):
        mat = dataclasses.replace(MATERIALS[name], damping=MATERIALS[name].damping)
        # the strip's free edges carry no lateral stress, so the law's Poisson coupling k_uv softens it:
        # k_eff = k_v - k_uv² / k_u (the clamped top row, 5 cm of 50, is stiffer; neglected)
        exact = stvk_elongation(mat.warp_uniaxial_stiffness(), mat.density, 0.5)
        for label, cfg in variants:
            t0 = time.perf_counter()
            e, en, work = run(mat, cfg, args.seconds, args.dx)
            last = e[-window:]
            osc = 0.5 * (last.max() - last.min())
            print(f"{name:<10} {label:<28} {exact * 1e3:9.4f} {last.mean() * 1e3:9.4f} "
                  f"{100 * (last.mean() - exact) / exact:+8.1f} {100 * osc / exact:14.1f} {en.max() * 1e3:10.3f} "
                  f"{work * 1e3:8.3f} {time.perf_counter() - t0:6.1f}", flush=True)


if __name__ == "__main__":
    main()
