"""The Motion type: validation, resampling, segments, lead-in and the npz format."""

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from datagen.errors import InputError
from datagen.motion.motion import NPZ_KEYS, Motion
from datagen.geometry.rotations import axis_angle_to_matrix_np


def make_motion(frames=31, fps=30.0, seed=0, **kwargs):
    """Random smooth-ish poses (angles well below pi) and a random-walk translation."""
    rng = np.random.default_rng(seed)
    poses = rng.normal(scale=0.4, size=(frames, 24, 3))
    trans = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0.0, 0.9, 0.0]
    args = {"label": 3, "label_name": "walk",
                "source": {"kind": "procedural", "generator": "test", "params": {"seed": seed}}}
    args.update(kwargs)
    return Motion(poses=poses, trans=trans, fps=fps, **args)


def geodesic(a, b):
    """Angle (radians) between the rotations of axis-angle arrays a and b [..., 3]."""
    rel = axis_angle_to_matrix_np(a).swapaxes(-1, -2) @ axis_angle_to_matrix_np(b)
    return np.arccos(np.clip((np.trace(rel, axis1=-2, axis2=-1) - 1) / 2, -1, 1))


# ----------------------------------------------------------------------------- validation

def test_valid_motion_and_derived_quantities():
    m = make_motion(frames=31, fps=30.0)
    assert m.frame_count == 31
    assert m.duration == pytest.approx(1.0)
    np.testing.assert_allclose(m.times, np.arange(31) / 30.0)
    assert m.poses.shape == (31, 24, 3) and m.poses.dtype == np.float64
    assert "frames=31" in repr(m)
    flat = Motion(poses=m.poses.reshape(31, 72), trans=m.trans, fps=30, label=np.int64(3), label_name="walk")
    np.testing.assert_array_equal(flat.poses, m.poses)
    assert flat.fps == 30.0 and isinstance(flat.label, int) and flat.source == {}


def test_motion_is_frozen_and_owns_its_arrays():
    poses = np.zeros((4, 24, 3))
    m = Motion(poses=poses, trans=np.zeros((4, 3)), fps=30, label=0, label_name="rest")
    poses[0, 0, 0] = 1.0
    assert m.poses[0, 0, 0] == 0.0
    with pytest.raises(AttributeError):
        m.fps = 60.0


def test_wrong_joint_count():
    with pytest.raises(InputError, match=r"expected 24 joints per frame .*got 23"):
        Motion(poses=np.zeros((5, 23, 3)), trans=np.zeros((5, 3)), fps=30, label=0, label_name="x")
    with pytest.raises(InputError, match=r"expected 24 joints per frame .*got 52"):
        Motion(poses=np.zeros((5, 156)), trans=np.zeros((5, 3)), fps=30, label=0, label_name="x")
    with pytest.raises(InputError, match=r"poses has shape \(5, 24\); expected \[T, 24, 3\]"):
        Motion(poses=np.zeros((5, 24)), trans=np.zeros((5, 3)), fps=30, label=0, label_name="x")


def test_mismatched_frame_counts_and_bad_trans():
    with pytest.raises(InputError, match=r"trans has 9 frames but poses has 10; pass one root translation"):
        Motion(poses=np.zeros((10, 24, 3)), trans=np.zeros((9, 3)), fps=30, label=0, label_name="x")
    with pytest.raises(InputError, match=r"trans has shape \(10, 2\); expected \[T, 3\]"):
        Motion(poses=np.zeros((10, 24, 3)), trans=np.zeros((10, 2)), fps=30, label=0, label_name="x")
    with pytest.raises(InputError, match="poses has 0 frames"):
        Motion(poses=np.zeros((0, 24, 3)), trans=np.zeros((0, 3)), fps=30, label=0, label_name="x")


def test_non_finite_values():
    poses = np.zeros((10, 24, 3))
    poses[3, 5, 0] = np.nan
    poses[7, 2, 1] = np.inf
    poses[7, 2, 2] = -np.inf
    with pytest.raises(InputError, match=r"poses has 3 non-finite values \(NaN or inf\) in 2 frames \[3, 7\], "
                                         r"joints \[2, 5\]"):
        Motion(poses=poses, trans=np.zeros((10, 3)), fps=30, label=0, label_name="x")
    trans = np.zeros((10, 3))
    trans[4, 1] = np.nan
    with pytest.raises(InputError, match=r"trans has 1 non-finite value \(NaN or inf\) in 1 frame \[4\]"):
        Motion(poses=np.zeros((10, 24, 3)), trans=trans, fps=30, label=0, label_name="x")


@pytest.mark.parametrize("fps", [0, -5.0, float("nan"), float("inf")])
def test_fps_must_be_positive(fps):
    with pytest.raises(InputError, match=r"fps must be finite and > 0 frames per second"):
        Motion(poses=np.zeros((2, 24, 3)), trans=np.zeros((2, 3)), fps=fps, label=0, label_name="x")


