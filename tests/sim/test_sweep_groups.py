"""The kernels that share one vertex's (or one scene's) sums out over several threads add every item
exactly once, on a scene with membrane, bending, cloth-cloth and body contacts (the cloth folded
round a sphere onto itself):

- the sweeps' partial sums (``sweep_kernels.colour_partials``): over any number of groups they add
  up to the one-group sum, for every colour;
- the global step's per-scene dot products (``newton_kernels.scene_dot``): with warp's blocks of
  one thread (the CPU's default) and of ``DOT_LANES`` threads (``warp.config.enable_cpu_blocks``)
  they are the float64 dot product of each scene's vertices.
"""

from __future__ import annotations

import numpy as np
import pytest

from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState
from tests.sim.test_physics import DT, small_sphere_scene


@pytest.fixture(scope="module")
def folded():
    """The solver and state after 24 frames, when the cloth has folded onto itself."""
    model, _v0, _f = small_sphere_scene()
    solver = SolverVBD(model, SolverConfig())
    control = BodyControl.from_numpy(model, model.host.body_rest)
    a, b = ClothState.from_model(model), ClothState.from_model(model)
    for _ in range(24):
        solver.step(a, b, control, DT)
        a, b = b, a
    return model, solver, a


def _partials(model, solver, x, groups: int):
    """Each colour's per-vertex sums of force, Hessian and elastic Hessian over ``groups`` groups."""
    import warp as wp

    from datagen.sim import sweep_kernels as S

    m, c = model, solver.config
    out = []
    for col in m.colours:
        bufs = [wp.zeros((groups, col.shape[0]), dtype=t) for t in (wp.vec3, wp.mat33, wp.mat33)]
        wp.launch(S.colour_partials, (groups, col.shape[0]), inputs=[
            col, x, solver.x_prev, m.active, m.damping, m.faces, m.dm_inv, m.tri_area, m.tri_stiff, m.tri_lock,
            m.edges, m.rest_angle, m.bend_k, m.v2f_offsets, m.v2f, m.v2e_offsets, m.v2e, solver.body_has,
            solver.body_point, solver.body_normal, solver.body_radius, c.body_stiffness, solver.vt_count,
            solver.vt_tri, solver.tv_count, solver.tv_vert, solver.ee_count, solver.ee_edge, c.self_radius,
            c.self_stiffness, c.self_friction, 1e-4, DT / c.substeps, *bufs])
        out.append([b.numpy().astype(np.float64).sum(0) for b in bufs])
    return out


def test_sweep_groups_add_up_to_the_one_group_sum(folded):
    model, solver, state = folded
    contacts = int(solver.vt_count.numpy().sum() + solver.ee_count.numpy().sum())
    on_body = int((solver.body_has.numpy() > 0).any(1).sum())
    assert contacts > 0 and on_body > 0, "the scene no longer has cloth-cloth and body contacts to share out"
    one = _partials(model, solver, state.positions, 1)
    for groups in (4, 7):
        many = _partials(model, solver, state.positions, groups)
        worst = 0.0
        for a, b in zip(one, many, strict=True):
            for x, y in zip(a, b, strict=True):
                scale = max(np.abs(x).max(), 1e-30)
                worst = max(worst, np.abs(x - y).max() / scale)
        print(f"\n{contacts} cloth-cloth contacts, {on_body} vertices on the body: {groups} groups against one, "
              f"largest difference {worst:.1e} of the largest entry")
        assert worst < 3e-5


def test_scene_dot_is_the_dot_product_of_each_scene(folded):
    import warp as wp

    from datagen.sim import newton_kernels as N

    rng = np.random.default_rng(0)
    n = 1000
    ranges = np.array([[0, 0], [0, 1], [1, 300], [300, 1000]], dtype=np.int32)  # empty, one vertex, two ranges
    a_np, b_np = rng.normal(size=(n, 3)).astype(np.float32), rng.normal(size=(n, 3)).astype(np.float32)
    want = [float((a_np[p0:p1].astype(np.float64) * b_np[p0:p1]).sum()) for p0, p1 in ranges]
    a, b = wp.array(a_np, dtype=wp.vec3), wp.array(b_np, dtype=wp.vec3)
    saved = wp.config.enable_cpu_blocks
    try:
        for blocks in (False, True):
            wp.config.enable_cpu_blocks = blocks
            out = wp.zeros(len(ranges), dtype=wp.float64)
            wp.launch_tiled(N.scene_dot, dim=[len(ranges)], block_dim=N.DOT_LANES,
                            inputs=[a, b, wp.array(ranges, dtype=wp.int32), out])
            np.testing.assert_allclose(out.numpy(), want, rtol=1e-6, atol=1e-9)
    finally:
        wp.config.enable_cpu_blocks = saved
