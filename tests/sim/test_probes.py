"""The solver's convergence probes (:class:`~datagen.sim.probes.CgTrace`, :class:`~datagen.sim.probes.SweepTrace`,
called back by the solver) record what they say and change nothing: a traced run is bitwise the untraced one (CPU)."""

from __future__ import annotations

import numpy as np

from datagen.sim.model import ClothModelBuilder
from datagen.sim.probes import CgTrace, SweepTrace
from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState
from tests.sim.meshes import grid

SUBSTEPS, ITERATIONS, GLOBAL = 3, 6, 7


def _run(trace: bool, frames: int = 3):
    """A 30 cm cotton square falling onto a sphere; its positions every frame and the traces."""
    import trimesh

    v, f = grid(13, 13, 0.025, y=0.0)
    s = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    sv, sf = np.asarray(s.vertices, dtype=np.float64) + [0.0, -0.105, 0.0], np.asarray(s.faces, dtype=np.int64)
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name="cotton")
    b.add_body(sv, sf)
    model = b.finalize("cpu")
    solver = SolverVBD(model, SolverConfig(substeps=SUBSTEPS, iterations=ITERATIONS, global_iterations=GLOBAL))
    cg, sweeps = CgTrace(), SweepTrace()
    if trace:
        solver.probes = (cg, sweeps)
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    out = []
    for _ in range(frames):
        solver.step(s0, s1, BodyControl.from_numpy(model, sv), 1.0 / 30)
        s0, s1 = s1, s0
        out.append(s0.numpy()[0].copy())
    return np.stack(out), cg.entries, sweeps.entries, solver.substeps_for(1.0 / 30)


def test_traces_record_every_step_and_change_nothing():
    plain, _, _, _ = _run(False)
    traced, cg, sweeps, substeps = _run(True)
    assert substeps >= SUBSTEPS  # the config's is the fewest; a substep lasts at most max_substep
    assert np.array_equal(plain.view(np.uint32), traced.view(np.uint32))
    assert len(cg) == 3 * substeps  # one global step a substep
    for rz in cg:
        assert rz.shape == (GLOBAL + 2, 1)  # the cold start (d = 0), the warm start, each iteration
        assert np.isfinite(rz).all() and (rz >= 0).all()
        assert rz[0, 0] > 0 and rz[-1, 0] < rz[0, 0]  # the iterations reduce the residual
    assert len(sweeps) == 3 * substeps * ITERATIONS  # one entry a sweep
    assert all(moves.shape == (plain.shape[1],) and np.isfinite(moves).all() for _, _, moves, _, _ in sweeps)
