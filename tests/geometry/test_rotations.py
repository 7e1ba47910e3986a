"""Rotation conversions: round trips, numpy vs torch, scipy, angles near 0 and pi, gradients, 6D."""

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation, Slerp

from datagen.geometry import rotations as rot

RNG_SEED = 1234
N = 500


def random_axis_angle(n=N, seed=RNG_SEED, shape=None):
    """Axis-angle with uniformly random axes and angles in [0, pi) (a unique representation)."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = rng.uniform(0.0, np.pi * 0.999, size=(n, 1))
    r = axis * angle
    return r if shape is None else r.reshape(shape + (3,))


def to_xyzw(q):
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)


def from_xyzw(q):
    q = np.concatenate([q[..., 3:], q[..., :3]], axis=-1)
    return np.where(q[..., :1] < 0, -q, q)


# Every representation from the matrix and back, so every pair can be converted.
REPS = {
    "axis_angle": (rot.matrix_to_axis_angle_np, rot.axis_angle_to_matrix_np),
    "quaternion": (rot.matrix_to_quaternion_np, rot.quaternion_to_matrix_np),
    "rotation_6d": (rot.matrix_to_rotation_6d_np, rot.rotation_6d_to_matrix_np),
    "matrix": (lambda m: m, lambda m: m),
}
# Direct conversions that the module provides (the others go through the matrix).
DIRECT = {
    ("axis_angle", "quaternion"): rot.axis_angle_to_quaternion_np,
    ("quaternion", "axis_angle"): rot.quaternion_to_axis_angle_np,
}


def convert(x, src, dst):
    if (src, dst) in DIRECT:
        return DIRECT[(src, dst)](x)
    return REPS[dst][0](REPS[src][1](x))


@pytest.mark.parametrize("src", list(REPS))
@pytest.mark.parametrize("dst", list(REPS))
def test_round_trip_every_pair(src, dst):
    matrices = Rotation.from_rotvec(random_axis_angle()).as_matrix()
    x = REPS[src][0](matrices)
    back = convert(convert(x, src, dst), dst, src)
    np.testing.assert_allclose(back, x, atol=1e-10)
    # And the intermediate is the same rotation.
    np.testing.assert_allclose(REPS[dst][1](convert(x, src, dst)), matrices, atol=1e-10)


def test_direct_axis_angle_quaternion_agree_with_matrix_route():
    r = random_axis_angle()
    np.testing.assert_allclose(rot.axis_angle_to_quaternion_np(r),
                               rot.matrix_to_quaternion_np(rot.axis_angle_to_matrix_np(r)), atol=1e-12)
    q = rot.axis_angle_to_quaternion_np(r)
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(q),
                               rot.matrix_to_axis_angle_np(rot.quaternion_to_matrix_np(q)), atol=1e-10)


def test_against_scipy():
    r = random_axis_angle()
    ref = Rotation.from_rotvec(r)
    m = ref.as_matrix()
    np.testing.assert_allclose(rot.axis_angle_to_matrix_np(r), m, atol=1e-12)
    np.testing.assert_allclose(rot.matrix_to_axis_angle_np(m), ref.as_rotvec(), atol=1e-10)
    np.testing.assert_allclose(rot.matrix_to_quaternion_np(m), from_xyzw(ref.as_quat()), atol=1e-12)
    np.testing.assert_allclose(rot.axis_angle_to_quaternion_np(r), from_xyzw(ref.as_quat()), atol=1e-12)
    q = rot.axis_angle_to_quaternion_np(r)
    np.testing.assert_allclose(rot.quaternion_to_matrix_np(q), Rotation.from_quat(to_xyzw(q)).as_matrix(), atol=1e-12)
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(q), Rotation.from_quat(to_xyzw(q)).as_rotvec(),
                               atol=1e-10)


def test_column_vector_convention():
    # 90 degrees about +z takes +x to +y when applied as R @ v.
    R = rot.axis_angle_to_matrix_np(np.array([0.0, 0.0, np.pi / 2]))
    np.testing.assert_allclose(R @ np.array([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)
    q = rot.axis_angle_to_quaternion_np(np.array([0.0, 0.0, np.pi / 2]))
    np.testing.assert_allclose(q, [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], atol=1e-15)
    six = rot.matrix_to_rotation_6d_np(R)
    np.testing.assert_allclose(six, np.concatenate([R[:, 0], R[:, 1]]))


def test_quaternions_are_canonical_and_unit():
    # Angles above pi map to the canonical quaternion (w >= 0) of the same rotation.
    r = random_axis_angle() * 1.9
    q = rot.axis_angle_to_quaternion_np(r)
    assert np.all(q[:, 0] >= 0)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(rot.quaternion_to_matrix_np(q), rot.axis_angle_to_matrix_np(r), atol=1e-12)
    # -q is the same rotation: same matrix, same axis-angle; non-unit input is normalised.
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(-3.0 * q), rot.quaternion_to_axis_angle_np(q),
                               atol=1e-12)
    assert np.all(np.linalg.norm(rot.quaternion_to_axis_angle_np(q), axis=-1) <= np.pi + 1e-12)


def test_batched_leading_dims_and_float32():
    r = random_axis_angle(n=24, shape=(2, 3, 4))
    m = rot.axis_angle_to_matrix_np(r)
    assert m.shape == (2, 3, 4, 3, 3)
    assert rot.matrix_to_quaternion_np(m).shape == (2, 3, 4, 4)
    assert rot.matrix_to_rotation_6d_np(m).shape == (2, 3, 4, 6)
    assert rot.rotation_6d_to_matrix_np(rot.matrix_to_rotation_6d_np(m)).shape == (2, 3, 4, 3, 3)
    np.testing.assert_allclose(rot.matrix_to_axis_angle_np(m), r, atol=1e-10)
    q32 = rot.axis_angle_to_quaternion_np(r.astype(np.float32))
    assert q32.dtype == np.float32
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(q32), r, atol=1e-5)
    assert rot.matrix_to_axis_angle_np(m.astype(np.float32)).dtype == np.float32


NUMPY_TORCH = [
    ("axis_angle_to_matrix", "axis_angle"),
    ("matrix_to_axis_angle", "matrix"),
    ("axis_angle_to_quaternion", "axis_angle"),
    ("quaternion_to_axis_angle", "quaternion"),
    ("quaternion_to_matrix", "quaternion"),
    ("matrix_to_quaternion", "matrix"),
    ("matrix_to_rotation_6d", "matrix"),
    ("rotation_6d_to_matrix", "rotation_6d"),
]


@pytest.mark.parametrize("name,rep", NUMPY_TORCH)
def test_numpy_and_torch_agree(name, rep):
    matrices = Rotation.from_rotvec(random_axis_angle(n=120)).as_matrix().reshape(4, 30, 3, 3)
    x = REPS[rep][0](matrices)
    if rep == "rotation_6d":  # not orthonormal: Gram-Schmidt must agree too
        x = x + np.random.default_rng(RNG_SEED).normal(scale=0.1, size=x.shape)
    out_np = getattr(rot, name + "_np")(x)
    out_t = getattr(rot, name)(torch.from_numpy(x))
    assert out_t.dtype == torch.float64 and tuple(out_t.shape) == out_np.shape
    np.testing.assert_allclose(out_t.numpy(), out_np, atol=1e-12)


def test_slerp_numpy_torch_agree_and_match_scipy():
    rng = np.random.default_rng(RNG_SEED)
    q0 = rot.axis_angle_to_quaternion_np(random_axis_angle(n=200, seed=1))
    q1 = rot.axis_angle_to_quaternion_np(random_axis_angle(n=200, seed=2))
    t = rng.uniform(size=200)
    out = rot.quaternion_slerp_np(q0, q1, t)
    out_t = rot.quaternion_slerp(torch.from_numpy(q0), torch.from_numpy(q1), torch.from_numpy(t))
    np.testing.assert_allclose(out_t.numpy(), out, atol=1e-12)
    for i in range(0, 200, 20):
        ref = Slerp([0.0, 1.0], Rotation.from_quat(to_xyzw(np.stack([q0[i], q1[i]]))))([t[i]])
        np.testing.assert_allclose(out[i], from_xyzw(ref.as_quat())[0], atol=1e-10)


def test_slerp_midpoint_endpoints_and_shortest_path():
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    qa = rot.axis_angle_to_quaternion_np(0.3 * axis)
    qb = rot.axis_angle_to_quaternion_np(1.7 * axis)
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(rot.quaternion_slerp_np(qa, qb, 0.5)), 1.0 * axis,
                               atol=1e-14)
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(rot.quaternion_slerp_np(qa, qb, 0.25)), 0.65 * axis,
                               atol=1e-14)
    np.testing.assert_allclose(rot.quaternion_slerp_np(qa, qb, 0.0), qa, atol=1e-15)
    np.testing.assert_allclose(rot.quaternion_slerp_np(qa, qb, 1.0), qb, atol=1e-15)
    # -qb is the same rotation: the path must not change (shortest arc).
    np.testing.assert_allclose(rot.quaternion_slerp_np(qa, -qb, 0.5), rot.quaternion_slerp_np(qa, qb, 0.5),
                               atol=1e-15)
    # From +170 to -170 degrees about z the short way passes through 180, not 0.
    q170 = rot.axis_angle_to_quaternion_np(np.radians([0.0, 0.0, 170.0]))
    qm170 = rot.axis_angle_to_quaternion_np(np.radians([0.0, 0.0, -170.0]))
    mid = rot.quaternion_to_matrix_np(rot.quaternion_slerp_np(q170, qm170, 0.5))
    np.testing.assert_allclose(mid, np.diag([-1.0, -1.0, 1.0]), atol=1e-12)
    # Nearly identical inputs (nlerp branch) still interpolate the angle linearly.
    q_close = rot.axis_angle_to_quaternion_np((0.3 + 1e-7) * axis)
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(rot.quaternion_slerp_np(qa, q_close, 0.3)),
                               (0.3 + 0.3e-7) * axis, atol=1e-15)


@pytest.mark.parametrize("angle", [1e-9, 0.0])
def test_small_angles(angle):
    axis = np.array([[0.6, 0.0, 0.8], [0.0, -1.0, 0.0], [1.0, 2.0, 3.0] / np.sqrt(14.0)])
    r = axis * angle
    m = rot.axis_angle_to_matrix_np(r)
    np.testing.assert_allclose(rot.matrix_to_axis_angle_np(m), r, atol=1e-15)
    q = rot.axis_angle_to_quaternion_np(r)
    np.testing.assert_allclose(rot.quaternion_to_axis_angle_np(q), r, rtol=1e-12, atol=1e-30)
    np.testing.assert_allclose(q[:, 1:], r / 2, rtol=1e-12, atol=1e-30)
    rt = torch.from_numpy(r)
    np.testing.assert_allclose(rot.quaternion_to_axis_angle(rot.axis_angle_to_quaternion(rt)).numpy(), r,
                               rtol=1e-12, atol=1e-30)
    np.testing.assert_allclose(rot.matrix_to_axis_angle(rot.axis_angle_to_matrix(rt)).numpy(), r, atol=1e-15)


@pytest.mark.parametrize("angle", [np.pi - 1e-7, np.pi])
@pytest.mark.parametrize("backend", ["numpy", "torch"])
def test_angles_near_pi(angle, backend):
    rng = np.random.default_rng(RNG_SEED)
    axis = np.concatenate([np.eye(3), rng.normal(size=(20, 3))])
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    r = axis * angle
    m = Rotation.from_rotvec(r).as_matrix()
    if backend == "numpy":
        back = rot.matrix_to_axis_angle_np(m)
        via_quat = rot.quaternion_to_axis_angle_np(rot.axis_angle_to_quaternion_np(r))
    else:
        back = rot.matrix_to_axis_angle(torch.from_numpy(m)).numpy()
        via_quat = rot.quaternion_to_axis_angle(rot.axis_angle_to_quaternion(torch.from_numpy(r))).numpy()
    for out in (back, via_quat):
        np.testing.assert_allclose(np.linalg.norm(out, axis=-1), angle, atol=1e-9)
        if angle < np.pi:  # unique: the same axis, not its negation
            np.testing.assert_allclose(out, r, atol=1e-8)
        else:  # at pi, r and -r are the same rotation: the axis up to sign
            err = np.minimum(np.abs(out - r).max(-1), np.abs(out + r).max(-1))
            assert err.max() < 1e-9
        np.testing.assert_allclose(rot.axis_angle_to_matrix_np(out), m, atol=1e-9)


def test_torch_gradients_finite_at_zero_angle():
    r = torch.zeros(5, 3, dtype=torch.float64, requires_grad=True)
    for f in (rot.axis_angle_to_matrix, rot.axis_angle_to_quaternion,
              lambda x: rot.quaternion_to_axis_angle(rot.axis_angle_to_quaternion(x)),
              lambda x: rot.matrix_to_axis_angle(rot.axis_angle_to_matrix(x)),
              lambda x: rot.rotation_6d_to_matrix(rot.matrix_to_rotation_6d(rot.axis_angle_to_matrix(x)))):
        (grad,) = torch.autograd.grad(f(r).pow(2).sum() + f(r).sum(), r)
        assert torch.isfinite(grad).all()
    # d(matrix_to_axis_angle)/dR at the identity, and the round trip's Jacobian there is I.
    eye = torch.eye(3, dtype=torch.float64).repeat(2, 1, 1).requires_grad_(True)
    (grad,) = torch.autograd.grad(rot.matrix_to_axis_angle(eye).sum(), eye)
    assert torch.isfinite(grad).all()
    jac = torch.autograd.functional.jacobian(
        lambda x: rot.matrix_to_axis_angle(rot.axis_angle_to_matrix(x)), torch.zeros(3, dtype=torch.float64))
    np.testing.assert_allclose(jac.numpy(), np.eye(3), atol=1e-12)
    # Slerp of identical quaternions (the linear branch) has finite gradients.
    q = torch.tensor([[1.0, 0.0, 0.0, 0.0]], dtype=torch.float64, requires_grad=True)
    t = torch.tensor([0.3], dtype=torch.float64, requires_grad=True)
    grads = torch.autograd.grad(rot.quaternion_slerp(q, q.detach().clone(), t).sum(), (q, t))
    assert all(torch.isfinite(g).all() for g in grads)


def test_torch_gradcheck_generic_rotations():
    r = torch.from_numpy(random_axis_angle(n=4)).requires_grad_(True)
    assert torch.autograd.gradcheck(lambda x: rot.matrix_to_axis_angle(rot.axis_angle_to_matrix(x)), (r,))
    assert torch.autograd.gradcheck(lambda x: rot.quaternion_to_axis_angle(rot.axis_angle_to_quaternion(x)), (r,))
    six = torch.from_numpy(np.random.default_rng(RNG_SEED).normal(size=(4, 6))).requires_grad_(True)
    assert torch.autograd.gradcheck(rot.rotation_6d_to_matrix, (six,))
    q0 = rot.axis_angle_to_quaternion(r.detach())
    q1 = rot.axis_angle_to_quaternion(r.detach().flip(0)).requires_grad_(True)
    t = torch.tensor([0.1, 0.4, 0.6, 0.9], dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda a, b: rot.quaternion_slerp(q0, a, b), (q1, t))


def test_rotation_6d_gram_schmidt():
    matrices = Rotation.from_rotvec(random_axis_angle(n=200)).as_matrix()
    six = rot.matrix_to_rotation_6d_np(matrices)
    np.testing.assert_allclose(six[:, :3], matrices[:, :, 0])
    np.testing.assert_allclose(six[:, 3:], matrices[:, :, 1])
    # Scaling the first column and adding any multiple of it to the second changes nothing.
    rng = np.random.default_rng(RNG_SEED)
    s1, s2, k = rng.uniform(0.5, 2.0, (3, 200, 1))
    skewed = np.concatenate([s1 * six[:, :3], s2 * six[:, 3:] + k * six[:, :3]], axis=-1)
    np.testing.assert_allclose(rot.rotation_6d_to_matrix_np(skewed), matrices, atol=1e-12)
    # A perturbed 6D input gives an orthonormal, right-handed matrix near the original, whose
    # first column is the normalised first half and whose second lies in the plane of both.
    noisy = six + rng.normal(scale=0.05, size=six.shape)
    for out in (rot.rotation_6d_to_matrix_np(noisy), rot.rotation_6d_to_matrix(torch.from_numpy(noisy)).numpy()):
        np.testing.assert_allclose(out.transpose(0, 2, 1) @ out, np.broadcast_to(np.eye(3), out.shape), atol=1e-12)
        np.testing.assert_allclose(np.linalg.det(out), 1.0, atol=1e-12)
        a1 = noisy[:, :3] / np.linalg.norm(noisy[:, :3], axis=-1, keepdims=True)
        np.testing.assert_allclose(out[:, :, 0], a1, atol=1e-12)
        normal = np.cross(noisy[:, :3], noisy[:, 3:])
        np.testing.assert_allclose(np.einsum("ni,ni->n", out[:, :, 1], normal), 0.0, atol=1e-12)
        assert np.all(np.einsum("ni,ni->n", out[:, :, 1], noisy[:, 3:]) > 0)
        assert np.abs(out - matrices).max() < 0.3
