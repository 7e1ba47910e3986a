"""Quality measures of motions on a body, and the filter that drops interpenetrating ones.

Per motion, on a given body:

- **limb-torso interpenetration**: share of checked frames in which some limb vertex (forearm,
  hand, lower upper arm, shin, foot) lies inside the torso. A limb vertex ``p`` with normal ``n``
  counts when ``p + eps * n`` (``eps`` = 4 mm, so skin in mere contact does not count) is inside
  the closed posed body (winding number, warp) *and* on the inner side of the nearest torso face
  within 10 cm (so a fold of the skin behind a bent knee, inside the limb itself, does not count).
  Paper 001 discards such sequences; :func:`filter_motions` does the same and says how many.
- **arm-leg clearance**: the smallest distance (m) from a forearm or hand vertex to a thigh or shin
  vertex over the checked frames. Where a forearm rests on a thigh the skinned body's parts meet or
  overlap, and cloth caught between them has no room: a simulator tears it (the squat of motion
  generator version 1 did, with its arms hanging onto the thighs). :func:`filter_motions` drops
  motions below ``min_arm_leg_clearance``.
- **foot skate**: mean horizontal speed (m/s) of the toe and ankle joints over frames in which
  that joint is in contact (within 1.5 cm of its rest height above the ground and moving
  vertically slower than 0.15 m/s).
- **ground penetration**: deepest foot vertex below the ground (m, >= 0).
- **joint-limit violations**: share of frames with some joint outside :data:`JOINT_LIMITS_DEG`
  (by more than 1 degree), and the worst excess.
- **jerk**: mean and 99th-percentile norm of the third time derivative of joint positions (m/s^3).
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass

import numpy as np
import warp as wp

from datagen.body.skeleton import SMPL_JOINT_NAMES
from datagen.geometry.queries import signed_distance
from datagen.geometry.rotations import axis_angle_to_matrix_np
from datagen.motion.motion import Motion
from datagen.motion.procedural import euler_angles

__all__ = ["JOINT_LIMITS_DEG", "BodyProbe", "MotionQuality", "filter_motions", "measure_motion"]

log = logging.getLogger(__name__)


def _mirror(lim):
    """Right-side limits from left-side ones: Y and Z ranges flip sign."""
    (x0, x1), (y0, y1), (z0, z1) = lim
    return ((x0, x1), (-y1, -y0), (-z1, -z0))


_LEFT = {
    "hip": ((-125, 40), (-50, 50), (-35, 65)),
    "knee": ((-5, 155), (-15, 15), (-15, 15)),
    "ankle": ((-45, 60), (-40, 40), (-35, 35)),
    "foot": ((-45, 45), (-45, 45), (-45, 45)),
    "collar": ((-30, 30), (-30, 30), (-30, 30)),
    "shoulder": ((-175, 95), (-110, 110), (-110, 100)),
    "elbow": ((-95, 95), (-155, 5), (-20, 20)),
    "wrist": ((-85, 85), (-85, 85), (-85, 85)),
    "hand": ((-45, 45), (-45, 45), (-45, 45)),
}
JOINT_LIMITS_DEG: dict[str, tuple[tuple[float, float], ...]] = {
    "spine1": ((-30, 50), (-35, 35), (-30, 30)),
    "spine2": ((-30, 50), (-35, 35), (-30, 30)),
    "spine3": ((-30, 50), (-35, 35), (-30, 30)),
    "neck": ((-45, 50), (-50, 50), (-35, 35)),
    "head": ((-45, 50), (-50, 50), (-35, 35)),
    **{f"left_{k}": v for k, v in _LEFT.items()},
    **{f"right_{k}": _mirror(v) for k, v in _LEFT.items()},
}
"""Allowed local rotation per joint: (min, max) degrees about X, Y, Z in the joint's Euler order
(:func:`datagen.motion.procedural.euler_order`), from the T-pose. Ranges are the usual
anatomical ones (e.g. hip flexion 125, knee flexion 155, elbow flexion 155 degrees), a little
wide where SMPL's joints stand for several anatomical ones (spine, shoulder). The pelvis (the
global orientation) is free."""

_TORSO = {"pelvis", "spine1", "spine2", "spine3", "neck", "head", "left_collar", "right_collar"}
_LIMB = {f"{s}_{j}" for s in ("left", "right") for j in ("elbow", "wrist", "hand", "knee", "ankle", "foot")}
_FEET = {f"{s}_{j}" for s in ("left", "right") for j in ("ankle", "foot")}
_FOREARM = {f"{s}_{j}" for s in ("left", "right") for j in ("elbow", "wrist", "hand")}
_LEG = {f"{s}_{j}" for s in ("left", "right") for j in ("hip", "knee")}


@dataclass(frozen=True)
class MotionQuality:
    """The measures of one motion on one body (see the module docstring for definitions)."""

    label_name: str
    frames_checked: int
    penetration_share: float
    penetration_frames: int
    arm_leg_clearance: float
    foot_skate: float
    contact_share: float
    ground_penetration: float
    limit_violation_share: float
    limit_worst_excess_deg: float
    limit_worst_joint: str
    jerk_mean: float
    jerk_p99: float

    def as_dict(self) -> dict:
        return asdict(self)



@wp.kernel
def _inside_torso(body: wp.uint64, torso: wp.uint64, points: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.int32)):
    """1 for a point inside the body (winding number) and inside the torso (the torso's own normals)."""
    tid = wp.tid()
    p = points[tid]
    if signed_distance(body, p, 1.0) < 0.0:
        t = wp.mesh_query_point_sign_normal(torso, p, 0.1)
        if t.result and t.sign < 0.0:
            out[tid] = 1


class BodyProbe:
    """A body prepared for quality checks: limb/torso vertex sets and a warp mesh for queries."""

    def __init__(self, model, betas=None, eps: float = 0.004, device: str | None = None):
        self.model = model
        self.betas = np.zeros(model.shape_dim) if betas is None else np.asarray(betas, dtype=np.float64)
        self.eps = float(eps)
        self.faces = np.asarray(model.faces, dtype=np.int32)
        dominant = np.asarray(model.weights).argmax(1)
        names = np.array(SMPL_JOINT_NAMES)[dominant]
        rest_v = np.asarray(model.shaped(self.betas))[0]
        rest_j = np.asarray(model.rest_joints(self.betas))[0]
        limb = np.isin(names, list(_LIMB))
        # the upper arm away from the armpit (LBS folds the armpit into the torso by construction)
        for s in ("left", "right"):
            sh = SMPL_JOINT_NAMES.index(f"{s}_shoulder")
            far = np.linalg.norm(rest_v - rest_j[sh], axis=1) > 0.12
            limb |= (names == f"{s}_shoulder") & far
        self.limb_vertices = np.flatnonzero(limb)
        torso_v = np.isin(names, list(_TORSO))
        self.torso_faces = np.flatnonzero(torso_v[self.faces].all(1))
        self.foot_vertices = np.flatnonzero(np.isin(names, list(_FEET)))
        self.forearm_vertices = np.flatnonzero(np.isin(names, list(_FOREARM)))
        self.leg_vertices = np.flatnonzero(np.isin(names, list(_LEG)))
        self.ground_y = float(rest_v[:, 1].min())
        self.rest_joints = rest_j
        self.device = device or wp.get_preferred_device()
        self._mesh = None
        self._torso = None

    def _meshes(self, verts: np.ndarray):
        pts = wp.array(verts.astype(np.float32), dtype=wp.vec3, device=self.device)
        tpts = wp.array(verts.astype(np.float32), dtype=wp.vec3, device=self.device)
        if self._mesh is None:
            self._mesh = wp.Mesh(points=pts, indices=wp.array(self.faces.ravel(), dtype=wp.int32, device=self.device),
                                 support_winding_number=True)
            self._torso = wp.Mesh(points=tpts, indices=wp.array(self.faces[self.torso_faces].ravel(),
                                                                dtype=wp.int32, device=self.device))
        else:
            self._mesh.points.assign(pts)
            self._mesh.refit()
            self._torso.points.assign(tpts)
            self._torso.refit()
        return self._mesh, self._torso

    def penetrating(self, verts: np.ndarray) -> int:
        """Number of limb vertices inside the torso for one posed frame ``verts`` [V, 3]."""
        normals = _vertex_normals(verts, self.faces)
        q = verts[self.limb_vertices] + self.eps * normals[self.limb_vertices]
        mesh, torso = self._meshes(verts)
        out = wp.zeros(len(q), dtype=wp.int32, device=self.device)
        wp.launch(_inside_torso, dim=len(q), inputs=[mesh.id, torso.id, wp.array(q.astype(np.float32), dtype=wp.vec3,
                                                                                 device=self.device), out],
                  device=self.device)
        return int(out.numpy().sum())

    def arm_leg_clearance(self, verts: np.ndarray) -> float:
        """Smallest distance (m) from a forearm or hand vertex to a thigh or shin vertex of ``verts``."""
        from scipy.spatial import cKDTree

        return float(cKDTree(verts[self.leg_vertices]).query(verts[self.forearm_vertices])[0].min())


def _vertex_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def measure_motion(motion: Motion, probe: BodyProbe, *, stride: int = 3, chunk: int = 64) -> MotionQuality:
    """Measure ``motion`` on ``probe``'s body; interpenetration is checked every ``stride`` frames."""
    model, betas = probe.model, probe.betas
    T = motion.frame_count
    fps = motion.fps
    # joints for every frame (skate, jerk); vertices on the checked frames
    joints = np.empty((T, 24, 3))
    pen_frames, sink, checked, clearance = 0, 0.0, 0, np.inf
    check = set(range(0, T, max(1, int(stride))))
    for s in range(0, T, chunk):
        e = min(T, s + chunk)
        verts, jts = model.pose(np.repeat(betas[None], e - s, 0), motion.poses[s:e].reshape(e - s, -1), motion.trans[s:e])
        joints[s:e] = jts
        for i in range(e - s):
            if s + i in check:
                checked += 1
                if probe.penetrating(verts[i]) > 0:
                    pen_frames += 1
                clearance = min(clearance, probe.arm_leg_clearance(verts[i]))
        sink = max(sink, float(probe.ground_y - verts[:, probe.foot_vertices, 1].min()))
    # foot skate
    speeds, contacts = [], 0
    for name in ("left_ankle", "right_ankle", "left_foot", "right_foot"):
        j = SMPL_JOINT_NAMES.index(name)
        rest_h = probe.rest_joints[j, 1] - probe.ground_y
        h = joints[:, j, 1] - probe.ground_y
        vel = np.diff(joints[:, j], axis=0) * fps  # [T-1, 3]
        c = (h[1:] < rest_h + 0.015) & (h[:-1] < rest_h + 0.015) & (np.abs(vel[:, 1]) < 0.15)
        contacts += int(c.sum())
        speeds.append(np.linalg.norm(vel[c][:, [0, 2]], axis=1))
    speeds = np.concatenate(speeds)
    # joint limits
    mats = axis_angle_to_matrix_np(motion.poses)
    worst, worst_joint = 0.0, ""
    bad = np.zeros(T, dtype=bool)
    for name, lim in JOINT_LIMITS_DEG.items():
        j = SMPL_JOINT_NAMES.index(name)
        ang = np.degrees(euler_angles(name, mats[:, j]))
        lo = np.array([a for a, _ in lim])
        hi = np.array([b for _, b in lim])
        excess = np.maximum(lo - ang, ang - hi).max(1)
        bad |= excess > 1.0
        if excess.max() > worst:
            worst, worst_joint = float(excess.max()), name
    # jerk
    if T >= 4:
        jerk = np.linalg.norm(np.diff(joints, n=3, axis=0), axis=-1) * fps**3
        jerk_mean, jerk_p99 = float(jerk.mean()), float(np.percentile(jerk, 99))
    else:
        jerk_mean = jerk_p99 = 0.0
    return MotionQuality(
        label_name=motion.label_name, frames_checked=checked,
        penetration_share=pen_frames / max(checked, 1), penetration_frames=pen_frames,
        arm_leg_clearance=float(clearance),
        foot_skate=float(speeds.mean()) if len(speeds) else 0.0, contact_share=contacts / (4 * max(T - 1, 1)),
        ground_penetration=max(sink, 0.0), limit_violation_share=float(bad.mean()),
        limit_worst_excess_deg=max(worst, 0.0), limit_worst_joint=worst_joint,
        jerk_mean=jerk_mean, jerk_p99=jerk_p99,
    )


def filter_motions(motions: list[Motion], probe: BodyProbe, *, max_penetration_share: float = 0.0,
                   min_arm_leg_clearance: float = 0.01,
                   stride: int = 3) -> tuple[list[Motion], list[MotionQuality]]:
    """Drop motions whose limb-torso interpenetration share exceeds ``max_penetration_share`` or
    whose forearms come nearer the legs than ``min_arm_leg_clearance`` (m; 1 cm leaves room for
    two layers of cloth and their contact margins).

    Returns the kept motions and every motion's :class:`MotionQuality` (in input order). Logs how
    many were dropped, per reason and label.
    """
    kept, report = [], []
    dropped: dict[str, dict[str, int]] = {"limb-torso interpenetration": {}, "forearms on the legs": {}}
    for m in motions:
        q = measure_motion(m, probe, stride=stride)
        report.append(q)
        reason = ("limb-torso interpenetration" if q.penetration_share > max_penetration_share else
                  "forearms on the legs" if q.arm_leg_clearance < min_arm_leg_clearance else None)
        if reason:
            dropped[reason][m.label_name] = dropped[reason].get(m.label_name, 0) + 1
        else:
            kept.append(m)
    total = sum(sum(d.values()) for d in dropped.values())
    if total:
        log.info("dropped %d of %d motions: %s", total, len(motions), "; ".join(
            f"{reason}: " + ", ".join(f"{k} {v}" for k, v in sorted(d.items())) for reason, d in dropped.items() if d))
    else:
        log.info("kept all %d motions (no limb-torso interpenetration, forearms clear of the legs)", len(motions))
    return kept, report
