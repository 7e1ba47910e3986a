"""Physics of the cloth solver under dynamic loads, at the shipped presets (issue 59): longer frames,
a sharp-edged support, a drop onto it. Each run checks the mechanical energy balance
E = kinetic + elastic - work of gravity, which with a static support can only fall, and, where
statics has an answer, that the cloth settles there. ``python -m benchmarks physics-limits`` prints
the same cases at every preset and more frame rates, strains and edge lengths (docs/simulator.md).

The tolerance on E is the hanging-strip tests': a rise above its running minimum of at most
max(1e-7 J, 1e-3 x gravity's work). The positions are float32: a vertex of a 0.5 m strip is resolved
to 3e-8 m, and the energies summed from them (float64) move by about 1e-8 J on these scenes between
two frames that do nothing; the relative part allows for the penalty contact's stored energy, which
E leaves out (m g / k_c of compression a vertex: below 1e-9 J on these meshes).
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.physics_limits import disc_model, run, square_cylinder, strip_model, strip_static
from datagen.materials import MATERIALS
from datagen.sim.settings import StepConfig
from datagen.sim.solver import SolverConfig, SolverVBD


def energy_tolerance(work: float) -> float:
    """The largest rise of E above its running minimum taken as rounding [J] (module doc)."""
    return max(1e-7, 1e-3 * abs(work))


def test_substeps_follow_the_frame_time_and_the_edge_length():
    """A frame of dt has max(substeps, ceil(dt / max_substep)) substeps: the production 10 at 30 fps
    (and at 60: never fewer than ``substeps``), 20 at 15 fps, 60 at 5, 13 at 24; a mesh finer than
    ``substep_edge`` (1.5 cm) takes substeps shorter in proportion: 15 at 1 cm and 30 fps, 12 at the
    skirt's 1.3 cm. The solver's edge length is the smallest scene's median."""
    from benchmarks.physics_limits import strip_model
    from datagen.sim.solver import mesh_edge_length

    steps = StepConfig()
    assert [steps.substeps_for(1.0 / fps) for fps in (30, 60, 15, 5, 24)] == [10, 10, 20, 60, 13]
    assert [steps.substeps_for(1.0 / 30, edge) for edge in (0.01, 0.013, 0.015, 0.02, 0.005)] == [15, 12, 10, 10, 30]
    assert StepConfig(substeps=20).substeps_for(1.0 / 30) == 20
    assert StepConfig(max_substep=0.1).substeps_for(1.0 / 5) == 10
    assert StepConfig(substep_edge=0.0).substeps_for(1.0 / 30, 0.005) == 10
    model, _v, _bottom = strip_model(MATERIALS["cotton"])
    assert mesh_edge_length(model.host) == pytest.approx(0.01)
    assert SolverVBD(model, SolverConfig(self_collision=False)).substeps_for(1.0 / 30) == 15


def test_a_frame_time_or_edge_length_the_solver_cannot_hold_is_refused_with_what_to_do():
    """A step that the substep rule would split into more than ``substep_cap`` (100) substeps is
    refused before anything runs, with an InputError that names the frame rate (and, where a
    finer mesh is the cause, the edge length) that would do: 2 frames/s at 1.5 cm edges (150
    substeps), and a patch of 1 mm edges at 30 fps (150) through the solver's own step. ``substeps``
    set that high by hand is taken as asked; a raised cap lets the rule through."""
    from datagen.errors import InputError
    from datagen.sim.model import ClothModelBuilder
    from datagen.sim.state import BodyControl, ClothState
    from benchmarks.physics_limits import strip_mesh

    steps = StepConfig()
    with pytest.raises(InputError, match=r"needs 150 substeps.*substep_cap = 100.*3 frames/s or more"):
        steps.substeps_for(0.5, 0.015)
    assert StepConfig(substep_cap=150).substeps_for(0.5, 0.015) == 150
    assert StepConfig(substeps=150).substeps_for(1.0 / 30, 0.001) == 150
    assert steps.substeps_for(1.0 / 5, 0.01) == 90  # 5 frames/s on the 1 cm strip: held
    v, f, frames, top, _bottom = strip_mesh(dx=0.001, width=0.004, length=0.004)
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name="cotton", pinned=top, material_frames=frames)
    model = b.finalize("cpu")
    solver = SolverVBD(model, SolverConfig(self_collision=False))
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    refused = r"1 mm edges needs 150 substeps.*45 frames/s or more.*edges of 1.5 mm or longer"
    with pytest.raises(InputError, match=refused):
        solver.step(s0, s1, BodyControl.from_numpy(model, model.host.body_rest), 1.0 / 30)


