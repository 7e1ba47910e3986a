"""BVH reader (retarget onto SMPL, units, joint maps) and writer (round trip, bvhio compatible)."""

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from datagen.body.skeleton import SMPL_JOINT_NAMES, SMPL_PARENTS
from datagen.errors import InputError
from datagen.motion.bvh import UNIT_SCALES, _import_bvhio, read_bvh, write_bvh
from datagen.motion.motion import Motion
from datagen.geometry.rotations import axis_angle_to_matrix_np

bvhio = _import_bvhio()
CMU_UNIT = 0.0254 / 0.45

# A CMU-style skeleton (cgspeed units: about 27 units from toes to the top of the head), T-pose rest,
# facing +Z with the left side on +X: (name, parent, offset, end-site offset or None).
SIDE = [  # left side; the right side mirrors X
    ("{L}HipJoint", "Hips", (0.0, 0.0, 0.0), None),
    ("{S}UpLeg", "{L}HipJoint", (1.65, -1.8, 0.62), None),
    ("{S}Leg", "{S}UpLeg", (2.6, -7.1, 0.0), None),
    ("{S}Foot", "{S}Leg", (2.5, -7.0, 0.0), None),
    ("{S}ToeBase", "{S}Foot", (0.0, -1.0, 2.3), (0.0, 0.0, 1.2)),
    ("{S}Shoulder", "Spine1", (0.0, 1.0, 0.0), None),
    ("{S}Arm", "{S}Shoulder", (3.4, 0.0, 0.0), None),
    ("{S}ForeArm", "{S}Arm", (5.0, 0.0, 0.0), None),
    ("{S}Hand", "{S}ForeArm", (3.5, 0.0, 0.0), None),
    ("{S}FingerBase", "{S}Hand", (0.0, 0.0, 0.0), None),
    ("{S}HandIndex1", "{S}FingerBase", (0.7, 0.0, 0.0), (0.6, 0.0, 0.0)),
    ("{L}Thumb", "{S}Hand", (0.0, 0.0, 0.0), (0.5, 0.0, 0.5)),
]
CENTRE = [
    ("Hips", None, (0.0, 0.0, 0.0), None),
    ("LowerBack", "Hips", (0.0, 0.0, 0.0), None),
    ("Spine", "LowerBack", (0.03, 2.1, -0.1), None),
    ("Spine1", "Spine", (0.05, 2.1, -0.04), None),
    ("Neck", "Spine1", (0.0, 1.8, 0.1), None),
    ("Neck1", "Neck", (0.0, 1.5, 0.1), None),
    ("Head", "Neck1", (0.0, 1.5, -0.1), (0.0, 1.5, 0.0)),
]


def cmu_skeleton(extra=()):
    joints = list(CENTRE)
    for S, L, sign in (("Left", "L", 1.0), ("Right", "R", -1.0)):
        for name, parent, off, end in SIDE:
            fmt = {"S": S, "L": L}
            joints.append((name.format(**fmt), parent.format(**fmt), (sign * off[0], off[1], off[2]),
                           None if end is None else (sign * end[0], end[1], end[2])))
    return joints + list(extra)


def write_bvh_text(path, joints, rotations, positions, frame_time=1 / 120, root_offset=(0.0, 0.0, 0.0),
                   order="ZYX", scale=1.0):
    """Write a BVH: ``rotations`` {joint: [T, 3] degrees in ``order``}, ``positions`` [T, 3] (root)."""
    T = len(positions)
    children = {}
    for name, parent, _, _ in joints:
        children.setdefault(parent, []).append(name)
    info = {name: (off, end) for name, _, off, end in joints}
    lines, columns = ["HIERARCHY"], []

    def fmt(v):
        return " ".join(f"{x * scale:.6f}" for x in v)

    def emit(name, depth):
        pad = "\t" * depth
        off, end = info[name]
        lines.append(f"{pad}{'ROOT' if depth == 0 else 'JOINT'} {name}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}\tOFFSET {fmt(root_offset if depth == 0 else off)}")
        rot = " ".join(f"{a}rotation" for a in order)
        if depth == 0:
            lines.append(f"{pad}\tCHANNELS 6 Xposition Yposition Zposition {rot}")
            columns.append(np.asarray(positions, dtype=float) * scale)
        else:
            lines.append(f"{pad}\tCHANNELS 3 {rot}")
        columns.append(rotations.get(name, np.zeros((T, 3))))
        for child in children.get(name, []):
            emit(child, depth + 1)
        if end is not None:
            lines.extend([f"{pad}\tEnd Site", f"{pad}\t{{", f"{pad}\t\tOFFSET {fmt(end)}", f"{pad}\t}}"])
        lines.append(f"{pad}}}")

    emit(children[None][0], 0)
    lines += ["MOTION", f"Frames: {T}", f"Frame Time: {frame_time:.7f}"]
    table = np.concatenate(columns, axis=1)
    lines += [" ".join(f"{v:.6f}" for v in row) for row in table]
    path.write_text("\n".join(lines) + "\n")


