"""``simulate`` (the batched scene runner) records every frame's own positions, and refuses a batch
too large for its device before allocating anything."""

from __future__ import annotations

import numpy as np
import pytest

import datagen.sim.device as dv
import datagen.sim.scene as sc
from datagen.errors import SimulationError
from datagen.materials import MATERIALS
from datagen.sim.scene import RunConfig, SceneArrays, simulate


def falling_patch(n: int = 6, T: int = 8) -> SceneArrays:
    """An n x n cotton patch 1 m above a small tetrahedron far below it (it falls freely)."""
    u = np.linspace(0.0, 0.2, n)
    gx, gz = np.meshgrid(u, u, indexing="ij")
    verts = np.stack([gx.ravel(), np.ones(n * n), gz.ravel()], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, c, b], 1), np.stack([a, d, c], 1)])
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), (len(faces), 1, 1))
    body = np.array([[0.0, -10.0, 0.0], [0.1, -10.0, 0.0], [0.0, -10.0, 0.1], [0.0, -9.9, 0.0]])  # far below
    body_faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return SceneArrays(garment_vertices=verts, garment_faces=faces, material=MATERIALS["cotton"],
                       material_frames=frames,
                       weft_scale=np.ones(len(faces)),
                       body_frames=np.repeat(body[None], T, 0), body_faces=body_faces, fps=30.0, lead_frames=0)


def test_recorded_frames_are_copies_not_views_of_the_state_buffers():
    """On the CPU warp's ``.numpy()`` is a view of the array: recording it would make every
    frame alias one of the two ping-pong states. A falling cloth must have a lower mean height
    in each recorded frame than in the one before."""
    scene = falling_patch()
    config = RunConfig(settle_rest=1, lead_in=0.0, settle_pose=0, ramp=0.0)
    (result,) = simulate([scene], config, device="cpu")
    heights = result.positions[..., 1].mean(axis=1)
    assert len(heights) >= 5
    assert np.all(np.diff(heights) < -1e-4), heights


def test_a_batch_too_large_for_the_device_is_refused_before_anything_is_allocated(monkeypatch):
    """The batch's memory is estimated from its garment and body vertices and compared with what
    the device has free; a batch that does not fit is refused with both figures and what to do,
    before the model is built (here the device is told to have 1 MiB free)."""
    scenes = [falling_patch(), falling_patch(n=20)]
    need = dv.check_device_memory(scenes, "cpu")
    assert need == (36 + 400) * dv.BYTES_PER_GARMENT_VERTEX + 2 * 4 * dv.BYTES_PER_BODY_VERTEX
    monkeypatch.setattr(dv, "device_free_bytes", lambda device: 2**20)
    built = []
    monkeypatch.setattr(sc.ClothModelBuilder, "finalize", lambda *a, **k: built.append(1))
    with pytest.raises(SimulationError) as exc:
        simulate(scenes, RunConfig(settle_rest=1, lead_in=0.0, settle_pose=0, ramp=0.0), device="cpu")
    msg = str(exc.value)
    assert "a batch of 2 scenes (largest garment 400 vertices) needs about 2 MiB" in msg and "1 MiB free" in msg
    assert "simulation.batch_size" in msg and "garment_edge_length" in msg
    assert built == []


def test_phases_count_the_frames_the_schedule_simulates():
    from datagen.sim.scene import RunConfig, frame_schedule

    for rc, fps, recorded in ((RunConfig(), 30.0, 60), (RunConfig(settle_rest=10, settle_pose=5, ramp=0.5), 30.0, 60),
                              (RunConfig(), 24.0, 7)):
        lead = round(rc.lead_in * fps)
        schedule, first = frame_schedule(rc, lead, lead + rc.motion_frames(recorded, fps), fps)
        phases = rc.phases(recorded, fps)
        assert sum(phases.values()) == len(schedule) and first == len(schedule) - recorded, (phases, len(schedule))


def test_a_failed_scene_is_frozen_and_the_other_scenes_do_not_change(monkeypatch):
    """``RunConfig.freeze_failed``: from the frame a scene fails it is no longer simulated, its
    vertices held where they were (here a falling patch made to fail at its fourth frame stops in
    mid-air); another scene of the batch gives bitwise the positions it gives when the failed scene
    runs to the end; the failure and its frame are the same either way."""
    from datagen.sim.metrics import Failure, Metrics

    calls = {"n": 0}

    def fail_scene_1_at_frame_3(self, frame, scene, thresholds):
        if scene != 1:
            return None
        calls["n"] += 1
        return Failure("stretch", "made to fail by the test") if calls["n"] >= 4 else None

    monkeypatch.setattr(Metrics, "failure", fail_scene_1_at_frame_3)
    runs = {}
    for freeze in (True, False):
        calls["n"] = 0
        config = RunConfig(settle_rest=1, lead_in=0.0, settle_pose=0, ramp=0.0, freeze_failed=freeze)
        runs[freeze] = simulate([falling_patch(), falling_patch(n=7)], config, device="cpu")
    frozen, free = runs[True], runs[False]
    assert frozen[1].failure_frame == free[1].failure_frame == 3 and frozen[1].failure.code == "stretch"
    assert frozen[0].failure is None and np.array_equal(frozen[0].positions, free[0].positions)
    k = frozen[1].failure_frame - frozen[1].recorded_from  # the recorded frame where it failed
    after = frozen[1].positions[k:]
    assert len(after) >= 3 and all(np.array_equal(p, after[0]) for p in after)
    assert np.array_equal(frozen[1].positions[:k + 1], free[1].positions[:k + 1])  # the same until it failed
    heights = free[1].positions[k:, :, 1].mean(axis=1)  # run to the end, it keeps falling
    assert np.all(np.diff(heights) < -1e-4)


