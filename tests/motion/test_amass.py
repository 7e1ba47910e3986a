"""AMASS reader: joint conversion, Z-up to Y-up, frame rates, label maps and errors (synthetic files)."""

import json

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.motion.amass import (
    LabelMap,
    load_label_map,
    read_amass,
    resolve_label,
    up_axis_rotation,
)
from datagen.motion.labels import LABELS
from datagen.geometry.rotations import axis_angle_to_matrix_np

C = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # -90 deg about X: Z up -> Y up


def write_amass(path, frames=12, width=156, fps=120.0, seed=0, fps_key="mocap_framerate", drop=(), **overrides):
    """A synthetic AMASS npz: random finite poses; frame 0 stands upright in AMASS's Z-up world."""
    rng = np.random.default_rng(seed)
    poses = rng.normal(scale=0.3, size=(frames, width))
    poses[0, :3] = [np.pi / 2, 0.0, 0.0]  # AMASS root orientation of a body standing along +Z
    arrays = {
        "poses": poses,
        "trans": rng.normal(size=(frames, 3)),
        "betas": rng.normal(size=16),
        fps_key: np.float64(fps),
        "gender": np.str_("female"),
        "dmpls": np.zeros((frames, 8)),
    }
    arrays.update(overrides)
    for key in drop:
        arrays.pop(key)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, **arrays)
    return arrays


def test_smplh_joints_up_axis_and_source(tmp_path):
    f = tmp_path / "01_01_poses.npz"
    arrays = write_amass(f)
    m = read_amass(f, label_name="walk")
    src = arrays["poses"].reshape(12, 52, 3)
    assert m.poses.shape == (12, 24, 3) and m.fps == 120.0
    np.testing.assert_array_equal(m.poses[:, 1:22], src[:, 1:22])  # body joints copied
    np.testing.assert_array_equal(m.poses[:, 22:], 0.0)             # SMPL hands: identity
    # The standing frame's root (+90 deg about X in Z-up) becomes the identity in Y-up.
    np.testing.assert_allclose(axis_angle_to_matrix_np(m.poses[0, 0]), np.eye(3), atol=1e-12)
    np.testing.assert_allclose(axis_angle_to_matrix_np(m.poses[:, 0]), C @ axis_angle_to_matrix_np(src[:, 0]),
                               atol=1e-12)
    np.testing.assert_allclose(m.trans, arrays["trans"][:, [0, 2, 1]] * [1, 1, -1], atol=1e-12)
    assert m.label == LABELS.index("walk") and m.label_name == "walk"
    assert m.source["kind"] == "file" and m.source["format"] == "amass" and m.source["path"] == str(f)
    assert m.source["betas"] == pytest.approx(arrays["betas"].tolist())
    assert m.source["body_model"] == "smplh" and m.source["gender"] == "female"


def test_up_axis_y_keeps_the_root(tmp_path):
    f = tmp_path / "a.npz"
    arrays = write_amass(f)
    m = read_amass(f, label_name="walk", up_axis="y")
    np.testing.assert_array_equal(m.poses[:, 0], arrays["poses"][:, :3])
    np.testing.assert_array_equal(m.trans, arrays["trans"])
    with pytest.raises(InputError, match="up_axis"):
        read_amass(f, label_name="walk", up_axis="x")
    np.testing.assert_array_equal(up_axis_rotation("z"), C)


def test_smpl_and_smplx_widths_and_framerate_key(tmp_path):
    f72, f165 = tmp_path / "smpl.npz", tmp_path / "smplx.npz"
    a72 = write_amass(f72, width=72)
    a165 = write_amass(f165, width=165, fps=60.0, fps_key="mocap_frame_rate")
    m72 = read_amass(f72, label_name="run", up_axis="y")
    np.testing.assert_array_equal(m72.poses, a72["poses"].reshape(-1, 24, 3))  # SMPL: hands kept
    m165 = read_amass(f165, label_name="run", up_axis="y")
    np.testing.assert_array_equal(m165.poses[:, :22], a165["poses"].reshape(-1, 55, 3)[:, :22])
    np.testing.assert_array_equal(m165.poses[:, 22:], 0.0)
    assert m165.fps == 60.0 and m165.source["body_model"] == "smplx"


def test_root_orient_pose_body_layout(tmp_path):
    f = tmp_path / "x.npz"
    rng = np.random.default_rng(3)
    root, body = rng.normal(size=(5, 3)), rng.normal(size=(5, 63))
    np.savez(f, root_orient=root, pose_body=body, trans=np.zeros((5, 3)), mocap_frame_rate=30.0)
    m = read_amass(f, label_name="walk", up_axis="y")
    np.testing.assert_array_equal(m.poses[:, 1:22].reshape(5, 63), body)
    assert m.source["betas"] is None