def euler(angles, order="ZYX"):
    return Rotation.from_euler(order, angles, degrees=True).as_matrix()


def mats(poses):
    return axis_angle_to_matrix_np(poses)


# SMPL joint -> the CMU joints whose local rotations compose into it (BVH joints between mapped
# ones fold into the next mapped joint).
CMU_CHAINS = {
    "pelvis": ["Hips"], "spine1": ["LowerBack"], "spine2": ["Spine"], "spine3": ["Spine1"],
    "neck": ["Neck"], "head": ["Neck1", "Head"],
    **{f"{s}_{smpl}": [f"{S}{bvh}" for bvh in chain] for s, S in (("left", "Left"), ("right", "Right"))
       for smpl, chain in (("hip", ["HipJoint", "UpLeg"]), ("knee", ["Leg"]), ("ankle", ["Foot"]),
                           ("foot", ["ToeBase"]), ("collar", ["Shoulder"]), ("shoulder", ["Arm"]),
                           ("elbow", ["ForeArm"]), ("wrist", ["Hand"]), ("hand", ["FingerBase"]))},
}
CMU_CHAINS["left_hip"] = ["LHipJoint", "LeftUpLeg"]
CMU_CHAINS["right_hip"] = ["RHipJoint", "RightUpLeg"]


@pytest.fixture
def cmu_file(tmp_path):
    rng = np.random.default_rng(1)
    T = 6
    joints = cmu_skeleton()
    rotations = {name: rng.uniform(-60, 60, size=(T, 3)) for name, *_ in joints}
    rotations["Hips"][0] = rotations["LeftUpLeg"][0] = 0.0
    rotations["Hips"][1] = [0.0, 90.0, 0.0]   # Z Y X: a quarter turn about Y
    rotations["LeftUpLeg"][1] = [30.0, 0.0, 0.0]
    rotations["LHipJoint"][1] = 0.0
    positions = np.stack([np.linspace(0, 10, T), np.full(T, 17.0), np.zeros(T)], axis=1)
    path = tmp_path / "01_01.bvh"
    write_bvh_text(path, joints, rotations, positions)
    return path, rotations, positions


def test_cmu_retarget_matches_known_rotations(cmu_file):
    path, rotations, positions = cmu_file
    m = read_bvh(path, label_name="walk")
    assert m.poses.shape == (6, 24, 3) and m.fps == 120.0
    assert m.source["builtin_map"] == "cmu" and m.source["scale"] == pytest.approx(CMU_UNIT)
    assert {"LHipJoint", "Neck1", "LThumb", "LeftHandIndex1"} <= set(m.source["ignored_joints"])
    got = mats(m.poses)
    for smpl, chain in CMU_CHAINS.items():
        expected = np.eye(3)
        for bvh in chain:
            expected = expected @ euler(rotations[bvh])
        np.testing.assert_allclose(got[:, SMPL_JOINT_NAMES.index(smpl)], expected, atol=1e-5, err_msg=smpl)
    # Hand-checked frame: pelvis a quarter turn about Y, left hip 30 degrees about Z.
    np.testing.assert_allclose(got[1, 0], euler([0, 90, 0]), atol=1e-9)
    np.testing.assert_allclose(m.poses[1, 1], [0, 0, np.radians(30)], atol=1e-9)
    np.testing.assert_allclose(m.trans, positions * CMU_UNIT, atol=1e-9)  # root OFFSET is 0


def test_euler_convention_agrees_with_bvhio(cmu_file):
    path, rotations, _ = cmu_file
    bvh = bvhio.readAsBvh(str(path))
    joint = {j.Name: j for j, _, _ in bvh.Root.layout()}["LeftForeArm"]
    for t, key in enumerate(joint.Keyframes):
        q = key.Rotation  # glm quaternion, w x y z
        ours = Rotation.from_matrix(euler(rotations["LeftForeArm"][t]))
        theirs = Rotation.from_quat([q.x, q.y, q.z, q.w])
        assert (ours.inv() * theirs).magnitude() < 1e-5


