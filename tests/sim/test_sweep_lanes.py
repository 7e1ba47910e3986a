"""The kernels that share one vertex's (or one scene's) sums out over a block of threads add every
item exactly once: the sweeps' per-vertex solve (``datagen.sim.sweep_kernels``) and the global
step's per-scene dot products (``newton_kernels.scene_dot``). On the CPU, warp's blocks of one
thread (the default) and of ``SWEEP_LANES`` / ``DOT_LANES`` threads (``warp.config.enable_cpu_blocks``)
give the same step up to float rounding, on a scene with membrane, bending, cloth-cloth and body
contacts."""

from __future__ import annotations

import numpy as np

from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState
from datagen.sim.sweep_kernels import SWEEP_LANES
from tests.sim.test_physics import DT, small_sphere_scene


def test_blocks_of_lanes_give_the_one_thread_step():
    import warp as wp

    model, _v0, _f = small_sphere_scene()
    config = SolverConfig()
    control = BodyControl.from_numpy(model, model.host.body_rest)
    # two solvers stepped alike (blocks of one thread) to where the cloth has folded round the
    # sphere onto itself, then one more step each: with blocks of one thread and of SWEEP_LANES
    runs = []
    for _ in range(2):
        solver = SolverVBD(model, config)
        a, b = ClothState.from_model(model), ClothState.from_model(model)
        for _ in range(24):
            solver.step(a, b, control, DT)
            a, b = b, a
        runs.append((solver, a, b))
    x0 = runs[0][1].numpy()[0].astype(np.float64)
    assert np.array_equal(runs[1][1].numpy()[0], runs[0][1].numpy()[0])
    solver = runs[0][0]
    contacts = int(solver.vt_count.numpy().sum() + solver.ee_count.numpy().sum())
    on_body = int((solver.body_has.numpy() > 0).any(1).sum())
    assert contacts > 0 and on_body > 0, "the scene no longer has cloth-cloth and body contacts to share out"
    results = []
    saved = wp.config.enable_cpu_blocks
    try:
        for (solver, a, b), blocks in zip(runs, (False, True), strict=True):
            wp.config.enable_cpu_blocks = blocks
            solver.step(a, b, control, DT)
            results.append(b.numpy()[0].astype(np.float64))
    finally:
        wp.config.enable_cpu_blocks = saved
    moved = np.abs(results[0] - x0).max()
    diff = np.abs(results[0] - results[1]).max()
    print(f"\n{contacts} cloth-cloth contacts, {on_body} vertices on the body; one frame moves up to "
          f"{moved * 1e3:.2f} mm; blocks of 1 and {SWEEP_LANES} threads differ by {diff:.2e} m")
    assert moved > 1e-4
    assert diff < 1e-5