def test_resample_on_read(tmp_path):
    f = tmp_path / "a.npz"
    write_amass(f, frames=121)  # 1 s at 120 fps
    m = read_amass(f, label_name="walk", fps=30)
    assert m.fps == 30 and m.frame_count == 31 and m.source["resampled_from_fps"] == 120.0


def test_label_maps_json_and_yaml(tmp_path):
    patterns = {"*/CMU/*walk*": "walk", "*jump*": "jump", "*salsa*": "salsa"}
    jmap = tmp_path / "labels.json"
    jmap.write_text(json.dumps({"patterns": patterns}))
    ymap = tmp_path / "labels.yaml"
    ymap.write_text("patterns:\n" + "".join(f'  "{k}": {v}\n' for k, v in patterns.items()))
    walk, both, salsa = tmp_path / "CMU" / "07_walk.npz", tmp_path / "walk_jump.npz", tmp_path / "s" / "Salsa_1.npz"
    for f in (walk, both, salsa):
        write_amass(f, frames=3)
    for map_file in (jmap, ymap):
        lm = load_label_map(map_file)
        assert isinstance(lm, LabelMap) and lm.vocabulary == (*LABELS, "salsa")
        m = read_amass(walk, map_file)
        assert (m.label, m.label_name) == (LABELS.index("walk"), "walk")
        m = read_amass(both, lm)  # no */CMU/ in the path: the basename matches "*jump*"
        assert (m.label, m.label_name) == (LABELS.index("jump"), "jump")
        m = read_amass(salsa, lm)  # case-insensitive; a name drape does not generate comes after LABELS
        assert (m.label, m.label_name) == (len(LABELS), "salsa")
        m = read_amass(salsa, lm, label_name="run")  # override
        assert (m.label, m.label_name) == (LABELS.index("run"), "run")
    first = LabelMap.from_patterns({"*walk*": "walk", "*jump*": "jump"})
    assert first.match(both) == "walk"  # first match wins


def test_unlabelled_is_an_error_unless_allowed(tmp_path):
    f = tmp_path / "mystery.npz"
    write_amass(f, frames=3)
    lm_file = tmp_path / "labels.json"
    lm_file.write_text(json.dumps({"patterns": {"*walk*": "walk"}}))
    with pytest.raises(InputError, match=r"mystery\.npz.*labels\.json|labels\.json.*mystery\.npz"):
        read_amass(f, lm_file)
    with pytest.raises(InputError, match="label_name"):
        read_amass(f)
    m = read_amass(f, lm_file, allow_unlabelled=True)
    assert (m.label, m.label_name) == (-1, "unlabelled")
    assert resolve_label("x.npz", label_name="new_thing") == (len(LABELS), "new_thing")


def test_errors(tmp_path):
    missing = tmp_path / "missing_trans.npz"
    write_amass(missing, drop=("trans",))
    with pytest.raises(InputError, match=r"no 'trans'.*\[T, 156\]"):
        read_amass(missing, label_name="walk")
    no_rate = tmp_path / "no_rate.npz"
    write_amass(no_rate, drop=("mocap_framerate",))
    with pytest.raises(InputError, match="mocap_framerate"):
        read_amass(no_rate, label_name="walk")
    narrow = tmp_path / "w60.npz"
    write_amass(narrow, width=60)
    with pytest.raises(InputError, match=r"\(12, 60\).*72 \(SMPL, .*156 \(SMPL-H, .*165 \(SMPL-X"):
        read_amass(narrow, label_name="walk")
    bad = tmp_path / "nan.npz"
    arrays = write_amass(bad)
    arrays["poses"][4, 10] = np.nan
    np.savez(bad, **arrays)
    with pytest.raises(InputError, match=r"non-finite.*\[4\]"):
        read_amass(bad, label_name="walk")
    with pytest.raises(InputError, match="does not exist"):
        read_amass(tmp_path / "nope.npz", label_name="walk")
    with pytest.raises(InputError, match="does not exist"):
        load_label_map(tmp_path / "nope.json")
    broken = tmp_path / "broken.yaml"
    broken.write_text("patterns: [unclosed\n")
    with pytest.raises(InputError, match="YAML"):
        load_label_map(broken)
    wrong = tmp_path / "wrong.json"
    wrong.write_text(json.dumps({"walk": "*walk*"}))
    with pytest.raises(InputError, match="patterns"):
        load_label_map(wrong)