def test_unit_guess_and_scale_override(tmp_path, caplog):
    T = 2
    positions = np.tile([0.0, 17.0, 0.0], (T, 1))
    cm = tmp_path / "cm.bvh"
    write_bvh_text(cm, cmu_skeleton(), {}, positions, scale=CMU_UNIT / 0.01)
    with caplog.at_level("INFO", logger="datagen.motion.bvh"):
        m = read_bvh(cm, label_name="walk")
    assert m.source["scale"] == UNIT_SCALES["cm"] and "guessed unit 'cm'" in caplog.text
    np.testing.assert_allclose(m.trans[0], [0.0, 17.0 * CMU_UNIT, 0.0], atol=1e-6)
    inches = tmp_path / "in.bvh"
    write_bvh_text(inches, cmu_skeleton(), {}, positions, scale=CMU_UNIT / 0.0254)
    assert read_bvh(inches, label_name="walk").source["scale"] == UNIT_SCALES["in"]
    assert read_bvh(cm, label_name="walk", scale=0.5).source["scale"] == 0.5
    tiny = tmp_path / "tiny.bvh"
    write_bvh_text(tiny, cmu_skeleton(), {}, positions, scale=0.001)
    with pytest.raises(InputError, match="pass scale="):
        read_bvh(tiny, label_name="walk")


def test_unknown_joint_error_and_map_file_override(tmp_path):
    T = 3
    rng = np.random.default_rng(5)
    wing = ("LeftWing", "Spine1", (1.0, 0.5, -1.0), (1.0, 0.0, 0.0))
    pinky = ("LeftPinky", "LeftHand", (0.5, 0.0, -0.3), (0.5, 0.0, 0.0))  # under a mapped wrist: ignored
    joints = cmu_skeleton(extra=[wing, pinky])
    rotations = {name: rng.uniform(-40, 40, size=(T, 3)) for name, *_ in joints}
    path = tmp_path / "wing.bvh"
    write_bvh_text(path, joints, rotations, np.zeros((T, 3)))
    with pytest.raises(InputError) as info:
        read_bvh(path, label_name="walk")
    msg = str(info.value)
    assert "LeftWing" in msg and "LeftPinky" not in msg and "null" in msg and "joint_map" in msg
    map_file = tmp_path / "map.json"
    map_file.write_text(json.dumps({"LeftWing": None, "Neck": None, "Neck1": "neck"}))
    m = read_bvh(path, map_file, label_name="walk")
    assert "LeftWing" in m.source["ignored_joints"] and "LeftPinky" in m.source["ignored_joints"]
    got = mats(m.poses)
    np.testing.assert_allclose(got[:, SMPL_JOINT_NAMES.index("neck")],
                               euler(rotations["Neck"]) @ euler(rotations["Neck1"]), atol=1e-5)
    np.testing.assert_allclose(got[:, SMPL_JOINT_NAMES.index("head")], euler(rotations["Head"]), atol=1e-5)
    yaml_map = tmp_path / "map.yaml"
    yaml_map.write_text("LeftWing: left_collar\n")  # LeftShoulder maps there too
    with pytest.raises(InputError, match="both map to SMPL joint 'left_collar'"):
        read_bvh(path, yaml_map, label_name="walk")
    with pytest.raises(InputError, match="not an SMPL joint"):
        read_bvh(path, {"LeftWing": "left_wing"}, label_name="walk")
    with pytest.raises(InputError, match="not below"):  # left and right legs swapped
        read_bvh(path, {"LeftWing": None, "LeftLeg": "right_knee", "RightLeg": "left_knee"}, label_name="walk")


def test_z_up_file(tmp_path):
    to_z = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # Y-up -> Z-up
    joints = [(n, p, tuple(to_z @ np.array(o)), None if e is None else tuple(to_z @ np.array(e)))
              for n, p, o, e in cmu_skeleton()]
    rotations = {"Hips": np.array([[40.0, 0.0, 0.0]]), "LeftUpLeg": np.array([[0.0, 0.0, 30.0]])}
    path = tmp_path / "zup.bvh"
    write_bvh_text(path, joints, rotations, np.array([[1.0, 2.0, 17.0]]))
    m = read_bvh(path, up_axis="z", label_name="walk")
    assert m.source["scale"] == pytest.approx(CMU_UNIT)
    np.testing.assert_allclose(mats(m.poses[0, 0]), euler([0, 40, 0], "XYZ"), atol=1e-9)  # turn about up
    np.testing.assert_allclose(mats(m.poses[0, 1]), euler([30, 0, 0], "XYZ"), atol=1e-9)  # X stays X
    np.testing.assert_allclose(m.trans[0], np.array([1.0, 17.0, -2.0]) * CMU_UNIT, atol=1e-9)


