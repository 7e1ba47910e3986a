"""Posing: numpy vs torch vs smplx's lbs vs a plain per-vertex loop."""

import numpy as np
import pytest
import torch

from datagen.errors import InputError
from datagen.geometry.rotations import axis_angle_to_matrix_np


def loop_lbs(m, betas, pose):
    """Reference: SMPL written out joint by joint and vertex by vertex."""
    v = m.v_template + m.shapedirs @ betas
    J = m.J_regressor @ v
    R = axis_angle_to_matrix_np(pose.reshape(24, 3))
    feat = np.concatenate([(R[j] - np.eye(3)).reshape(-1) for j in range(1, 24)])
    if m.posedirs is not None:
        v = v + (feat @ m.posedirs).reshape(-1, 3)
    G = []
    for j in range(24):
        T = np.eye(4)
        T[:3, :3] = R[j]
        T[:3, 3] = J[j] - (J[m.parents[j]] if j else 0)
        G.append(T if j == 0 else G[m.parents[j]] @ T)
    out = np.zeros_like(v)
    for i in range(len(v)):
        acc = np.zeros((4, 4))
        for j in range(24):
            A = G[j].copy()
            A[:3, 3] -= G[j][:3, :3] @ J[j]
            acc += m.weights[i, j] * A
        out[i] = acc[:3, :3] @ v[i] + acc[:3, 3]
    return out, np.array([g[:3, 3] for g in G])


def test_numpy_matches_plain_loop(small_model):
    rng = np.random.default_rng(1)
    betas, pose = rng.normal(size=10), rng.normal(scale=0.5, size=72)
    ref_v, ref_j = loop_lbs(small_model, betas, pose)
    v, j = small_model.pose(betas[None], pose[None])
    np.testing.assert_allclose(v[0], ref_v, atol=1e-12)
    np.testing.assert_allclose(j[0], ref_j, atol=1e-12)


def test_torch_matches_numpy_and_smplx(small_model):
    from smplx.lbs import lbs as smplx_lbs

    rng = np.random.default_rng(2)
    betas, pose, transl = rng.normal(size=(5, 10)), rng.normal(scale=0.6, size=(5, 72)), rng.normal(size=(5, 3))
    v_np, j_np = small_model.pose(betas, pose, transl)
    tm = small_model.torch(dtype=torch.float64)
    v_t, j_t = tm(torch.tensor(betas), torch.tensor(pose), torch.tensor(transl))
    np.testing.assert_allclose(v_t.numpy(), v_np, atol=1e-12)
    np.testing.assert_allclose(j_t.numpy(), j_np, atol=1e-12)
    v_s, _ = smplx_lbs(torch.tensor(betas), torch.tensor(pose), tm.v_template, tm.shapedirs, tm.posedirs,
                       tm.J_regressor, torch.tensor(small_model.parents), tm.weights)
    np.testing.assert_allclose(v_s.numpy() + transl[:, None], v_np, atol=1e-6)  # smplx adds 1e-8 to angles


def test_torch_is_differentiable(small_model):
    tm = small_model.torch(dtype=torch.float64)
    betas = torch.zeros(2, 10, dtype=torch.float64, requires_grad=True)
    pose = torch.zeros(2, 24, 3, dtype=torch.float64, requires_grad=True)  # gradients at exactly zero angle
    v, _ = tm(betas, pose)
    (v ** 2).sum().backward()
    assert torch.isfinite(pose.grad).all() and pose.grad.abs().sum() > 0
    assert torch.isfinite(betas.grad).all() and betas.grad.abs().sum() > 0
    assert torch.autograd.gradcheck(lambda b, p: tm(b, p)[0][:, :20], (betas.detach()[:1].requires_grad_(),
                                    (0.3 * torch.ones(1, 24, 3, dtype=torch.float64)).requires_grad_()))


def test_rest_pose_and_rigid_root(small_model):
    v0, _ = small_model.pose()
    np.testing.assert_allclose(v0[0], small_model.v_template, atol=1e-12)
    root = np.zeros((1, 24, 3))
    root[0, 0] = [0.0, np.pi / 2, 0.0]
    v1, j1 = small_model.pose(None, root)
    R = axis_angle_to_matrix_np(root[0, 0])
    j0 = small_model.rest_joints()[0, 0]
    np.testing.assert_allclose(v1[0], (small_model.v_template - j0) @ R.T + j0, atol=1e-12)


def test_batch_broadcasting(small_model):
    rng = np.random.default_rng(3)
    betas, pose = rng.normal(size=(1, 10)), rng.normal(scale=0.3, size=(4, 24, 3))
    v, _ = small_model.pose(betas, pose)
    for b in range(4):
        vb, _ = small_model.pose(betas, pose[b:b + 1])
        np.testing.assert_allclose(v[b], vb[0], atol=1e-12)


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        ({"betas": np.zeros((1, 11))}, r"betas must have shape \[batch, S\] with 1 <= S <= 10"),
        ({"pose": np.zeros((1, 23, 3))}, r"pose θ must have shape \[batch, 24, 3\] or \[batch, 72\]"),
        ({"pose": np.full((1, 72), np.nan)}, r"pose has 72 non-finite value"),
        ({"betas": np.array([[np.inf] + [0] * 9])}, r"betas has 1 non-finite"),
        ({"transl": np.zeros((1, 2))}, r"transl must have shape \[batch, 3\]"),
        ({"betas": np.zeros((2, 10)), "pose": np.zeros((3, 72))}, r"betas batch 2 and pose batch 3 differ"),
    ],
)
def test_bad_inputs_are_explained(small_model, kwargs, pattern):
    with pytest.raises(InputError, match=pattern):
        small_model.pose(**kwargs)


def test_lbs_np_float32_close_to_float64(small_model):
    rng = np.random.default_rng(4)
    betas, pose = rng.normal(size=(2, 10)), rng.normal(scale=0.3, size=(2, 72))
    v64, _ = small_model.pose(betas, pose)
    v32, _ = small_model.pose(betas, pose, dtype=np.float32)
    assert v32.dtype == np.float32
    np.testing.assert_allclose(v32, v64, atol=1e-5)