def test_label_and_source_checked():
    ok = {"poses": np.zeros((2, 24, 3)), "trans": np.zeros((2, 3)), "fps": 30}
    with pytest.raises(InputError, match="label must be an int"):
        Motion(**ok, label="walk", label_name="walk")
    with pytest.raises(InputError, match="label_name must be a str"):
        Motion(**ok, label=1, label_name=1)
    with pytest.raises(InputError, match="source must be JSON-serialisable"):
        Motion(**ok, label=1, label_name="walk", source={"f": object()})
    # numpy values in the source are converted to plain JSON values.
    m = Motion(**ok, label=1, label_name="walk", source={"params": {"speed": np.float32(1.5), "n": np.int64(2)}})
    assert m.source == {"params": {"speed": 1.5, "n": 2}}


# ----------------------------------------------------------------------------- resample

def test_resample_30_60_30_preserves_original_frames():
    m = make_motion(frames=31, fps=30.0)
    up = m.resample(60.0)
    assert up.frame_count == 61 and up.fps == 60.0
    assert up.duration == pytest.approx(m.duration)
    np.testing.assert_allclose(up.poses[::2], m.poses, atol=1e-6)
    np.testing.assert_allclose(up.trans[::2], m.trans, atol=1e-6)
    down = up.resample(30.0)
    assert down.frame_count == 31
    np.testing.assert_allclose(down.poses, m.poses, atol=1e-6)
    np.testing.assert_allclose(down.trans, m.trans, atol=1e-6)
    assert down.source["resampled_from_fps"] == 60.0 and down.label == m.label


def test_resample_midpoints_are_slerp_midpoints():
    m = make_motion(frames=11, fps=30.0, seed=5)
    up = m.resample(60.0)
    mid = up.poses[1::2]  # halfway between original frames k and k + 1
    R0 = Rotation.from_rotvec(m.poses[:-1].reshape(-1, 3))
    R1 = Rotation.from_rotvec(m.poses[1:].reshape(-1, 3))
    expected = R0 * Rotation.from_rotvec(0.5 * (R0.inv() * R1).as_rotvec())
    np.testing.assert_allclose(axis_angle_to_matrix_np(mid.reshape(-1, 3)), expected.as_matrix(), atol=1e-10)
    # Equal angular distance to both neighbours, per joint.
    np.testing.assert_allclose(geodesic(m.poses[:-1], mid), geodesic(mid, m.poses[1:]), atol=1e-9)
    np.testing.assert_allclose(up.trans[1::2], 0.5 * (m.trans[:-1] + m.trans[1:]), atol=1e-12)


def test_resample_single_axis_rotation_and_frame_times():
    # One joint turning about a fixed axis at a constant rate: any resampling is exact.
    frames, fps = 16, 30.0
    axis = np.array([0.0, 0.6, 0.8])
    angles = np.linspace(0.0, 1.5, frames)
    poses = np.zeros((frames, 24, 3))
    poses[:, 18] = angles[:, None] * axis
    trans = np.stack([np.linspace(0, 1, frames), np.zeros(frames), np.zeros(frames)], axis=1)
    m = Motion(poses=poses, trans=trans, fps=fps, label=0, label_name="turn")
    r = m.resample(24.0)
    # New frames at k / 24 s while <= duration = 15 / 30 s: k = 0..12.
    assert r.frame_count == 13
    t = np.arange(13) / 24.0
    rate = 1.5 / m.duration
    np.testing.assert_allclose(r.poses[:, 18], (rate * t)[:, None] * axis, atol=1e-12)
    np.testing.assert_allclose(r.trans[:, 0], t / m.duration, atol=1e-12)
    np.testing.assert_array_equal(r.poses[:, :18], 0.0)
    with pytest.raises(InputError, match="the new fps must be finite and > 0"):
        m.resample(0)


# ----------------------------------------------------------------------------- segments

def test_segments_count_and_contents():
    m = make_motion(frames=130, fps=30.0, seed=2)
    segs = m.segments(60)
    assert len(segs) == 2  # frames 0-59 and 60-119; the 10-frame tail is dropped
    for seg, start in zip(segs, (0, 60)):
        assert seg.frame_count == 60 and seg.fps == m.fps and seg.label == m.label
        np.testing.assert_array_equal(seg.poses, m.poses[start:start + 60])
        np.testing.assert_array_equal(seg.trans, m.trans[start:start + 60])
        assert seg.source["segment_start"] == start and seg.source["segment_length"] == 60
        assert seg.source["generator"] == "test"
    overlapping = m.segments(length=60, stride=30)
    assert [s.source["segment_start"] for s in overlapping] == [0, 30, 60]
    np.testing.assert_array_equal(overlapping[1].poses, m.poses[30:90])
    # Segments of a segment record their start in the original motion.
    nested = overlapping[1].segments(length=20)
    assert [s.source["segment_start"] for s in nested] == [30, 50, 70]
    np.testing.assert_array_equal(nested[2].poses, m.poses[70:90])
    assert m.segments(length=131) == []
    assert len(m.segments(length=130)) == 1


