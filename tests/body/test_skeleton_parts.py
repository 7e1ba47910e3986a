"""The body's collision parts (datagen.body.skeleton.face_parts) on the default body."""

from __future__ import annotations

import numpy as np
import pytest

from datagen.body.skeleton import BODY_PARTS, SMPL_JOINT_NAMES, face_parts


def test_every_joint_is_in_one_part():
    joints = [j for _, js in BODY_PARTS for j in js]
    assert sorted(joints) == sorted(SMPL_JOINT_NAMES)


def test_face_parts_split_the_default_body_into_torso_arms_and_legs(default_body):
    """Every part has faces; each arm's and leg's faces lie on its own side of the body (x of the
    face centres has the sign of the part's first joint), the arms above the legs."""
    m = default_body
    part = face_parts(m.weights, m.faces)
    assert part.shape == (len(m.faces),)
    counts = np.bincount(part, minlength=len(BODY_PARTS))
    print("\nfaces per part: " + ", ".join(f"{n} {c}" for (n, _), c in zip(BODY_PARTS, counts)))
    assert (counts > 0).all()
    centres = m.v_template[m.faces].mean(1)
    joints = np.asarray(m.J_regressor @ m.v_template)
    names = [n for n, _ in BODY_PARTS]
    for name, js in BODY_PARTS[1:]:
        side = np.sign(joints[SMPL_JOINT_NAMES.index(js[0]), 0])
        assert (np.sign(centres[part == names.index(name), 0]) == side).mean() > 0.99, name
    arm_y = centres[part == names.index("left_arm"), 1].mean()
    leg_y = centres[part == names.index("left_leg"), 1].mean()
    assert arm_y > leg_y


def test_face_parts_refuses_other_skeletons():
    with pytest.raises(ValueError, match="24"):
        face_parts(np.ones((3, 22)) / 22, np.array([[0, 1, 2]]))
