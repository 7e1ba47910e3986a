"""The move bound's segment (issue 66): ``kernels.bounded_move`` and ``kernels.carry_bound``.

The sweeps, the global step, the initial guess and the Chebyshev step keep each vertex within its
bound of the segment from its detection position to where the body carries it.
Where nothing carries it the segment is a point and the bound must be the ball of before, bit for
bit (static-body scenes keep their positions); where the body carries it, the whole segment is
allowed and nothing off it by more than the bound.
"""

import numpy as np
import pytest
import warp as wp

from datagen.sim import kernels as K


@wp.kernel
def _moves(target: wp.array(dtype=wp.vec3), start: wp.array(dtype=wp.vec3), end: wp.array(dtype=wp.vec3),
           bound: wp.array(dtype=float), out: wp.array(dtype=wp.vec3), ball: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = K.bounded_move(target[i], start[i], end[i], bound[i])
    # the clamp every kernel had before the segment
    xi = target[i]
    move = xi - start[i]
    L = wp.length(move)
    if L > bound[i]:
        xi = start[i] + move * (bound[i] / L)
    ball[i] = xi


def _run(new, start, end, bound):
    wp.init()
    a = [wp.array(np.asarray(v, np.float32), dtype=wp.vec3, device="cpu") for v in (new, start, end)]
    b = wp.array(np.asarray(bound, np.float32), dtype=float, device="cpu")
    out, ball = (wp.zeros(len(new), dtype=wp.vec3, device="cpu") for _ in range(2))
    wp.launch(_moves, len(new), inputs=[*a, b, out, ball], device="cpu")
    return out.numpy(), ball.numpy()


def test_without_a_carry_the_bound_is_the_ball_of_before_bit_for_bit():
    rng = np.random.default_rng(0)
    start = rng.normal(size=(500, 3)) * 0.1
    new = start + rng.normal(size=(500, 3)) * 0.005
    out, ball = _run(new, start, start, rng.uniform(0.001, 0.006, 500))
    assert np.array_equal(out.view(np.uint32), ball.view(np.uint32))
    assert not np.array_equal(out, new.astype(np.float32))  # some were clamped


def test_a_carried_vertex_may_ride_its_segment_and_no_farther_off_it_than_the_bound():
    start, end, b = np.zeros(3), np.array([0.0, 0.0, 0.0133]), 0.0027  # 4 m/s at 10 substeps of 1/30 s
    new = np.array([
        [0.0, 0.0, 0.010],  # on the segment: kept
        [0.002, 0.0, 0.005],  # within the bound of it: kept
        [0.010, 0.0, 0.005],  # beside it: pulled to the bound, level with where it was
        [0.0, 0.0, 0.030],  # past its end: pulled to the bound beyond the end
        [0.0, 0.0, -0.010],  # behind its start: the ball about the start
    ])
    out, _ = _run(new, np.tile(start, (5, 1)), np.tile(end, (5, 1)), np.full(5, b))
    np.testing.assert_allclose(out[:2], new[:2], atol=1e-7)
    np.testing.assert_allclose(out[2], [b, 0.0, 0.005], atol=1e-7)
    np.testing.assert_allclose(out[3], [0.0, 0.0, 0.0133 + b], atol=1e-7)
    np.testing.assert_allclose(out[4], [0.0, 0.0, -b], atol=1e-7)


def _carry(x_det, x_prev, disp, plane_point, normal, query=0.03):
    wp.init()
    n = len(x_det)
    v3 = lambda a: wp.array(np.asarray(a, np.float32).reshape(-1, 3), dtype=wp.vec3, device="cpu")  # noqa: E731
    p2 = lambda a: wp.array(np.asarray(a, np.float32).reshape(n, 1, 3), dtype=wp.vec3, device="cpu")  # noqa: E731
    has = wp.array(np.array([[0 if p is None else 1] for p in plane_point], np.int32), dtype=wp.int32, device="cpu")
    pts = [np.zeros(3) if p is None else p for p in plane_point]
    end = wp.zeros(n, dtype=wp.vec3, device="cpu")
    wp.launch(K.carry_bound, n, device="cpu", inputs=[
        v3(x_det), v3(x_prev), has, p2(pts), p2(normal), p2(disp), query,
        wp.array(np.ones(n, np.int32), dtype=wp.int32, device="cpu"), end])
    return end.numpy()


def test_the_segment_is_the_body_s_move_and_nothing_where_the_body_does_not_move():
    z, up = np.zeros(3), np.array([0.0, 0.0, 1.0])
    x = np.array([[0.0, 0.0, 0.005]] * 4)
    disp = np.array([[0.0, 0.0, 0.0133]] * 4)  # 4 m/s at 10 substeps of 1/30 s
    disp[1] = 0.0  # a body at rest
    planes = [z + disp[0], z, None, z + disp[0]]
    end = _carry(x, x, disp, planes, [up] * 4)
    np.testing.assert_allclose(end[0], x[0] + disp[0], atol=1e-7)  # carried by the limb
    assert np.array_equal(end[1], x[1].astype(np.float32))  # a body at rest: the ball of before, bit for bit
    assert np.array_equal(end[2], x[2].astype(np.float32))  # no body near: the ball of before
    # a later detection in the substep, the vertex already 10 mm along: only the 3.3 mm left
    later = x[3] + [0.001, 0.0, 0.010]
    end = _carry(later[None], x[3][None], disp[3][None], [planes[3]], [up])
    np.testing.assert_allclose(end[0], later + [0.0, 0.0, 0.0033], atol=1e-6)


@pytest.mark.parametrize("distance, share", [(0.010, 1.0), (0.0225, 0.5), (0.035, 0.0)])
def test_the_body_s_carry_fades_from_half_the_query_to_its_edge(distance, share):
    up = np.array([0.0, 0.0, 1.0])
    x = np.array([[0.0, 0.0, distance]])
    disp = np.array([[0.0, 0.0, 0.002]])  # 2 mm towards the cloth
    end = _carry(x, x, disp, [disp[0]], [up])
    np.testing.assert_allclose(end[0], x[0] + disp[0] * share, atol=1e-6)
