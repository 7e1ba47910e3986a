"""The membrane law's buckling branch: the kernels' forces against the energy that
``datagen.sim.metrics.elastic_energy`` defines, and the branch's own scaling."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import warp as wp

from datagen.materials import MATERIALS, Material
from datagen.sim.kernels import membrane_force_hessian, vec5
from datagen.sim.metrics import elastic_energy
from datagen.sim.model import ClothModelBuilder
from tests.sim.meshes import grid

SILK = MATERIALS["silk"]


def patch(material: Material):
    """A flat 4 x 4 cm patch (2 cm grid in the XZ plane, weft along X, warp along Z) and its
    model on the CPU."""
    v, f = grid(3, 3, 0.02)
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), (len(f), 1, 1))
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name=material, material_frames=frames)
    return v, b.finalize("cpu")


@wp.kernel
def _membrane_forces(x: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32), dm_inv: wp.array(dtype=wp.mat22),
                     tri_area: wp.array(dtype=float), tri_stiff: wp.array(dtype=vec5),
                     tri_lock: wp.array(dtype=wp.vec2), out: wp.array2d(dtype=wp.vec3)):
    f, local = wp.tid()
    fm, hm = membrane_force_hessian(faces[f, local], local, f, x, x, faces, dm_inv, tri_area, tri_stiff, tri_lock,
                                    0.0, 1.0)
    out[f, local] = fm


def kernel_forces(model, x: np.ndarray) -> np.ndarray:
    """Every vertex's membrane force [N] from the solver's kernel (no damping), [N, 3]."""
    xs = wp.array(x.astype(np.float32), dtype=wp.vec3, device="cpu")
    out = wp.zeros((model.face_count, 3), dtype=wp.vec3, device="cpu")
    wp.launch(_membrane_forces, dim=(model.face_count, 3), device="cpu",
              inputs=[xs, model.faces, model.dm_inv, model.tri_area, model.tri_stiff, model.tri_lock, out])
    per_corner = out.numpy().astype(np.float64)
    forces = np.zeros_like(x)
    for c in range(3):
        np.add.at(forces, model.host.faces[:, c], per_corner[:, c])
    return forces


def test_compression_costs_the_buckling_ratio_of_the_same_tension():
    """Shortening the weft by 10 % (warp and shear untouched) stores r times the energy it stores
    under the linear law; stretching it by 10 % stores the same under both."""
    v, buckled = patch(SILK)
    _, linear = patch(dataclasses.replace(SILK, buckling_ratio=1.0))
    for scale, ratio in ((0.9, SILK.buckling_ratio), (1.1, 1.0)):
        x = v * np.array([scale, 1.0, 1.0])
        e_buckled, e_linear = elastic_energy(buckled.host, x), elastic_energy(linear.host, x)
        assert e_linear > 0
        assert e_buckled / e_linear == pytest.approx(ratio, rel=1e-9)


@pytest.mark.parametrize("weft, warp", [(0.92, 1.03), (1.04, 0.95), (0.9, 0.94)])
def test_kernel_forces_are_the_energy_gradient_on_the_buckling_branch(weft, warp):
    """The force the solver's membrane kernel puts on every vertex is minus the gradient of the
    energy that the energy balance uses (central differences in float64), with one direction, the
    other, or both in compression, plus a small shear (the two must agree for the balance to
    mean anything)."""
    v, model = patch(SILK)
    rng = np.random.default_rng(0)
    x = v * np.array([weft, 1.0, warp]) + np.array([0.03, 0.0, 0.0]) * v[:, 2:3]
    x[:, [0, 2]] += rng.normal(scale=2e-4, size=(len(x), 2))
    forces = kernel_forces(model, x)
    grad = np.zeros_like(x)
    eps = 1e-7
    for i in range(len(x)):
        for d in (0, 2):  # the patch stays flat: no bending
            xp, xm = x.copy(), x.copy()
            xp[i, d] += eps
            xm[i, d] -= eps
            grad[i, d] = (elastic_energy(model.host, xp) - elastic_energy(model.host, xm)) / (2 * eps)
    scale = np.abs(grad).max()
    assert scale > 0
    np.testing.assert_allclose(forces, -grad, atol=2e-3 * scale)


def test_a_buckling_ratio_outside_its_range_is_refused():
    from datagen.errors import InputError

    with pytest.raises(InputError, match="buckling_ratio must be in"):
        dataclasses.replace(SILK, buckling_ratio=0.0)
    with pytest.raises(InputError, match="buckling_ratio must be in"):
        dataclasses.replace(SILK, buckling_ratio=1.5)
