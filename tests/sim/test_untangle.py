"""Intersection contour minimisation (``datagen.sim.untangle_kernels``): a fold of one piece of
cloth poked through another is pushed back out; cloth that does not cross itself is left exactly
where it is, by the kernels and by the solver. What it does in garments (the T-shirt runs whose
crossings it undoes) is measured by ``benchmarks/sim.py run-scenes`` (``docs/simulator.md``)."""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp

from datagen.sim import untangle_kernels as U
from datagen.sim.detection_kernels import face_bounds
from datagen.sim.metrics import crossings
from datagen.sim.model import ClothModelBuilder
from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState
from tests.sim.meshes import grid

DT = 1.0 / 30.0


TIP = 25 + 12
"""The lower patch's centre vertex."""


def poked(tip: float = 0.003, device: str = "cpu"):
    """Two flat 8 x 8 cm patches of jersey in one scene, 2 cm grids in XZ, the upper one at y = 0
    and the lower one 5 mm under it (beyond the contact distance); and positions where the lower
    one's centre vertex is raised to ``tip``: for a tip above 0 the tent around it pokes through
    the upper patch (a closed intersection contour around the tip). Returns the model and those
    positions."""
    up_v, up_f = grid(5, 5, 0.02, y=0.0, centre=(0.0, 0.0))
    lo_v, lo_f = grid(5, 5, 0.02, y=-0.005, centre=(0.006, 0.004))
    b = ClothModelBuilder()
    b.add_cloth(up_v, up_f, material_name="jersey", scene=0)
    b.add_cloth(lo_v, lo_f, material_name="jersey", scene=0)
    model = b.finalize(device)
    x = model.host.rest_positions.astype(np.float32).copy()
    x[TIP, 1] = tip
    return model, x


class Crossings:
    """Edge-triangle crossings of a model's cloth at given positions (the per-frame metric's kernel)."""

    def __init__(self, model):
        self.model = model
        self.lo = wp.zeros(model.face_count, dtype=wp.vec3, device="cpu")
        self.hi = wp.zeros(model.face_count, dtype=wp.vec3, device="cpu")
        wp.launch(face_bounds, model.face_count, inputs=[model.rest_positions, model.faces, self.lo, self.hi],
                  device="cpu")
        self.bvh = wp.Bvh(self.lo, self.hi)
        self.out = wp.zeros(model.edge_count, dtype=wp.int32, device="cpu")
        self.none = wp.zeros((model.edge_count, 0), dtype=wp.int32, device="cpu")
        self.order = wp.array(np.arange(model.edge_count, dtype=np.int32), device="cpu")  # index order

    def __call__(self, x) -> int:
        m = self.model
        wp.launch(face_bounds, m.face_count, inputs=[x, m.faces, self.lo, self.hi], device="cpu")
        self.bvh.refit()
        wp.launch(crossings, m.edge_count, inputs=[self.bvh.id, x, m.particle_scene, m.faces, m.edge_pairs, self.out,
                                                   self.none, self.order], device="cpu")
        return int(self.out.numpy().sum())


def contour_steps(model, x, step: float, count: int, marked_out: list | None = None) -> list[int]:
    """``count`` steps of the kernels alone (no solver) from positions ``x``, as the solver runs
    them: the first queries every edge and marks those that cross, the later ones query only the
    marked edges. The crossings before each step and after the last; ``marked_out`` gets the
    number of marked edges."""
    m = model
    cross = Crossings(m)
    bvh = wp.Bvh(cross.lo, cross.hi)
    push = wp.zeros((m.particle_count, 3), dtype=wp.int32, device="cpu")
    hits = wp.zeros(m.particle_count, dtype=wp.int32, device="cpu")
    frozen = wp.zeros(m.scene_count, dtype=wp.int32, device="cpu")
    marked = wp.zeros(m.edge_count, dtype=wp.int32, device="cpu")
    counts = []
    for it in range(count):
        counts.append(cross(x))
        push.zero_()
        hits.zero_()
        wp.launch(face_bounds, m.face_count, inputs=[x, m.faces, cross.lo, cross.hi], device="cpu")
        bvh.refit()
        wp.launch(U.contour_gradients, m.edge_count, inputs=[bvh.id, x, m.particle_scene, m.faces, m.edges, frozen,
                                                             int(it > 0), marked, push, hits, cross.order], device="cpu")
        if it == 0 and marked_out is not None:
            marked_out.append(int(marked.numpy().sum()))
        wp.launch(U.apply_untangle, m.particle_count, inputs=[push, hits, m.active, step, x], device="cpu")
    counts.append(cross(x))
    return counts


