"""The procedural motion library: every label, determinism, style ranges, IK contact, quality, CLI."""

from __future__ import annotations

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.motion.labels import LABELS, label_index, label_vocabulary
from datagen.motion.library import _GENERATORS, LABEL_PARAMS, make_motion, style_params
from datagen.motion.procedural import J, Rig, euler, forward_kinematics
from datagen.geometry.rotations import axis_angle_to_matrix_np

FRAMES = 60


@pytest.fixture(scope="module")
def rig(default_body):
    return Rig.from_body(default_body)


@pytest.fixture(scope="module")
def library(rig):
    return {label: make_motion(label, seed=0, frames=FRAMES, rig=rig) for label in LABELS}


@pytest.fixture(scope="module")
def probe(default_body):
    from datagen.motion.quality import BodyProbe

    return BodyProbe(default_body)


def test_at_least_16_labels_with_two_dances_and_a_generator_each():
    assert len(LABELS) >= 16
    assert sum(name.startswith("dance") for name in LABELS) >= 2
    assert set(_GENERATORS) == set(LABELS) == set(LABEL_PARAMS)
    assert label_vocabulary(["walk", "cartwheel"]) == (*LABELS, "cartwheel")


def test_every_label_generates_finite_labelled_motion(library):
    for i, label in enumerate(LABELS):
        m = library[label]
        assert m.poses.shape == (FRAMES, 24, 3) and m.trans.shape == (FRAMES, 3)
        assert np.isfinite(m.poses).all() and np.isfinite(m.trans).all()
        assert m.label == i == label_index(label) and m.label_name == label
        assert m.source["kind"] == "procedural" and m.source["seed"] == 0
        assert set(m.source["params"]) == set(LABEL_PARAMS[label])


def test_same_seed_same_motion_other_seed_other_motion(rig, library):
    again = make_motion("dance_sway", seed=0, frames=FRAMES, rig=rig)
    np.testing.assert_array_equal(again.poses, library["dance_sway"].poses)
    np.testing.assert_array_equal(again.trans, library["dance_sway"].trans)
    other = make_motion("dance_sway", seed=1, frames=FRAMES, rig=rig)
    assert np.abs(other.poses - again.poses).max() > 0.05


def test_style_parameters_drawn_in_range_and_overridable():
    for label in ("walk", "squat", "box"):
        for seed in range(20):
            p = style_params(label, seed)
            for name, spec in LABEL_PARAMS[label].items():
                assert spec.low <= p[name] <= spec.high
    assert style_params("squat", 3, {"depth": 0.3})["depth"] == 0.3


def test_bad_label_and_parameters_say_what_is_allowed(rig):
    with pytest.raises(InputError, match="known labels: walk, run"):
        make_motion("moonwalk", rig=rig)
    with pytest.raises(InputError, match=r"allowed range is \[0.2, 0.38\]"):
        make_motion("squat", params={"depth": 1.0}, rig=rig)
    with pytest.raises(InputError, match="has no style parameter 'speed'"):
        make_motion("walk", params={"speed": 1.0}, rig=rig)
    with pytest.raises(InputError, match="frames must be an integer >= 2"):
        make_motion("walk", frames=1, rig=rig)


def test_sign_conventions(rig):
    """The axes the generators rely on (documented in datagen.motion.procedural)."""
    def fk(joint, R):
        local = np.repeat(np.eye(3)[None, None], 24, axis=1).copy()
        local[0, J[joint]] = R[0]
        pos, _ = forward_kinematics(rig, rig.rest_joints[None, 0], local)
        return pos[0] - rig.rest_joints

    a = 0.5
    assert fk("left_hip", euler("left_hip", x=-a))[J["left_ankle"], 2] > 0.1  # foot swings forward
    assert fk("left_knee", euler("left_knee", x=a))[J["left_ankle"], 2] < -0.1  # shin folds back
    assert fk("left_shoulder", euler("left_shoulder", z=-a))[J["left_wrist"], 1] < -0.1  # arm lowers
    assert fk("right_shoulder", euler("right_shoulder", z=a))[J["right_wrist"], 1] < -0.1
    assert fk("left_elbow", euler("left_elbow", y=-a))[J["left_wrist"], 2] > 0.05  # forearm forward
    assert fk("spine1", euler("spine1", x=a))[J["head"], 2] > 0.1  # trunk bends forward


