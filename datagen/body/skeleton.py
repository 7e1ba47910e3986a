"""SMPL's 24-joint skeleton: names, order and parents (Loper et al. 2015)."""

from __future__ import annotations

import numpy as np

SMPL_JOINT_NAMES: tuple[str, ...] = (
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
    "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand", "right_hand",
)
"""Joint names in SMPL order."""

SMPL_PARENTS: tuple[int, ...] = (
    -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21,
)
"""Parent index of each joint; -1 for the root (pelvis)."""

JOINT_COUNT = 24
POSE_DIM = JOINT_COUNT * 3
"""Length of θ: 24 axis-angle rotations (the root's global orientation first)."""

POSE_BASIS_DIM = (JOINT_COUNT - 1) * 9
"""Length of the pose-blend-shape feature: (R - I) flattened for the 23 non-root joints."""


def kintree_table() -> np.ndarray:
    """SMPL's ``kintree_table`` [2, 24]: parents in row 0 (root's parent as 2**32 - 1), ids in row 1."""
    parents = np.array(SMPL_PARENTS, dtype=np.int64)
    parents[0] = 4294967295
    return np.stack([parents, np.arange(JOINT_COUNT, dtype=np.int64)])


def parents_from_kintree(kintree: np.ndarray) -> np.ndarray:
    """Parent indices [J] from a ``kintree_table`` [2, J] as SMPL files store it."""
    kintree = np.asarray(kintree)
    ids = kintree[1].astype(np.int64)
    id_to_index = {int(i): n for n, i in enumerate(ids)}
    parents = np.full(len(ids), -1, dtype=np.int64)
    for n, p in enumerate(kintree[0].astype(np.int64)):
        parents[n] = id_to_index.get(int(p), -1)
    parents[0] = -1
    return parents


BODY_PARTS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("torso", ("pelvis", "spine1", "spine2", "spine3", "neck", "left_collar", "right_collar", "head")),
    ("left_arm", ("left_shoulder", "left_elbow", "left_wrist", "left_hand")),
    ("right_arm", ("right_shoulder", "right_elbow", "right_wrist", "right_hand")),
    ("left_leg", ("left_hip", "left_knee", "left_ankle", "left_foot")),
    ("right_leg", ("right_hip", "right_knee", "right_ankle", "right_foot")),
)
"""The body's collision parts and the joints whose skinning weights make each one. A posed
skinned body overlaps itself where parts meet (arm and torso at the armpit, hand and thigh):
cloth between two parts needs a contact with each, which one closest point on the whole body
cannot give (see ``datagen.sim``)."""


def face_parts(weights: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The :data:`BODY_PARTS` index of every face [F] (int32): the part with the largest sum of
    its joints' skinning weights over the face's three vertices.

    Args:
        weights: skinning weights [V, 24] in SMPL joint order.
        faces: triangles [F, 3].
    """
    w = np.asarray(weights, dtype=np.float64)
    if w.ndim != 2 or w.shape[1] != JOINT_COUNT:
        raise ValueError(f"skinning weights must be [V, {JOINT_COUNT}], got {w.shape}")
    group = np.zeros((JOINT_COUNT, len(BODY_PARTS)))
    for p, (_name, joints) in enumerate(BODY_PARTS):
        for j in joints:
            group[SMPL_JOINT_NAMES.index(j), p] = 1.0
    per_vertex = w @ group
    return np.argmax(per_vertex[np.asarray(faces)].sum(1), axis=1).astype(np.int32)
