"""Where the solver holds its energy balance and its statics, and where it does not (issue 59).

Four cases, each at every requested preset, at the production solver settings unless said; each
prints, per run, the largest rise of the mechanical energy balance E = kinetic + elastic - work of
gravity above its running minimum (with a static support E can only fall; the penalty contact's
stored energy is left out, below 1e-9 J for cloth resting at its weight on k_c = 1e4 N/m) and the
static answer where there is one:

- ``fps``: the 5 cm x 50 cm hanging strip of ``tests/sim/test_physics.py`` (1 cm grid, warp along
  its length, top row pinned, no air drag, self-collision off) for 2 s at each frame rate; its
  elongation (mean of the last 0.5 s) against the 1-D static answer.
- ``release``: the same strip started stretched by ``--strain`` (35 %: beyond the lock at 30 %)
  along its length and let go (self-collision off); it recoils, bounces and must settle at the
  static answer.
- ``rim``: a 30 cm disc (1.5 cm edges) dropped from 1 mm above its contact distance onto a plain
  18 cm cylinder with a square rim (the Cusick set-up without the rounding), self-collision on.
- ``edge``: the Cusick disc on the rounded support (``benchmarks/cusick.py``) at ``--edges`` edge
  lengths, self-collision on.
- ``cost``: the production scene of ``python -m benchmarks sim prepare`` (the T-shirt walking, its
  ``--inputs`` .npz), ``--frames`` frames after two: CPU ms a frame in all and in the global step,
  and how far the global step's conjugate gradients get (each Newton step's rᵀP⁻¹r after its last
  iteration over before its first: median and 90th percentile over the substeps). The preset
  list does not apply (the garment's own material).

    python -m benchmarks physics-limits [--cases fps,release,rim,edge,cost] [--presets cotton,denim]
        [--fps 5,15,30,60] [--strain 0.35] [--edges 0.01,0.015] [--frames 10] [--set KEY=VALUE ...]
        [--inputs sim_inputs.npz]

The ``rim`` and ``edge`` cases run ``--frames`` frames (the energy is made in the first ones); each
line ends with the CPU time per substep.
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


def strip_mesh(dx: float = 0.01, width: float = 0.05, length: float = 0.5):
    """A strip in the XY plane hanging down from y = 0 (weft X, warp Y): vertices, faces, material
    frames, the pinned top row and the bottom row."""
    nx, ny = int(round(width / dx)) + 1, int(round(length / dx)) + 1
    X, Y = np.meshgrid(np.arange(nx) * dx, -np.arange(ny) * dx, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)
    f = np.array([[i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1] for i in range(nx - 1) for j in range(ny - 1)]
                 + [[i * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1] for i in range(nx - 1) for j in range(ny - 1)])
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), (len(f), 1, 1))
    return v, f, frames, np.flatnonzero(np.isclose(v[:, 1], 0.0)), np.flatnonzero(np.isclose(v[:, 1], -length))


def strip_static(mat, length: float = 0.5) -> float:
    """The hanging strip's static elongation [m]: 1-D StVK with the warp's uniaxial stiffness
    (``tests/sim/test_physics.stvk_strip_elongation``)."""
    from scipy.optimize import brentq

    k, rho = mat.warp_uniaxial_stiffness(), mat.density
    s = np.linspace(0.0, length, 2001)
    lam = [1.0 if q == 0 else brentq(lambda L, q=q: k * L * (L * L - 1) / 2 - rho * G * q, 1.0, 3.0) for q in s]
    return float(np.trapezoid(np.array(lam) - 1.0, s))


@dataclasses.dataclass(frozen=True, kw_only=True)
class Run:
    """One run's energy record: ``balance[k]`` E after frame k [J] (E before the first frame is
    ``start``), the final positions and velocities, CPU seconds per substep."""

    balance: np.ndarray
    start: float
    x: np.ndarray
    v: np.ndarray
    per_substep: float
    work: float
    heights: np.ndarray

    @property
    def rise(self) -> np.ndarray:
        """E after each frame above the lowest E before it [J]."""
        e = np.concatenate([[self.start], self.balance])
        return e[1:] - np.minimum.accumulate(e)[:-1]


def run(model, config: SolverConfig, frames: int, fps: float, positions=None, watch=None) -> Run:
    """``frames`` frames of 1/``fps`` s from ``positions`` (rest: the model's) at rest, static body;
    ``heights[k]`` is the mean height of the vertices ``watch`` after frame k [m]."""
    host = model.host
    x0 = np.asarray(host.rest_positions, dtype=np.float64) if positions is None else positions
    mass = host.mass
    s0, s1 = ClothState.from_model(model, positions), ClothState.from_model(model, positions)
    control = BodyControl.from_numpy(model, host.body_rest)
    solver = SolverVBD(model, config)
    start = elastic_energy(host, x0)
    out, heights, elapsed, x, v = [], [], 0.0, x0, np.zeros_like(x0)
    watch = np.zeros(0, dtype=int) if watch is None else watch
    for _ in range(frames):
        t0 = time.perf_counter()
        solver.step(s0, s1, control, 1.0 / fps)
        elapsed += time.perf_counter() - t0
        s0, s1 = s1, s0
        x, v = (a.astype(np.float64) for a in s0.numpy())
        work = G * float((mass * (x0[:, 1] - x[:, 1])).sum())
        out.append(0.5 * float((mass * (v * v).sum(1)).sum()) + elastic_energy(host, x) - work)
        heights.append(float(x[watch, 1].mean()) if len(watch) else 0.0)
    substeps = frames * solver.substeps_for(1.0 / fps)
    return Run(balance=np.array(out), start=start, x=x, v=v, per_substep=elapsed / max(substeps, 1), work=work,
               heights=np.array(heights))


def strip_model(mat):
    v, f, frames, top, bottom = strip_mesh()
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name=mat, pinned=top, material_frames=frames)
    return b.finalize("cpu"), v, bottom


def case_fps(mat, config, args) -> None:
    exact = strip_static(mat)
    cfg = dataclasses.replace(config, air_drag=0.0, self_contact=dataclasses.replace(config.self_contact, enabled=False))
    for fps in args.fps:
        model, v, bottom = strip_model(mat)
        frames = int(round(2.0 * fps))
        r = run(model, cfg, frames, fps, watch=bottom)
        last = -r.heights[-max(1, int(round(0.5 * fps))):].mean() - 0.5  # the mean of the last 0.5 s
        print(f"fps      {mat.name:<10} {fps:6g} fps: E rise max {r.rise.max():+.2e} J (gravity's work {r.work:.2e} J), "
              f"elongation {last * 1e3:.4f} mm against static {exact * 1e3:.4f} mm ({100 * (last - exact) / exact:+.1f} %), "
              f"{r.per_substep * 1e3:.2f} ms/substep", flush=True)


def case_release(mat, config, args) -> None:
    exact = strip_static(mat)
    cfg = dataclasses.replace(config, air_drag=0.0, self_contact=dataclasses.replace(config.self_contact, enabled=False))
    model, v, bottom = strip_model(mat)
    start = v * np.array([1.0, 1.0 + args.strain, 1.0])
    frames = int(round(args.seconds * 30))
    r = run(model, cfg, frames, 30.0, positions=start, watch=bottom)
    last = -r.heights[-15:].mean() - 0.5  # the mean of the last 0.5 s
    worst = int(np.argmax(r.rise))
    print(f"release  {mat.name:<10} {100 * args.strain:g} %, {args.seconds:g} s: E rise max {r.rise.max():+.2e} J at frame "
          f"{worst + 1} (E from {r.start:.3e} J), final elongation {last * 1e3:.4f} mm against static "
          f"{exact * 1e3:.4f} mm ({100 * (last - exact) / exact:+.1f} %), final speed {np.linalg.norm(r.v, axis=1).max():.4f} "
          f"m/s, {r.per_substep * 1e3:.2f} ms/substep", flush=True)


def square_cylinder(radius: float = 0.09, height: float = 0.4, sections: int = 96):
    """A closed cylinder of ``radius`` with its top face at y = 0 and a square (unrounded) rim."""
    import trimesh

    m = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
    v = np.asarray(m.vertices)[:, [0, 2, 1]]
    v[:, 1] -= height / 2
    m = trimesh.Trimesh(v, np.asarray(m.faces), process=True)
    if m.volume < 0:
        m.invert()
    return np.asarray(m.vertices), np.asarray(m.faces)


def disc_model(mat, edge: float, body, config):
    from benchmarks.cusick import SPECIMEN_RADIUS, disc_mesh

    v, f = disc_mesh(SPECIMEN_RADIUS, edge)
    v[:, 1] += mat.thickness + config.body.margin + 0.001
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]), (len(f), 1, 1))
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name=mat, material_frames=frames)
    b.add_body(*body)
    return b.finalize("cpu")


def case_rim(mat, config, args) -> None:
    model = disc_model(mat, 0.015, square_cylinder(), config)
    r = run(model, config, args.frames, 30.0)
    worst = int(np.argmax(r.rise))
    print(f"rim      {mat.name:<10} square rim, {args.frames} frames: E rise max {r.rise.max():+.2e} J at frame {worst + 1} "
          f"(gravity's work {r.work:.2e} J), {r.per_substep * 1e3:.2f} ms/substep", flush=True)


def case_edge(mat, config, args) -> None:
    from benchmarks.cusick import support_mesh

    for edge in args.edges:
        model = disc_model(mat, edge, support_mesh(), config)
        r = run(model, config, args.frames, 30.0)
        worst = int(np.argmax(r.rise))
        print(f"edge     {mat.name:<10} {edge * 100:g} cm edges, {args.frames} frames: E rise max {r.rise.max():+.2e} J at "
              f"frame {worst + 1} (gravity's work {r.work:.2e} J), {r.per_substep * 1e3:.2f} ms/substep", flush=True)


def case_cost(config, args) -> None:
    from benchmarks.common import play, prepared_batch, scene_name
    from datagen.sim.probes import CgTrace

    d = np.load(args.inputs)
    batch, frames = prepared_batch(d, 1, "cpu", args.frames + 2, config)
    solver, a, c, ctrl = batch.solver, batch.a, batch.c, batch.control
    a, c = play(solver, a, c, ctrl, frames[1:3])  # compiles, settles the first contacts
    spent = [0.0]
    inner = solver._global_step

    def timed(x, h):
        t0 = time.perf_counter()
        inner(x, h)
        spent[0] += time.perf_counter() - t0
    solver._global_step = timed
    trace = CgTrace()
    solver.probes = (trace,)
    t = time.perf_counter()
    a, c = play(solver, a, c, ctrl, frames[3:])
    wall = (time.perf_counter() - t) / (len(frames) - 3)
    ratio = np.array([e[-1].max() / max(e[0].max(), 1e-300) for e in trace.entries])  # over the cold start
    s = config.steps
    steps, warm = getattr(s, "global_steps", 1), getattr(s, "warm_start", False)  # (the code before them had neither)
    print(f"cost     {scene_name(d)} {len(d['garment'])} vertices, {steps} x {s.global_iterations} CG, "
          f"warm start {'on' if warm else 'off'}, {s.iterations} sweeps: {wall * 1e3:.0f} ms/frame, global step "
          f"{spent[0] / (len(frames) - 3) * 1e3:.0f} ms/frame; CG r'P^-1 r end/start median {np.median(ratio):.2e}, "
          f"90th percentile {np.quantile(ratio, 0.9):.2e} over {len(ratio)} Newton steps", flush=True)


CASES = {"fps": case_fps, "release": case_release, "rim": case_rim, "edge": case_edge}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default="fps,release,rim,edge")
    ap.add_argument("--presets", default=",".join(MATERIALS))
    ap.add_argument("--fps", default="5,15,30,60")
    ap.add_argument("--strain", type=float, default=0.35)
    ap.add_argument("--seconds", type=float, default=2.0, help="length of the release case [s]")
    ap.add_argument("--edges", default="0.01,0.015")
    ap.add_argument("--frames", type=int, default=10, help="frames of the rim and edge cases")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a SolverConfig field")
    ap.add_argument("--inputs", default="sim_inputs.npz",
                    help="the cost case's scene (python -m benchmarks sim prepare)")
    args = ap.parse_args(argv)
    args.fps = [float(s) for s in args.fps.split(",")]
    args.edges = [float(s) for s in args.edges.split(",")]
    kw = {}
    for item in args.set:
        k, _, val = item.partition("=")
        kw[k] = (val.lower() in ("1", "true", "on")) if val.lower() in ("true", "false", "on", "off") else (
            int(val) if val.lstrip("-").isdigit() else float(val) if val.replace(".", "", 1).replace("e-", "").isdigit()
            else val)
    config = SolverConfig(**kw)
    for case in args.cases.split(","):
        if case == "cost":
            case_cost(config, args)
            continue
        for name in args.presets.split(","):
            CASES[case](MATERIALS[name], config, args)


if __name__ == "__main__":
    main()