@pytest.mark.parametrize("name", list(MATERIALS))
def test_a_strip_at_15_fps_hangs_at_its_static_elongation_without_making_energy(name):
    """The 5 cm x 50 cm strip of every preset, hanging for 2 s at 15 frames/s (no air drag,
    self-collision off): within 1 % of its static elongation (the mean of the last 0.5 s) and E
    never above its running minimum beyond rounding. With the substeps fixed at 10 a frame (the
    code before 59) polyester hung 6 % short and every woven made energy (up to 1.1x gravity's work)."""
    mat = MATERIALS[name]
    exact = strip_static(mat)
    config = SolverConfig(air_drag=0.0, self_collision=False)
    model, _v, bottom = strip_model(mat)
    fps = 15.0
    r = run(model, config, int(2 * fps), fps, watch=bottom)
    elong = -r.heights[-int(0.5 * fps):].mean() - 0.5
    error = (elong - exact) / exact
    print(f"\n{name} strip at 15 fps ({config.steps.substeps_for(1 / fps, 0.01)} substeps a frame): elongation "
          f"{elong * 1e3:.4f} mm against {exact * 1e3:.4f} mm ({100 * error:+.2f} %), E rise max {r.rise.max():+.2e} J "
          f"(gravity's work {r.work:.2e} J)")
    assert abs(error) < 0.01
    assert r.rise.max() <= energy_tolerance(r.work)


@pytest.mark.parametrize("name", ["jersey", pytest.param("cotton", marks=pytest.mark.xfail(
    strict=True, reason="issue 59: cotton (buckling ratio 0.1) makes +2.3e-2 J (0.5 % of the released energy) "
    "while it bounces: the global step's 20 conjugate-gradient iterations do not carry the long waves of the "
    "recoil (rᵀP⁻¹r down 1.0e-4 of its start at the median substep, 3.8e-7 with 100); 60 iterations with 15 "
    "sweeps pass (+1.8e-6 J), at +1 % CPU time a frame on the walking T-shirt, but then denim on the square rim makes +7.4e-4 J"))])
def test_a_strip_released_from_35_percent_makes_no_energy(name):
    """The 50 cm strip started 35 % longer (beyond the lock at 30 %) and let go, 1 s (self-collision
    off, no air drag): E never above its running minimum beyond rounding (1e-7 J or 1e-5 x the
    elastic energy released, 0.33 J for jersey: float32 positions resolve a strain to about 1e-7, the
    energy, quadratic in it, to about 1e-6 of itself). It does not
    settle within 1 s (the strip snaps back and passes through itself, self-collision off), so no
    static answer is checked. Before 59 (10 substeps a frame) jersey made +1.0e-3 J in 2 s; the
    wovens make +5e-3 to +4e-2 J."""
    mat = MATERIALS[name]
    config = SolverConfig(air_drag=0.0, self_collision=False)
    model, v, bottom = strip_model(mat)
    r = run(model, config, 30, 30.0, positions=v * np.array([1.0, 1.35, 1.0]), watch=bottom)
    print(f"\n{name} strip released from 35 %, 1 s: E rise max {r.rise.max():+.2e} J (E at the start {r.start:.3e} J)")
    assert r.start > 0.1
    assert r.rise.max() <= max(1e-7, 1e-5 * r.start)


@pytest.fixture(scope="module")
def square_rim():
    return square_cylinder()