@pytest.mark.parametrize("kwargs", [{"length": 0}, {"length": 2.5}, {"length": 10, "stride": 0}])
def test_segments_bad_arguments(kwargs):
    with pytest.raises(InputError, match=r"must be an int >= 1 \(frames\)"):
        make_motion().segments(**kwargs)


# ----------------------------------------------------------------------------- lead-in

def test_lead_in_from_t_pose():
    m = make_motion(frames=20, fps=30.0, seed=3)
    led, n = m.with_lead_in(0.5)
    assert n == 15 and led.frame_count == 35 and led.source["lead_in_frames"] == 15
    np.testing.assert_array_equal(led.poses[0], np.zeros((24, 3)))
    np.testing.assert_array_equal(led.poses[n:], m.poses)  # ends exactly at the first frame
    np.testing.assert_array_equal(led.trans[n:], m.trans)
    np.testing.assert_array_equal(led.trans[:n], np.repeat(m.trans[:1], n, axis=0))
    # Each joint moves along the slerp path with a smoothstep ease: the fraction of the way
    # covered at lead-in frame i is 3u^2 - 2u^3, u = i / n.
    total = geodesic(np.zeros((24, 3)), m.poses[0])  # [24]
    covered = geodesic(np.zeros((n + 1, 24, 3)), led.poses[: n + 1])  # [n + 1, 24]
    u = np.arange(n + 1) / n
    np.testing.assert_allclose(covered, np.outer(u * u * (3 - 2 * u), total), atol=1e-9)
    remaining = geodesic(led.poses[: n + 1], np.broadcast_to(m.poses[0], (n + 1, 24, 3)))
    np.testing.assert_allclose(remaining + covered, np.broadcast_to(total, covered.shape), atol=1e-9)
    # The ease starts and ends with zero velocity.
    assert np.all(covered[1] < 0.02 * total) and np.all(total - covered[n - 1] < 0.02 * total)


def test_lead_in_from_given_rest_pose_and_edge_cases():
    m = make_motion(frames=10, fps=60.0, seed=4)
    rest = np.zeros((24, 3))
    rest[16] = [0.0, 0.0, -1.2]  # arms down, an A-pose
    rest[17] = [0.0, 0.0, 1.2]
    led, n = m.with_lead_in(0.25, rest_pose=rest)
    assert n == 15
    np.testing.assert_array_equal(led.poses[0], rest)
    np.testing.assert_array_equal(led.poses[n], m.poses[0])
    mid = geodesic(np.broadcast_to(rest, (24, 3)), led.poses[n // 2])
    assert np.all(mid <= geodesic(rest, m.poses[0]) + 1e-12)
    same, zero = m.with_lead_in(0.0)
    assert zero == 0 and same is m
    with pytest.raises(InputError, match="lead-in seconds must be finite and >= 0"):
        m.with_lead_in(-1.0)
    with pytest.raises(InputError, match=r"rest_pose has shape \(23, 3\); expected \[24, 3\]"):
        m.with_lead_in(0.5, rest_pose=np.zeros((23, 3)))


# ----------------------------------------------------------------------------- npz

def test_npz_round_trip(tmp_path):
    m = make_motion(frames=17, fps=120.0, seed=6, label=7, label_name="jumping jacks",
                    source={"kind": "file", "path": "/data/a.bvh", "params": {"scale": 0.01}})
    path = tmp_path / "motion.npz"
    m.save_npz(path)
    with np.load(path, allow_pickle=False) as data:
        assert sorted(data.files) == sorted(NPZ_KEYS)
        assert data["poses"].shape == (17, 72) and data["trans"].shape == (17, 3)
        assert float(data["mocap_framerate"]) == 120.0
        assert json.loads(str(data["source"]))["path"] == "/data/a.bvh"
    back = Motion.load_npz(path)
    np.testing.assert_array_equal(back.poses, m.poses)
    np.testing.assert_array_equal(back.trans, m.trans)
    assert (back.fps, back.label, back.label_name, back.source) == (m.fps, m.label, m.label_name, m.source)


def test_npz_errors(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        Motion.load_npz(tmp_path / "missing.npz")
    amass_like = tmp_path / "amass.npz"
    np.savez(amass_like, poses=np.zeros((3, 156)), trans=np.zeros((3, 3)), mocap_framerate=120.0)
    with pytest.raises(InputError, match=r"lacks \['label', 'label_name', 'source'\]"):
        Motion.load_npz(amass_like)
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"not a zip file")
    with pytest.raises(InputError, match="not a readable .npz"):
        Motion.load_npz(garbage)
    pickled = tmp_path / "pickled.npz"
    np.savez(pickled, poses=np.zeros((3, 72)), trans=np.zeros((3, 3)), mocap_framerate=30.0, label=1,
             label_name="x", source=np.array([{"kind": "file"}], dtype=object))
    with pytest.raises(InputError, match="pickled objects"):
        Motion.load_npz(pickled)