def test_planted_feet_stay_put_and_on_the_ground(rig):
    """Stance frames of a walk: the ball of the foot does not slide, nothing sinks below the floor."""
    from datagen.motion.library import _Ctx
    from datagen.motion.procedural import PoseTrack, assemble

    for seed in range(3):
        p = style_params("walk", seed)
        c = _Ctx(rig=rig, t=np.arange(90) / 30.0, p=p, track=PoseTrack(frame_count=90))
        _GENERATORS["walk"](c)
        poses, trans = assemble(rig, c.track)
        pos, _ = forward_kinematics(rig, trans + rig.rest_joints[0], axis_angle_to_matrix_np(poses))
        err = np.linalg.norm(pos[:, J["left_ankle"]] - c.track.ankle_target["left"], axis=1)
        assert np.median(err) < 1e-3 and err.max() < 0.02  # the IK reaches its targets
        ball = pos[:, J["left_foot"]]
        low = ball[:, 1] < rig.rest_joints[J["left_foot"], 1] + 2e-3
        slide = np.linalg.norm(np.diff(ball[:, [0, 2]], axis=0), axis=1)[low[1:] & low[:-1]]
        assert low.sum() > 20 and slide.max() < 3e-3  # m per frame while the ball is down
        assert ball[:, 1].min() > rig.rest_joints[J["left_foot"], 1] - 1e-3


def test_every_label_passes_the_quality_filters(library, probe):
    """Seed 0 of every label on the default body: no interpenetration, limits kept, feet on the floor."""
    from datagen.motion.quality import measure_motion

    for label, m in library.items():
        q = measure_motion(m, probe, stride=4)
        assert q.penetration_frames == 0, label
        assert q.arm_leg_clearance > 0.02, (label, q.arm_leg_clearance)  # m: room for cloth between
        assert q.limit_violation_share == 0.0, (label, q.limit_worst_joint, q.limit_worst_excess_deg)
        assert q.ground_penetration < 0.005, label
        assert q.foot_skate < 0.05, label  # m/s during contact
        R = axis_angle_to_matrix_np(m.poses)
        rel = np.einsum("tjba,tjbc->tjac", R[:-1], R[1:])  # R_t^T R_t+1
        step = np.arccos(np.clip((np.trace(rel, axis1=-2, axis2=-1) - 1) / 2, -1, 1))  # [T-1, 24] rad
        # no jumps: a discontinuity is one frame-to-frame rotation much larger than both of its
        # neighbours'; fast but continuous movements (a punch turns the elbow ~0.5 rad per
        # frame at 30 fps) pass
        jump = step[1:-1] - 3.0 * np.maximum(step[:-2], step[2:])
        assert jump.max() < 0.05, (label, jump.max())


def test_filter_drops_an_interpenetrating_motion(library, probe):
    from datagen.motion.motion import Motion
    from datagen.motion.quality import filter_motions
    from datagen.geometry.rotations import matrix_to_axis_angle_np

    bad = library["wave"].poses.copy()
    # left arm lowered and driven across the chest: the forearm goes into the torso
    R = euler("left_shoulder", x=-0.2, y=1.6, z=-1.2)[0]
    bad[:, J["left_shoulder"]] = matrix_to_axis_angle_np(R)
    bad[:, J["left_elbow"]] = matrix_to_axis_angle_np(euler("left_elbow", y=-0.3)[0])
    through = Motion(poses=bad, trans=library["wave"].trans, fps=30.0, label=6, label_name="wave")
    kept, report = filter_motions([library["walk"], through], probe, stride=6)
    assert kept == [library["walk"]]
    assert report[1].penetration_share > 0.5 and report[0].penetration_share == 0.0