def random_motion(frames=8, seed=0):
    rng = np.random.default_rng(seed)
    poses = rng.normal(scale=1.0, size=(frames, 24, 3))
    poses[min(2, frames - 1), 5] = Rotation.from_euler("ZXY", [30, 90, -20], degrees=True).as_rotvec()  # gimbal lock
    poses[min(3, frames - 1), 7] = Rotation.from_euler("ZXY", [30, -89.9999, -20], degrees=True).as_rotvec()
    trans = rng.normal(scale=0.5, size=(frames, 3))
    return Motion(poses=poses, trans=trans, fps=30.0, label=1, label_name="run")


def rest_joints():
    """A plausible T-pose SMPL skeleton in metres (about 1.5 m from toe joint to head end)."""
    offsets = {"pelvis": (0, 0.9, 0), "spine1": (0, 0.1, 0), "spine2": (0, 0.13, 0), "spine3": (0, 0.05, 0),
               "neck": (0, 0.22, 0), "head": (0, 0.1, 0.05), "hip": (0.09, -0.09, 0), "knee": (0.02, -0.38, 0),
               "ankle": (-0.01, -0.4, -0.04), "foot": (0.02, -0.05, 0.12), "collar": (0.07, 0.11, 0),
               "shoulder": (0.11, 0.03, 0), "elbow": (0.26, 0, 0), "wrist": (0.25, 0, 0), "hand": (0.09, 0, 0)}
    pos = np.zeros((24, 3))
    for k, name in enumerate(SMPL_JOINT_NAMES):
        base = name.split("_", 1)[-1]
        off = np.array(offsets[base], dtype=float)
        if name.startswith("right_"):
            off[0] = -off[0]
        pos[k] = off + (pos[SMPL_PARENTS[k]] if k else 0.0)
    return pos


def test_write_read_round_trip(tmp_path):
    m = random_motion()
    path = write_bvh(m, tmp_path / "smpl.bvh", rest_joints())
    back = read_bvh(path, label_name="run")
    assert back.source["builtin_map"] == "smpl" and back.source["scale"] == 1.0 and back.fps == 30.0
    np.testing.assert_allclose(mats(back.poses), mats(m.poses), atol=1e-5)
    np.testing.assert_allclose(back.trans, m.trans, atol=1e-6)
    assert back.source["ignored_joints"] == []


def test_bvhio_reads_written_file(tmp_path):
    m = random_motion(frames=4)
    path = write_bvh(m, tmp_path / "smpl.bvh", rest_joints())
    bvh = bvhio.readAsBvh(str(path))
    assert bvh.FrameCount == 4 and bvh.FrameTime == pytest.approx(1 / 30)
    layout = {j.Name: j for j, _, _ in bvh.Root.layout()}
    assert set(layout) == set(SMPL_JOINT_NAMES)
    np.testing.assert_allclose([layout["left_knee"].Offset.x, layout["left_knee"].Offset.y],
                               (rest_joints()[4] - rest_joints()[1])[:2], atol=1e-6)
    for t, key in enumerate(layout["left_elbow"].Keyframes):
        q = key.Rotation
        theirs = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
        np.testing.assert_allclose(theirs, mats(m.poses[t, SMPL_JOINT_NAMES.index("left_elbow")]), atol=1e-5)
    hierarchy = bvhio.readAsHierarchy(str(path))
    assert hierarchy.Name == "pelvis"


def test_file_errors(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        read_bvh(tmp_path / "nope.bvh", label_name="walk")
    truncated = tmp_path / "trunc.bvh"
    truncated.write_text("HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n")
    with pytest.raises(InputError, match="MOTION"):
        read_bvh(truncated, label_name="walk")
    m = random_motion(frames=2)
    path = write_bvh(m, tmp_path / "ok.bvh", rest_joints())
    text = path.read_text().splitlines()
    (tmp_path / "short.bvh").write_text("\n".join(text[:-1] + [" ".join(text[-1].split()[:-2])]) + "\n")
    with pytest.raises(InputError, match="frame 1 has 73 values"):
        read_bvh(tmp_path / "short.bvh", label_name="walk")
    with pytest.raises(InputError, match="label_name"):
        read_bvh(path)
    with pytest.raises(InputError, match="rest_joints"):
        write_bvh(m, tmp_path / "x.bvh", np.zeros((22, 3)))
