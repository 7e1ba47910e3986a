"""Settings that change how kernels are launched, not what they compute: ``SolverConfig.register_caps``
runs some kernels as register-capped copies of themselves (``detection_kernels.register_capped``: the
same code under CUDA's ``__launch_bounds__``), ``SolverConfig.coherent_order`` launches the tree
queries in Morton order (``model.launch_order``); the same result, bitwise."""

from __future__ import annotations

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
    for caps in ("detection", "all"):
        capped, capped_contacts = _run(caps, device)
        assert capped_contacts == contacts
        for k, ((a, ma), (b, mb)) in enumerate(zip(reference, capped)):
            assert np.array_equal(a, b), f"{caps}, frame {k}: moved by up to {np.abs(a - b).max():.3e} m"
            assert all(np.array_equal(ma[name], mb[name]) for name in ma), f"{caps}, frame {k}: metrics differ"


def test_register_caps_are_checked():
    assert set(REGISTER_CAPS) == {"none", "detection", "all"}
    with pytest.raises(InputError, match="register_caps must be one of none, detection, all"):
        SolverConfig(register_caps="some")


@pytest.mark.parametrize("device", _devices())
def test_coherent_launch_order_gives_the_same_result(device):
    """``SolverConfig.coherent_order`` launches the tree queries in Morton order and sorts the sweep
    colours the same way: every position and metric of every frame bitwise as in index order."""
    reference, contacts = _run("detection", device)
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
