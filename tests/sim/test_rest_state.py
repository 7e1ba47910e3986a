"""The flat rest state of sewing-pattern cloth: ``ClothModelBuilder.add_cloth(rest_corners=...)``.

A face's reference shape, rest area and mass come from its corners' 2D panel coordinates; hinges
rest flat. Shell cloth (no 2D coordinates) keeps its 3D rest shape (the physics tests and
``python -m benchmarks sim-positions-digest`` check that bit for bit).
"""

from __future__ import annotations

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.sim.metrics import elastic_energy
from datagen.sim.model import ClothModelBuilder, flat_rest_shape


def _grid(nx: int, ny: int, dx: float) -> tuple[np.ndarray, np.ndarray]:
    """A flat grid in 2D [V, 2] and its triangles [F, 3] (counter-clockwise)."""
    X, Y = np.meshgrid(np.arange(nx) * dx, np.arange(ny) * dx, indexing="ij")
    uv = np.stack([X.ravel(), Y.ravel()], 1)
    f = [[i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1] for i in range(nx - 1) for j in range(ny - 1)]
    f += [[i * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1] for i in range(nx - 1) for j in range(ny - 1)]
    return uv, np.array(f)


def _model(x3: np.ndarray, faces: np.ndarray, corners: np.ndarray | None, grain=None, material="cotton"):
    b = ClothModelBuilder()
    b.add_cloth(x3, faces, material_name=material, rest_corners=corners, grain=grain)
    return b.finalize("cpu")


def test_a_sheared_panel_has_no_energy_at_its_2d_shape_and_some_where_it_was_placed():
    """A panel cut as a sheared parallelogram (grain at 30 degrees) and placed as a square: the
    membrane's reference is the cut, so the cloth laid out as cut (turned and moved in 3D) stores
    no energy, the square it was placed as does, and the rest area and mass are the cut's."""
    uv, f = _grid(6, 5, 0.04)
    shear = np.array([[1.0, 0.5], [0.0, 1.0]])
    cut = uv @ shear.T
    a = np.deg2rad(30)
    grain = np.tile([np.sin(a), np.cos(a)], (len(f), 1))
    placed = np.stack([uv[:, 0], np.zeros(len(uv)), uv[:, 1]], 1)  # the unsheared square, in y = 0
    model = _model(placed, f, cut[f], grain)
    # the cut laid out in 3D: turned about an arbitrary axis and moved
    rot = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))[0]
    laid = np.stack([cut[:, 0], cut[:, 1], np.zeros(len(cut))], 1) @ rot.T + [0.3, 1.2, -0.4]
    assert elastic_energy(model.host, laid) < 1e-12
    assert elastic_energy(model.host, placed) > 1e-4
    e1, e2 = cut[f[:, 1]] - cut[f[:, 0]], cut[f[:, 2]] - cut[f[:, 0]]
    cut_area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    np.testing.assert_allclose(model.host.tri_area, cut_area, rtol=1e-12)
    np.testing.assert_allclose(model.host.mass.sum(), cut_area.sum() * model_density(), rtol=1e-12)
    # the grain: stretching the laid cloth along its warp loads k_v, along its weft k_u
    warp2d = grain[0]
    weft2d = np.array([warp2d[1], -warp2d[0]])
    dm, _ = flat_rest_shape(cut[f], grain)
    e1 = cut[f[:, 1]] - cut[f[:, 0]]
    np.testing.assert_allclose(dm[:, 0, 0], e1 @ weft2d, atol=1e-15)
    np.testing.assert_allclose(dm[:, 1, 0], e1 @ warp2d, atol=1e-15)


def model_density() -> float:
    from datagen.materials import material

    return material("cotton").density


def test_a_flat_rectangle_laid_on_a_plane_keeps_no_rest_curvature():
    """A rectangle whose 2D rest state is flat, placed bent (a half cylinder), rests at hinge angle
    0 everywhere: laid flat it has no elastic energy, and the bending of the bent placement is
    energy (the shell path would have kept the bend as the rest shape)."""
    uv, f = _grid(8, 4, 0.03)
    radius = 0.06
    th = uv[:, 0] / radius
    bent = np.stack([radius * np.sin(th), radius * (1 - np.cos(th)), uv[:, 1]], 1)
    model = _model(bent, f, uv[f])
    assert np.all(model.host.rest_angle == 0.0)
    flat = np.stack([uv[:, 0], np.zeros(len(uv)), uv[:, 1]], 1)
    assert elastic_energy(model.host, flat) < 1e-12
    assert elastic_energy(model.host, bent) > 1e-6
    shell = _model(bent, f, None)
    assert np.abs(shell.host.rest_angle).max() > 0.1  # the shell path: the built bend is its rest shape
    assert elastic_energy(shell.host, bent) < 1e-12