@pytest.mark.parametrize("name", list(MATERIALS))
def test_a_disc_dropped_on_a_square_rim_makes_no_energy(name, square_rim):
    """A 30 cm disc (1.5 cm edges) dropped from 1 mm above its contact distance onto a plain
    cylinder with a square rim, 4 frames at the production settings, every preset: E never above
    its running minimum beyond rounding. Before 59 the vertices whose closest point was on the rim's
    edge got an adjacent face's plane extended past it and were pushed out 5 mm from the real edge:
    cotton +0.067 J, denim +0.30 J by frame 8 (gravity had done 1e-3 J); with the closest feature's
    normal denim still made +2.1e-3 J by frame 2 until the global step started from the last
    substep's correction (``StepConfig.warm_start``; without it wool made +4.6e-4 J; with the lock's
    full Hessian in the global step, not kept, wool made +9.2e-4 J: the rise is sensitive)."""
    mat = MATERIALS[name]
    config = SolverConfig()
    model = disc_model(mat, 0.015, square_rim, config)
    r = run(model, config, 4, 30.0)
    print(f"\n{name} disc on a square rim, 4 frames: E rise max {r.rise.max():+.2e} J (gravity's work {r.work:.2e} J)")
    assert r.work > 0
    assert r.rise.max() <= energy_tolerance(r.work)


def test_the_contact_query_pushes_a_vertex_by_a_sharp_rim_to_r_from_the_real_edge(square_rim):
    """``kernels.detect_body`` on the square-rimmed cylinder: a vertex 1 mm above its top is pushed
    up to the contact distance r; a vertex 2 mm beside the rim and 1 mm above its top, whose closest
    point is on the rim's edge, gets the edge's normal (from that point to the vertex) and is pushed
    along it to r from the real edge, not to r above the top face's plane extended past the edge
    (which moved it 2.5 mm up and held cloth off a rim that is not there)."""
    import warp as wp

    from datagen.sim import kernels as K
    from datagen.sim.model import ClothModelBuilder
    from datagen.sim.state import BodyControl

    config = SolverConfig()
    cloth = np.array([[0.0, 0.001, 0.0], [0.09 + 0.002, 0.001, 0.0], [0.0, 0.001, 0.02]])
    b = ClothModelBuilder()
    b.add_cloth(cloth, np.array([[0, 1, 2]]), material_name="cotton")
    b.add_body(*square_rim)
    model = b.finalize("cpu")
    solver = SolverVBD(model, config)
    rest = model.host.body_rest.astype(np.float32)
    solver.place_body(BodyControl.from_numpy(model, rest))
    body = wp.array(rest, dtype=wp.vec3)
    pos = wp.array(cloth.astype(np.float32), dtype=wp.vec3)
    y = wp.array(cloth.astype(np.float32), dtype=wp.vec3)
    wp.launch(K.detect_body, 3, inputs=[
        solver.body_ids, model.body_face_base, model.body_face_part, model.body_face_border, pos,
        model.particle_scene, model.body_faces, body, body, config.body_query, solver.body_radius, model.active, y,
        solver.body_has, solver.body_point, solver.body_normal, solver.body_disp, solver.vertex_order])
    x = pos.numpy().astype(np.float64)
    r = float(solver.body_radius.numpy()[0])
    n = solver.body_normal.numpy()[1, 0].astype(np.float64)
    point = solver.body_point.numpy()[1, 0].astype(np.float64)
    away = cloth[1] - point
    print(f"\ncontact radius {r * 1e3:.2f} mm; the vertex over the top now {x[0, 1] * 1e3:.4f} mm high; the vertex by "
          f"the rim {np.linalg.norm(x[1] - point) * 1e3:.4f} mm from the edge ({x[1, 1] * 1e3:.4f} mm high), edge "
          f"normal {n}")
    np.testing.assert_allclose(x[0], [0.0, r, 0.0], atol=2e-6)
    np.testing.assert_allclose(n, away / np.linalg.norm(away), atol=1e-4)
    assert n[0] > 0.5 and n[1] > 0.2  # between the top's +Y and the side's +X
    assert abs(np.linalg.norm(x[1] - point) - r) < 2e-6  # r from the real edge
    assert x[1, 1] < r - 0.0005  # not r above the extended top plane
