"""Two layers of cloth in contact range closing on each other do not cross in the global step
(issue 66, ``small``'s scene 34).

The global step has no cloth-cloth contact forces; with the sweeps' bound floor (a distance below
6 mm counted as 6 mm: 2.7 mm a vertex) two layers 3-4.5 mm apart could each move 2.7 mm towards the
other there and cross: every new crossing of scene 34's frames 81-82 (pants squatting, the front
panels folding under the belly) appeared in the global step, the pairs' vertices moving 3.1-3.5 mm
in it. Here two cotton squares 3.5 mm apart bulge towards each other at up to 0.8 m/s each (2.7 mm
a substep) in the middle: without the floor in the global step (``kernels.global_bounds``: 1.6 mm
each at most here) no edge crosses a triangle after any substep's global step (24 did on main).
"""

import numpy as np

from datagen.sim.model import ClothModelBuilder
from datagen.sim.probes import Probe
from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState
from tests.sim.meshes import grid
from tests.sim.test_physics import COTTON


class _Crossings(Probe):
    """The edge-triangle crossings right after each substep's global step (at its first sweep)."""

    def __init__(self, faces, edges):
        self.faces, self.edges, self.counts = faces, edges, []

    def before_sweep(self, solver, substep, sweep, x):
        if sweep == 0:
            from benchmarks.crossing_regions import frame_crossings

            self.counts.append(len(frame_crossings(x.numpy().astype(np.float64), self.faces, self.edges)))


def test_two_layers_closing_in_contact_range_do_not_cross_in_the_global_step():
    v, f = grid(9, 9, 0.01)  # 8 x 8 cm in the XZ plane
    gap = 0.0035
    cv = np.concatenate([v, v + [0.002, gap, 0.003]])  # the upper layer shifted so edges meet triangles
    cf = np.concatenate([f, f + len(v)])
    b = ClothModelBuilder()
    b.add_cloth(cv, cf, material_name=COTTON)
    model = b.finalize("cpu")
    e = np.concatenate([cf[:, [0, 1]], cf[:, [1, 2]], cf[:, [2, 0]]])
    probe = _Crossings(cf, np.unique(np.sort(e, 1), axis=0))
    solver = SolverVBD(model, SolverConfig(gravity=(0.0, 0.0, 0.0)), probes=(probe,))
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    # a bump closing the gap in the middle, not at the edges (parallel sheets that pass through each
    # other whole leave no edge through a triangle)
    bump = 0.8 * np.exp(-(np.linalg.norm(cv[:, [0, 2]] - cv[:, [0, 2]].mean(0), axis=1) / 0.02) ** 2)
    vel = np.zeros_like(cv, dtype=np.float32)
    vel[: len(v), 1], vel[len(v):, 1] = bump[: len(v)], -bump[len(v):]
    s0.velocities.assign(vel)
    solver.step(s0, s1, BodyControl.from_numpy(model, model.host.body_rest), 1 / 30)
    assert probe.counts and max(probe.counts) == 0, f"crossings after each global step: {probe.counts}"