def test_a_flat_rectangle_on_a_plane_stays_flat():
    """Simulated: the rectangle placed bent over a plane falls flat onto it and stays flat (every
    vertex within 1 mm of the plane's contact distance after 1.5 s): no rest curvature is left."""
    from datagen.sim.settings import SolverConfig
    from datagen.sim.solver import SolverVBD
    from datagen.sim.state import BodyControl, ClothState

    uv, f = _grid(7, 5, 0.03)
    radius = 0.08
    th = (uv[:, 0] - uv[:, 0].mean()) / radius
    bent = np.stack([radius * np.sin(th), 0.02 + radius * (1 - np.cos(th)), uv[:, 1]], 1)
    b = ClothModelBuilder()
    b.add_cloth(bent, f, material_name="cotton", rest_corners=uv[f])
    s = 2.0
    b.add_body(np.array([[-s, 0, -s], [s, 0, -s], [s, 0, s], [-s, 0, s], [0, -s, 0]]),
               np.array([[0, 2, 1], [0, 3, 2], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))
    model = b.finalize("cpu")
    cfg = SolverConfig()
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    control = BodyControl.from_numpy(model, model.host.body_rest)
    solver = SolverVBD(model, cfg)
    for _ in range(45):
        solver.step(s0, s1, control, 1 / 30)
        s0, s1 = s1, s0
    x, _ = s0.numpy()
    contact = model.host.thickness[0] + cfg.body_margin
    print(f"\nflat rectangle on a plane: height {1e3 * x[:, 1].min():.3f}..{1e3 * x[:, 1].max():.3f} mm "
          f"(contact distance {1e3 * contact:.2f} mm)")
    assert np.abs(x[:, 1] - contact).max() < 1e-3


def test_rest_corners_are_checked():
    uv, f = _grid(3, 3, 0.05)
    x = np.stack([uv[:, 0], np.zeros(len(uv)), uv[:, 1]], 1)
    b = ClothModelBuilder()
    with pytest.raises(InputError, match="rest_corners"):
        b.add_cloth(x, f, rest_corners=uv)
    with pytest.raises(InputError, match="grain"):
        b.add_cloth(x, f, grain=np.tile([0.0, 1.0], (len(f), 1)))
    with pytest.raises(InputError, match="grain"):
        b.add_cloth(x, f, rest_corners=uv[f], grain=np.zeros((len(f), 2)))


def test_a_batch_mixing_shell_and_flat_cloth_keeps_the_shell_arrays():
    """A shell cloth's membrane and hinges are the same whether or not a flat cloth shares its batch."""
    uv, f = _grid(4, 4, 0.05)
    x = np.stack([uv[:, 0], 0.01 * np.sin(7 * uv[:, 0]), uv[:, 1]], 1)
    alone = _model(x, f, None)
    b = ClothModelBuilder()
    b.add_cloth(x, f, scene=0)
    b.add_cloth(x + [1, 0, 0], f, scene=1, rest_corners=uv[f])
    both = b.finalize("cpu")
    n, nf, ne = len(x), len(f), alone.edge_count
    np.testing.assert_array_equal(both.host.dm_inv[:nf], alone.host.dm_inv)
    np.testing.assert_array_equal(both.host.tri_area[:nf], alone.host.tri_area)
    np.testing.assert_array_equal(both.host.mass[:n], alone.host.mass)
    np.testing.assert_array_equal(both.host.rest_angle[:ne], alone.host.rest_angle)
    np.testing.assert_array_equal(both.host.bend_k[:ne], alone.host.bend_k)
    assert np.all(both.host.rest_angle[ne:] == 0.0)


def test_a_flat_panel_laid_flat_builds_the_shells_arrays():
    """A panel laid in 3D exactly as it was cut gets the same membrane and hinges from either path
    (to rounding): the flat rest state is the built one's where they agree."""
    uv, f = _grid(5, 4, 0.03)
    x = np.stack([uv[:, 0], np.zeros(len(uv)), -uv[:, 1]], 1)  # normal +Y: weft +X, warp -Z as the shell's frames
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]), (len(f), 1, 1))
    b = ClothModelBuilder()
    b.add_cloth(x, f, material_frames=frames)
    shell = b.finalize("cpu").host
    flat = _model(x, f, uv[f]).host
    for name in ("dm_inv", "tri_area", "mass", "vertex_area", "rest_angle", "bend_k"):
        np.testing.assert_allclose(getattr(flat, name), getattr(shell, name), rtol=1e-12, atol=1e-12, err_msg=name)


@pytest.mark.slow
def test_a_cusick_disc_cut_flat_and_started_bent_drapes_in_its_range():
    """Cotton's Cusick specimen as a flat-cut panel, started bent into a bowl (rim 4 cm up): its
    drape coefficient after 3 s is in cotton's published range (0.40-0.60), as the shell disc's is
    (the six presets: ``python -m benchmarks sewing-cusick``)."""
    from benchmarks.sewing_cusick import drape_coefficient, drape_flat
    from datagen.materials import MATERIALS, drape_range

    x, f, speed = drape_flat(MATERIALS["cotton"], 0.015, 3.0, 0.3)
    dc, nodes = drape_coefficient(x, f)
    lo, hi = drape_range("cotton")
    print(f"\ncotton cut flat, started bent: DC {dc:.3f} ({nodes} nodes), range {lo}-{hi}, end speed {speed:.3f} m/s")
    assert lo <= dc <= hi