def test_squat_forearms_stay_off_the_thighs(default_body):
    """Every squat seed on the fat body keeps its forearms 3 cm or more from the legs (generator
    version 1's squat rested them on the thighs, and cloth caught between tore in the simulator)."""
    from datagen.body.shapes import resolve_betas
    from datagen.motion.quality import BodyProbe, measure_motion

    fat = BodyProbe(default_body, resolve_betas(default_body, body="fat")[0])
    for seed in range(10):
        q = measure_motion(make_motion("squat", seed=seed, frames=90), fat, stride=3)
        assert q.arm_leg_clearance > 0.03, (seed, q.arm_leg_clearance)


def test_filter_drops_forearms_on_the_thighs(library, probe):
    from datagen.motion.motion import Motion
    from datagen.motion.quality import filter_motions
    from datagen.geometry.rotations import matrix_to_axis_angle_np

    bad = library["squat"].poses.copy()
    # both arms hanging straight down through the squat: the forearms meet the thighs at the bottom
    for side, sign in (("left", 1.0), ("right", -1.0)):
        bad[:, J[f"{side}_shoulder"]] = matrix_to_axis_angle_np(euler(f"{side}_shoulder", z=-sign * 1.45)[0])
        bad[:, J[f"{side}_elbow"]] = 0.0
    low = Motion(poses=bad, trans=library["squat"].trans, fps=30.0, label=3, label_name="squat")
    kept, report = filter_motions([library["squat"], low], probe, stride=3)
    assert kept == [library["squat"]]
    assert report[1].arm_leg_clearance < 0.01 < report[0].arm_leg_clearance


def test_cli_list_make_export_import(tmp_path, capsys):
    from datagen.cli import main

    assert main(["motion", "list"]) == 0
    assert "dance_disco" in capsys.readouterr().out
    out = tmp_path / "walk.npz"
    assert main(["motion", "make", "--label", "walk", "--seed", "3", "--frames", "40", "--out", str(out)]) == 0
    from datagen.motion.motion import Motion

    m = Motion.load_npz(out)
    assert m.frame_count == 40 and m.label_name == "walk"
    bvh = tmp_path / "walk.bvh"
    assert main(["motion", "export", str(out), "--format", "bvh", "--out", str(bvh)]) == 0
    back = tmp_path / "back.npz"
    assert main(["motion", "import", str(bvh), "--label-name", "walk", "--out", str(back)]) == 0
    R0 = axis_angle_to_matrix_np(m.poses)
    R1 = axis_angle_to_matrix_np(Motion.load_npz(back).poses)
    assert np.abs(R0 - R1).max() < 1e-4
    assert main(["motion", "make", "--label", "flying", "--out", str(tmp_path / "x.npz")]) == 2
    assert "known labels" in capsys.readouterr().err
    assert not (tmp_path / "x.npz").exists()


def test_every_label_exports_to_bvh_and_usd_and_reads_back(library, default_body, tmp_path):
    from datagen.motion.bvh import read_bvh
    from datagen.export.motion import write_motion_bvh, write_motion_usd

    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from pxr import Usd, UsdGeom

    for label, m in library.items():
        short = m.segments(length=6)[0]
        path = write_motion_bvh(short, tmp_path / f"{label}.bvh", default_body)
        back = read_bvh(path, label_name=label)
        R0, R1 = axis_angle_to_matrix_np(short.poses), axis_angle_to_matrix_np(back.poses)
        assert np.abs(R0 - R1).max() < 1e-4, label
        usd = write_motion_usd(short, tmp_path / f"{label}.usda", default_body)
        stage = Usd.Stage.Open(str(usd))
        mesh = next(UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
        verts, _ = default_body.pose(np.zeros((1, default_body.shape_dim)), short.poses[5].reshape(1, -1), short.trans[5:6])
        np.testing.assert_allclose(np.asarray(mesh.GetPointsAttr().Get(5)), verts[0], atol=1e-5)