def test_contour_gradient_pushes_a_poked_tent_back():
    """The kernels alone, 1 mm steps: the tent's 12 crossings (its six edges through the upper patch,
    the upper patch's six edges through its six triangles)
    fall to none, and the tip moves down while the upper patch above it moves up."""
    model, x0 = poked()
    x = wp.array(x0, dtype=wp.vec3, device="cpu")
    marked = []
    counts = contour_steps(model, x, 0.001, 12, marked)
    x1 = x.numpy()
    print(f"\ncrossings per contour step (1 mm): {counts}; edges marked at the first: {marked}")
    assert counts[0] == 12
    assert marked == [7]  # seven edges make the 12 edge-triangle crossings; the later steps query only these
    assert counts[-1] == 0
    assert x1[TIP, 1] < x0[TIP, 1]
    above = np.argmin(np.linalg.norm(x0[:25, [0, 2]] - x0[TIP, [0, 2]], axis=1))
    assert x1[above, 1] > x0[above, 1]


def test_contour_gradient_leaves_uncrossed_cloth_alone():
    """With the tip under the upper patch nothing crosses, and the kernels move nothing."""
    model, x0 = poked(tip=-0.001)
    x = wp.array(x0, dtype=wp.vec3, device="cpu")
    assert contour_steps(model, x, 0.002, 3) == [0, 0, 0, 0]
    assert np.array_equal(x.numpy(), x0)


def test_solver_without_crossings_is_unchanged_by_the_untangling():
    """Where the cloth crosses nowhere the untangling moves nothing: with the lower patch's centre
    0.5 mm under the upper patch (in contact) 1 s of the solver gives bitwise the same positions
    with it on (the default) and off."""
    runs = []
    for step in (SolverConfig().untangle_step, 0.0):
        model, x0 = poked(tip=-0.0045)
        cross = Crossings(model)
        s0, s1 = ClothState.from_model(model, x0), ClothState.from_model(model, x0)
        control = BodyControl.from_numpy(model, model.host.body_rest)
        solver = SolverVBD(model, SolverConfig(untangle_step=step))
        for _ in range(30):
            solver.step(s0, s1, control, DT)
            s0, s1 = s1, s0
            assert cross(s0.positions) == 0
        runs.append(s0.positions.numpy())
    assert SolverConfig().untangle_step > 0
    assert np.array_equal(runs[0], runs[1])


@pytest.mark.parametrize("device", ["cpu", pytest.param("cuda", marks=pytest.mark.skipif(
    wp.get_cuda_device_count() == 0, reason="needs a CUDA device: thread order only varies there"))])
def test_untangling_is_bitwise_repeatable(device):
    """Two solvers on the poked scene (crossings, so the untangling moves vertices) give bitwise
    the same positions after 3 frames: the gradients are summed as integers, so the order in which
    CUDA threads add them does not matter. (A third run without the untangling ends elsewhere.)"""
    runs = []
    for step in (SolverConfig().untangle_step, SolverConfig().untangle_step, 0.0):
        model, x0 = poked(device=device)
        s0, s1 = ClothState.from_model(model, x0), ClothState.from_model(model, x0)
        control = BodyControl.from_numpy(model, model.host.body_rest)
        solver = SolverVBD(model, SolverConfig(gravity=(0.0, 0.0, 0.0), untangle_step=step))
        for _ in range(3):
            solver.step(s0, s1, control, DT)
            s0, s1 = s1, s0
        runs.append(s0.positions.numpy())
    assert np.array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0], runs[2])  # the untangling did act on this scene
