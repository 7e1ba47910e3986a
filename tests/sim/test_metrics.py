"""The simulator's measures (``datagen.sim.metrics``: on the host, and per frame on the device)
against their definitions."""

from __future__ import annotations

import numpy as np
import pytest

from datagen.sim.metrics import principal_strain


def test_principal_strain_is_the_largest_stretch_minus_one():
    """A triangle stretched by 1.1 along one in-plane direction and 0.95 across it, then rotated
    and moved: its largest principal strain is 0.1, whatever its orientation; a mesh at rest has 0."""
    rng = np.random.default_rng(0)
    rest = np.array([[0.0, 0.0, 0.0], [0.02, 0.0, 0.0], [0.007, 0.015, 0.0]])
    faces = np.array([[0, 1, 2]])
    a = np.radians(30.0)
    d = np.array([np.cos(a), np.sin(a), 0.0])
    e = np.array([-np.sin(a), np.cos(a), 0.0])
    stretch = 1.1 * np.outer(d, d) + 0.95 * np.outer(e, e) + np.outer([0, 0, 1.0], [0, 0, 1.0])
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moved = rest @ stretch.T @ q.T + np.array([0.3, -1.0, 2.0])
    assert np.allclose(principal_strain(rest, faces, moved), [0.1], atol=1e-12)
    assert np.allclose(principal_strain(rest, faces, np.stack([rest, moved])), [[0.0], [0.1]], atol=1e-12)


def test_per_frame_stretch_energy_and_nan_match_their_host_definitions():
    """The per-frame metrics computed on the device (stretch, kinetic energy, non-finite values,
    depth) equal their float64 numpy definitions, scene by scene: three scenes of different
    sizes and materials, each with a sphere body, the cloth moved at random; scene 1 holds a NaN
    velocity and scene 2 a NaN position."""
    import trimesh

    from datagen.sim.metrics import Metrics
    from datagen.sim.model import ClothModelBuilder
    from datagen.sim.solver import SolverConfig, SolverVBD
    from datagen.sim.state import ClothState
    from tests.sim.meshes import grid

    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.1)
    b = ClothModelBuilder()
    for s, (n, mat) in enumerate(((4, "cotton"), (6, "silk"), (5, "denim"))):
        b.add_cloth(*grid(n, n, 0.02, y=0.12), material_name=mat, scene=s)
        b.add_body(np.asarray(sphere.vertices), np.asarray(sphere.faces), scene=s)
    model = b.finalize("cpu")
    solver = SolverVBD(model, SolverConfig())
    rng = np.random.default_rng(3)
    h = model.host
    x = h.rest_positions + rng.normal(scale=0.004, size=h.rest_positions.shape)
    x[h.particle_range[0, 0]] = [0.0, 0.05, 0.0]  # inside scene 0's sphere, 5 cm deep
    v = rng.normal(size=x.shape)
    v[h.particle_range[1, 0] + 2, 1] = np.nan
    x[h.particle_range[2, 0] + 1, 0] = np.nan
    state = ClothState.from_model(model, x)
    state.velocities.assign(v.astype(np.float32))
    got = Metrics(model).measure(state, solver)

    x64 = x.astype(np.float32).astype(np.float64)
    v64 = v.astype(np.float32).astype(np.float64)
    F, D = h.faces, h.dm_inv
    e1, e2 = x64[F[:, 1]] - x64[F[:, 0]], x64[F[:, 2]] - x64[F[:, 0]]
    f0 = e1 * D[:, 0, 0, None] + e2 * D[:, 1, 0, None]
    f1 = e1 * D[:, 0, 1, None] + e2 * D[:, 1, 1, None]
    a, bb, c = (f0 * f0).sum(1), (f1 * f1).sum(1), (f0 * f1).sum(1)
    stretch = np.nan_to_num(np.sqrt(np.maximum(0.5 * (a + bb) + np.sqrt(0.25 * (a - bb) ** 2 + c * c), 0.0)) - 1.0,
                            nan=np.inf)
    ke = np.nan_to_num(0.5 * h.mass * (v64 * v64).sum(1), nan=np.inf)
    fs, vs = h.particle_scene[F[:, 0]], h.particle_scene
    for s in range(3):
        sel = fs == s
        assert np.isclose(got["stretch_max"][s], stretch[sel].max(), rtol=1e-12, atol=0)
        mean = (stretch[sel] * h.tri_area[sel]).sum() / h.tri_area[sel].sum()
        assert np.isclose(got["stretch_mean"][s], mean, rtol=1e-12, atol=0) or (np.isinf(mean) and np.isinf(
            got["stretch_mean"][s]))
        k = ke[vs == s].sum()
        assert np.isclose(got["kinetic_energy"][s], k, rtol=1e-12) or (np.isinf(k) and np.isinf(got["kinetic_energy"][s]))
    assert got["nan"].tolist() == [False, False, True]
    assert np.isinf(got["kinetic_energy"][1]) and np.isfinite(got["kinetic_energy"][[0]]).all()
    assert np.isinf(got["stretch_max"][2]) and np.isfinite(got["stretch_max"][:2]).all()
    assert got["penetration_count"][0] >= 1 and abs(got["penetration_depth"][0] - 0.05) < 0.005


def test_principal_strain_against_a_cut_reads_the_panel_not_a_3d_template():
    """A pattern garment's strain is measured against its cut (per-corner 2D rest): a triangle cut as a
    unit right triangle, placed turned in 3D and stretched 10 % along its first edge, reads 0.1 whatever
    3D template is given, and the same as against a flat 3D copy of the cut."""
    from datagen.sim.metrics import principal_strain

    cut = np.array([[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]])
    faces = np.array([[0, 1, 2]])
    turn = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    placed = np.array([[0.0, 0.0, 0.0], [1.1, 0.0, 0.0], [0.0, 1.0, 0.0]]) @ turn.T
    squeezed_template = np.array([[0.0, 0.0, 0.0], [0.63, 0.0, 0.0], [0.0, 1.0, 0.0]])
    flat = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    assert principal_strain(squeezed_template, faces, placed, rest_corners=cut)[0] == pytest.approx(0.1, abs=1e-12)
    assert principal_strain(flat, faces, placed)[0] == pytest.approx(0.1, abs=1e-12)
    assert principal_strain(squeezed_template, faces, placed)[0] > 0.7  # the artefact: against the squeezed template
