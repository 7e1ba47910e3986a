"""Settings that change how kernels are launched, not what they compute: ``SolverConfig.register_caps``
runs some kernels as register-capped copies of themselves (``detection_kernels.register_capped``: the
same code under CUDA's ``__launch_bounds__``), ``SolverConfig.coherent_order`` launches the tree
queries in Morton order (``model.launch_order``); the same result, bitwise. ``SolverConfig.sweep_lanes``
splits a vertex's sums in the sweeps over several threads of a warp: the same result up to the
order of the additions (on a CPU one thread walks each vertex)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.sim.metrics import Metrics
from datagen.sim.model import ClothModelBuilder
from datagen.sim.solver import REGISTER_CAPS, SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState
from tests.sim.meshes import grid
from tests.sim.test_projection_skip import _devices

FPS = 30


def _run(caps: str, device: str, frames: int = 8, **config):
    """Two 30 cm cotton layers 5 mm apart (one mesh) falling onto a sphere: cloth-cloth contacts
    between the layers from the first substep, body contact and projection once they land.
    Returns the positions and metrics of every frame and the contacts the last detection found."""
    import trimesh

    lower_v, lower_f = grid(13, 13, 0.025, y=0.0)
    upper_v, upper_f = grid(13, 13, 0.025, y=0.005, centre=(0.006, 0.004))
    v = np.vstack([lower_v, upper_v])
    f = np.vstack([lower_f, upper_f + len(lower_v)])
    s = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name="cotton")
    sv, sf = np.asarray(s.vertices, dtype=np.float64) + [0.0, -0.11, 0.0], np.asarray(s.faces, dtype=np.int64)
    b.add_body(sv, sf)
    model = b.finalize(device)
    solver = SolverVBD(model, SolverConfig(register_caps=caps, substeps=4, iterations=8, **config))
    metrics = Metrics(model)
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    out = []
    for _ in range(frames):
        solver.step(s0, s1, BodyControl.from_numpy(model, sv), 1.0 / FPS)
        s0, s1 = s1, s0
        out.append((s0.numpy()[0].copy(), metrics.measure(s0, solver)))
    contacts = int(solver.vt_count.numpy().sum() + solver.ee_count.numpy().sum())
    return out, contacts


@pytest.mark.parametrize("device", _devices())
def test_capped_kernels_give_the_same_result(device):
    reference, contacts = _run("none", device)
    assert contacts > 0  # the layers touch: the capped detection kernels had work to do
    for caps in ("detection",):
        capped, capped_contacts = _run(caps, device)
        assert capped_contacts == contacts
        for k, ((a, ma), (b, mb)) in enumerate(zip(reference, capped)):
            assert np.array_equal(a, b), f"{caps}, frame {k}: moved by up to {np.abs(a - b).max():.3e} m"
            assert all(np.array_equal(ma[name], mb[name]) for name in ma), f"{caps}, frame {k}: metrics differ"


def test_register_caps_are_checked():
    assert set(REGISTER_CAPS) == {"none", "detection"}
    with pytest.raises(InputError, match="LaunchConfig.register_caps = 'some' is not allowed; choose one of 'none', "
                                         "'detection'"):
        SolverConfig(register_caps="some")
    for lanes in (12, 64):
        with pytest.raises(InputError, match=f"LaunchConfig.sweep_lanes = {lanes} is not allowed; .*: a power of two"):
            SolverConfig(sweep_lanes=lanes)


@pytest.mark.parametrize("device", _devices())
def test_sweep_lanes_split_the_sums_not_the_result(device):
    """Every colour's sweep from one state (two frames in: cloth-cloth contacts and body planes)
    with 2 to 32 threads a vertex gives one thread a vertex's steps up to rounding (the sums are
    added in another order); on a CPU one thread walks each vertex whatever ``sweep_lanes`` says,
    bitwise. (Whole runs are not compared: this scene of two layers landing is chaotic, and a change
    of 1e-7 in the Chebyshev radius moves it by a millimetre a frame later.)"""
    import warp as wp

    from datagen.sim import solver as solver_module

    built = []
    init = solver_module.SolverVBD.__init__

    def keep(self, *args, **kwargs):
        init(self, *args, **kwargs)
        built.append(self)

    solver_module.SolverVBD.__init__ = keep
    try:
        _run("detection", device, frames=2)
    finally:
        solver_module.SolverVBD.__init__ = init
    solver = built[0]
    assert solver.vt_count.numpy().sum() > 0 and solver.body_has.numpy().any()  # contacts of both kinds
    x = solver.x_nm1  # the last sweep's start

    def sweep(lanes: int) -> np.ndarray:
        solver.config = dataclasses.replace(solver.config, sweep_lanes=lanes)
        outs = []
        for col in solver.colours:
            out = wp.clone(x)
            solver._solve_colour(col, x, out)  # at the last step's substep length
            outs.append(out.numpy()[col.numpy()])
        return np.concatenate(outs)

    one = sweep(1)
    moved = np.abs(one - np.concatenate([x.numpy()[c.numpy()] for c in solver.colours])).max()
    assert moved > 1.0e-5  # the sweep does move the cloth
    for lanes in (2, 16, 32):
        split = sweep(lanes)
        if device == "cpu":
            assert np.array_equal(split, one), f"{lanes} lanes on the CPU"
        else:
            assert np.abs(split - one).max() < 1.0e-4 * moved, f"{lanes} lanes"
            assert np.array_equal(sweep(lanes), split)  # the same bits again


@pytest.mark.parametrize("device", _devices())
def test_coherent_launch_order_gives_the_same_result(device):
    """``SolverConfig.coherent_order`` launches the tree queries in Morton order and sorts the sweep
    colours the same way: every position and metric of every frame bitwise as in index order."""
    reference, contacts = _run("detection", device, coherent_order=False)
    ordered, ordered_contacts = _run("detection", device, coherent_order=True)
    assert ordered_contacts == contacts > 0
    for k, ((a, ma), (b, mb)) in enumerate(zip(reference, ordered)):
        assert np.array_equal(a, b), f"frame {k}: moved by up to {np.abs(a - b).max():.3e} m"
        assert all(np.array_equal(ma[name], mb[name]) for name in ma), f"frame {k}: metrics differ"


def test_launch_order_is_a_spatially_coherent_permutation_per_scene():
    from datagen.sim.model import launch_order

    rng = np.random.default_rng(0)
    v, _ = grid(33, 33, 0.01)
    shuffled = v[rng.permutation(len(v))]
    pts = np.vstack([shuffled, shuffled])  # two scenes of one garment (scenes overlap in space)
    ranges = np.array([[0, len(v)], [len(v), 2 * len(v)]])
    order = launch_order(pts, ranges)
    assert order.dtype == np.int32
    assert sorted(order[:len(v)].tolist()) == list(range(len(v)))  # each scene keeps its own range
    assert sorted(order[len(v):].tolist()) == list(range(len(v), 2 * len(v)))
    assert np.array_equal(order[len(v):] - len(v), order[:len(v)])  # a scene's order is its own alone

    def warp_spread(p):  # median diagonal of the boxes of 32 consecutive points
        w = p[:len(p) // 32 * 32].reshape(-1, 32, 3)
        return float(np.median(np.linalg.norm(w.max(1) - w.min(1), axis=1)))

    assert warp_spread(pts[order[:len(v)]]) < 0.3 * warp_spread(shuffled)
    assert launch_order(np.zeros((1, 3)), np.array([[0, 1]])).tolist() == [0]