def test_batch_poses_each_body_motion_once_and_gives_each_scene_its_own_arrays(small_model, monkeypatch):
    """A batch of three garments over two motions poses the body twice (once per motion), and every
    scene's arrays equal those made for it alone."""
    import dataclasses

    from datagen.motion.library import make_motion

    betas = np.zeros(10)
    walk, wave = make_motion("walk", seed=0, frames=12, fps=30.0), make_motion("wave", seed=0, frames=12, fps=30.0)
    v = np.asarray(small_model.shaped(betas.reshape(1, -1)))[0]
    garment = type("G", (), {})()  # the fields scene_arrays reads from a garment
    garment.vertices, garment.faces, garment.material = v[:30].copy(), np.array([[0, 1, 2], [1, 2, 3]]), MATERIALS["silk"]
    garment.material_frames = lambda: np.tile(np.eye(2, 3), (2, 1, 1))
    garment.weft_rest_scale = lambda: np.ones(2)
    scenes = [sc.Scene(garment=garment, body=small_model, betas=betas, motion=m) for m in (walk, wave, walk)]
    calls = []
    real = sc._posed_body
    monkeypatch.setattr(sc, "_posed_body", lambda s, lead_in, *a: calls.append(id(s.motion)) or real(s, lead_in, *a))
    batch = sc.batch_arrays(scenes, 0.2)
    assert sorted(calls) == sorted([id(walk), id(wave)])
    for s, a in zip(scenes, batch, strict=True):
        alone = sc.scene_arrays(s, 0.2)
        for f in dataclasses.fields(alone):
            x, y = getattr(alone, f.name), getattr(a, f.name)
            if isinstance(x, np.ndarray):
                np.testing.assert_array_equal(x, y, err_msg=f.name)
    assert not np.array_equal(batch[0].body_frames, batch[1].body_frames)


def test_posing_with_the_torch_body_agrees_with_numpy(small_model):
    """The float64 torch posing that a CUDA batch uses (here on the CPU) gives the numpy posing's
    float32 body frames to an ulp, the same lead-in shift and the same face parts."""
    import torch

    from datagen.motion.library import make_motion

    betas = np.linspace(-1.0, 1.0, 10)
    walk = make_motion("walk", seed=3, frames=20, fps=30.0)
    garment = type("G", (), {})()
    scene = sc.Scene(garment=garment, body=small_model, betas=betas, motion=walk)
    a = sc._posed_body(scene, 0.2)
    b = sc._posed_body(scene, 0.2, small_model.torch(dtype=torch.float64, device="cpu"))
    assert a[1] == b[1] and a[2].dtype == b[2].dtype == np.float32 and a[2].shape == b[2].shape
    np.testing.assert_allclose(b[2], a[2], rtol=0, atol=4e-7)  # metres: a float32 ulp at 2-4 m
    np.testing.assert_allclose(b[3], a[3], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(b[4], a[4])
    assert not dv.torch_cuda("cpu") and not dv.torch_cuda(None)


def test_run_config_selects_its_solver_by_name_and_refuses_an_unknown_one():
    """``RunConfig.solver_name`` picks a solver of ``datagen.sim.interface.SOLVERS`` (the VBD solver by
    default, which satisfies the ``ClothSolver`` protocol); an unknown name is refused with the known ones,
    built directly or from a config mapping."""
    from datagen.config import load_config
    from datagen.errors import ConfigError, InputError
    from datagen.sim.interface import SOLVERS, ClothSolver, solver_class
    from datagen.sim.solver import SolverVBD

    from datagen.sim.interface import make_solver
    from datagen.sim.model import ClothModelBuilder
    from datagen.sim.solver import SolverConfig
    from tests.sim.meshes import grid

    assert RunConfig().solver_name == "vbd" and solver_class("vbd") is SolverVBD and set(SOLVERS) == {"vbd"}
    b = ClothModelBuilder()
    b.add_cloth(*grid(3, 3, 0.05), material_name="cotton")
    solver = make_solver("vbd", b.finalize("cpu"), SolverConfig())
    assert type(solver) is SolverVBD and isinstance(solver, ClothSolver) and solver.probes == ()
    with pytest.raises(InputError, match=r"unknown solver 'xpbd'; known solvers: vbd"):
        RunConfig(solver_name="xpbd")
    with pytest.raises(ConfigError, match=r"solver_name = 'xpbd' is not allowed; choose one of \['vbd'\]"):
        load_config(RunConfig, {"solver_name": "xpbd"})
