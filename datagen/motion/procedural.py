"""Building blocks of the procedural motion library: a rig, curves, footsteps and leg IK.

A procedural motion is assembled from a :class:`PoseTrack`: the pelvis's world position and
orientation per frame, local rotations of the upper body and arms written as Euler curves, and,
for each leg, either world targets for the ankle and the foot's orientation (solved by analytic
two-bone IK, so a planted foot does not slide and does not sink) or free local rotations (a kick).

Frames and axes are SMPL's: Y up, the body facing +Z, its left on +X, metres and radians. At rest
(all rotations zero) the body stands in drape's T-pose; every joint's local frame is then aligned
with the world axes, so "rotate the left shoulder about Z" means the same thing on any body.
Sign conventions used by the generators (checked by tests):

- hip and shoulder **X**: negative swings the limb forward (+Z); knee **X** positive flexes;
- left shoulder **Z** negative lowers the arm from the T-pose (right: positive);
- left elbow **Y** negative bends the forearm forward (right: positive);
- spine **X** positive bends forward, **Y** turns left, **Z** positive bends to the right.

The ground is the plane through the rest body's lowest vertex; a foot planted at its rest height
stands on it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from datagen.body.skeleton import JOINT_COUNT, SMPL_JOINT_NAMES, SMPL_PARENTS
from datagen.geometry.rotations import matrix_to_axis_angle_np

__all__ = [
    "Footsteps",
    "J",
    "PoseTrack",
    "Rig",
    "assemble",
    "euler",
    "heel_roll_offset",
    "plan_footsteps",
    "pulse",
    "rot_x",
    "rot_y",
    "rot_z",
    "smoothstep",
    "soft_clip",
    "solve_leg_ik",
]

J = {name: i for i, name in enumerate(SMPL_JOINT_NAMES)}
"""Joint index by SMPL name."""

_EULER_ORDER: dict[str, str] = {name: "yzx" for name in SMPL_JOINT_NAMES}
"""Extrinsic Euler order per joint (scipy's lower case: fixed axes, applied left to right).

Pelvis, spine, neck, head and legs use ``yzx``: twist about Y first, then sideways (Z), then
flexion about X last, so large flexions keep their meaning. Collars and shoulders use ``zyx``:
raise or lower the T-pose arm (Z) first, then swing it forward or back about X. Elbows, wrists and
hands use ``xzy``: twist about the forearm (X) first, flexion about Y last."""
for _side in ("left", "right"):
    for _j in ("collar", "shoulder"):
        _EULER_ORDER[f"{_side}_{_j}"] = "zyx"
    for _j in ("elbow", "wrist", "hand"):
        _EULER_ORDER[f"{_side}_{_j}"] = "xzy"


def euler_order(joint: str) -> str:
    """The extrinsic Euler order (scipy ``from_euler`` lower case) used for ``joint``'s limits."""
    return _EULER_ORDER[joint]


def euler(joint: str, x=0.0, y=0.0, z=0.0) -> np.ndarray:
    """Local rotation matrices [T, 3, 3] of ``joint`` from Euler angles about X, Y, Z (radians).

    The angles (scalars or [T] arrays) are applied in the joint's order (:func:`euler_order`).
    """
    order = _EULER_ORDER[joint]
    x, y, z = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64)) for a in (x, y, z)))
    by_axis = {"x": x, "y": y, "z": z}
    angles = np.stack([by_axis[a] for a in order], axis=-1)
    return Rotation.from_euler(order, angles).as_matrix()


def euler_angles(joint: str, matrices: np.ndarray) -> np.ndarray:
    """Euler angles [T, 3] about X, Y, Z (radians) of local rotations [T, 3, 3] of ``joint``."""
    order = _EULER_ORDER[joint]
    ang = Rotation.from_matrix(matrices.reshape(-1, 3, 3)).as_euler(order)
    out = np.empty_like(ang)
    for k, a in enumerate(order):
        out[:, "xyz".index(a)] = ang[:, k]
    return out


def rot_x(a) -> np.ndarray:
    """Rotations [T, 3, 3] about X by angles ``a`` [T] (radians)."""
    return Rotation.from_rotvec(np.outer(np.atleast_1d(a), [1.0, 0.0, 0.0])).as_matrix()


def rot_y(a) -> np.ndarray:
    """Rotations [T, 3, 3] about Y by angles ``a`` [T] (radians)."""
    return Rotation.from_rotvec(np.outer(np.atleast_1d(a), [0.0, 1.0, 0.0])).as_matrix()


def rot_z(a) -> np.ndarray:
    """Rotations [T, 3, 3] about Z by angles ``a`` [T] (radians)."""
    return Rotation.from_rotvec(np.outer(np.atleast_1d(a), [0.0, 0.0, 1.0])).as_matrix()


def smoothstep(u) -> np.ndarray:
    """``3u^2 - 2u^3`` for ``u`` clipped to [0, 1]: 0 -> 1 with zero slope at both ends."""
    u = np.clip(np.asarray(u, dtype=np.float64), 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def pulse(phase, width: float) -> np.ndarray:
    """A smooth periodic bump: 1 at integer ``phase``, falling to 0 at ``+-width/2`` cycles (C1)."""
    d = np.abs(((np.asarray(phase, dtype=np.float64) + 0.5) % 1.0) - 0.5)  # distance to nearest int
    u = np.clip(d / (0.5 * width), 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * u))


def soft_clip(x, low: float, high: float) -> np.ndarray:
    """``x`` squashed smoothly into (low, high) where it nears the ends (identity in the middle)."""
    x = np.asarray(x, dtype=np.float64)
    mid, half = 0.5 * (low + high), 0.5 * (high - low)
    u = (x - mid) / half
    knee = 0.8
    over = np.abs(u) > knee
    squashed = np.sign(u) * (knee + (1 - knee) * np.tanh((np.abs(u) - knee) / (1 - knee)))
    return mid + half * np.where(over, squashed, u)


@dataclass(frozen=True)
class Rig:
    """The skeleton a motion is generated for: rest joints [24, 3] (m) and the ground height (m)."""

    rest_joints: np.ndarray
    ground_y: float
    parents: tuple[int, ...] = SMPL_PARENTS

    @classmethod
    def from_body(cls, model, betas=None) -> Rig:
        """The rig of ``model`` (a :class:`~datagen.body.model.BodyModel`) with shape ``betas``."""
        betas = np.zeros(model.shape_dim) if betas is None else np.asarray(betas, dtype=np.float64)
        joints = np.asarray(model.rest_joints(betas), dtype=np.float64).reshape(JOINT_COUNT, 3)
        verts = np.asarray(model.shaped(betas), dtype=np.float64).reshape(-1, 3)
        return cls(rest_joints=joints, ground_y=float(verts[:, 1].min()))

    def offset(self, joint: int) -> np.ndarray:
        """Rest offset [3] of ``joint`` from its parent (m)."""
        return self.rest_joints[joint] - self.rest_joints[self.parents[joint]]

    @property
    def ankle_height(self) -> float:
        """Height of the rest ankles above the ground (m)."""
        return float(self.rest_joints[J["left_ankle"], 1] - self.ground_y)


@dataclass
class PoseTrack:
    """What a generator writes: pelvis world motion, local rotations and leg targets, over T frames.

    Attributes:
        pelvis_pos: pelvis joint world position [T, 3] (m).
        pelvis_rot: pelvis world orientation [T, 3, 3].
        local: local rotations [T, 24, 3, 3]; identity where not set. Leg joints are overwritten by
            IK for legs that have targets.
        ankle_target: per leg ("left"/"right"), ankle world position [T, 3] (m), or absent for a
            leg driven by its local rotations.
        foot_rot: per leg, the foot's world orientation [T, 3, 3] (used with ``ankle_target``).
    """

    frame_count: int
    pelvis_pos: np.ndarray = None
    pelvis_rot: np.ndarray = None
    local: np.ndarray = None
    ankle_target: dict = field(default_factory=dict)
    foot_rot: dict = field(default_factory=dict)

    def __post_init__(self):
        T = self.frame_count
        if self.pelvis_pos is None:
            self.pelvis_pos = np.zeros((T, 3))
        if self.pelvis_rot is None:
            self.pelvis_rot = np.repeat(np.eye(3)[None], T, axis=0)
        if self.local is None:
            self.local = np.repeat(np.repeat(np.eye(3)[None, None], JOINT_COUNT, axis=1), T, axis=0)

    def set(self, joint: str, matrices: np.ndarray) -> None:
        """Set ``joint``'s local rotation to ``matrices`` [T, 3, 3] (or [1, 3, 3], broadcast)."""
        self.local[:, J[joint]] = matrices

    def rotate(self, joint: str, matrices: np.ndarray) -> None:
        """Compose ``matrices`` [T, 3, 3] after ``joint``'s current local rotation (parent side)."""
        self.local[:, J[joint]] = matrices @ self.local[:, J[joint]]


def forward_kinematics(rig: Rig, pelvis_pos: np.ndarray, local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World joint positions [T, 24, 3] and orientations [T, 24, 3, 3] from local rotations.

    ``local[:, 0]`` is the pelvis's world orientation; ``pelvis_pos`` [T, 3] its world position.
    """
    T = local.shape[0]
    glob = np.empty_like(local)
    pos = np.empty((T, JOINT_COUNT, 3))
    glob[:, 0] = local[:, 0]
    pos[:, 0] = pelvis_pos
    for j in range(1, JOINT_COUNT):
        p = rig.parents[j]
        glob[:, j] = glob[:, p] @ local[:, j]
        pos[:, j] = pos[:, p] + glob[:, p] @ rig.offset(j)
    return pos, glob


@dataclass(frozen=True)
class Footsteps:
    """Per-foot ankle targets [T, 3] (m), foot yaw [T] (rad), and a contact flag [T] (planted)."""

    ankle: np.ndarray
    yaw: np.ndarray
    contact: np.ndarray
    pitch: np.ndarray


def plan_footsteps(rig: Rig, times: np.ndarray, path_xz: np.ndarray, heading: np.ndarray, *,
                   cycle_hz: float, duty: float, phase: float, lateral: float, lift: float,
                   toe_out: float = 0.0, side: str = "left", start_offset: np.ndarray | None = None,
                   heel_pitch: float = 0.0, heel_off: float = 0.0) -> Footsteps:
    """Footsteps that follow a ground path: planted during stance, a smooth arc during swing.

    The foot is on the ground for a ``duty`` share of each cycle of ``cycle_hz`` (cycles per
    second; one cycle is one step of this foot). During stance ``k`` it stays exactly where it
    landed: the path point at the stance's middle time, offset sideways by ``lateral`` (m, outward
    from the path in the heading frame) and turned by the heading there plus ``toe_out``. Between
    stances it travels on a smoothstep blend of the two footholds, lifted by ``lift * sin(pi s)``.

    Args:
        times: frame times [T] (s).
        path_xz: ground path [T, 2] (m), x and z of the point between the feet.
        heading: facing angle about Y [T] (rad); 0 faces +Z.
        phase: this foot's phase offset in cycles (0..1); its first stance is centred at
            ``-phase / cycle_hz`` seconds.
        start_offset: optional [2] extra x/z offset of every foothold (staggered stances).
        heel_pitch: foot pitch (rad) at mid-swing (toe down when positive).
        heel_off: foot pitch (rad) at toe-off: the heel rises about the ball of the foot over
            the second half of stance (the ball stays put), which lengthens the leg's reach.
    """
    sign = 1.0 if side == "left" else -1.0
    period = 1.0 / cycle_hz
    T = len(times)
    t0 = -phase * period
    k_first = int(np.floor((times[0] - t0) / period)) - 1
    k_last = int(np.ceil((times[-1] - t0) / period)) + 1
    ks = np.arange(k_first, k_last + 1)
    mids = t0 + ks * period  # stance mid times
    ext_t = np.concatenate([[times[0] - 10 * period], times, [times[-1] + 10 * period]])

    def interp(col, t):
        vals = np.concatenate([[col[0]], col, [col[-1]]])
        return np.interp(t, ext_t, vals)

    hx, hz = interp(path_xz[:, 0], mids), interp(path_xz[:, 1], mids)
    hh = interp(np.unwrap(heading), mids)
    off = np.zeros(2) if start_offset is None else np.asarray(start_offset, dtype=np.float64)
    # outward axis of the heading frame: the body's left (+X at heading 0) for the left foot
    ox, oz = np.cos(hh), -np.sin(hh)
    fx, fz = np.sin(hh), np.cos(hh)
    hold_x = hx + sign * lateral * ox + off[0] * ox * sign + off[1] * fx
    hold_z = hz + sign * lateral * oz + off[0] * oz * sign + off[1] * fz
    hold_yaw = hh + sign * toe_out

    # position of each frame within the step cycles
    u = (times - t0) / period  # in cycles; stance k is centred on u == k
    k = np.floor(u + 0.5).astype(int)  # nearest stance
    d = u - k  # -0.5..0.5 relative to stance middle
    half = 0.5 * duty
    in_stance = np.abs(d) <= half
    # swing from stance a (=k if d > 0 else k-1) to a+1; s in 0..1 over the swing
    a = np.where(d > 0, k, k - 1)
    start_u = a + half
    s = np.clip((u - start_u) / (1.0 - duty), 0.0, 1.0)
    ia, ib = a - k_first, a + 1 - k_first
    ks_idx = np.where(in_stance, k - k_first, ia)
    w = np.where(in_stance, 0.0, smoothstep(s))
    x = np.where(in_stance, hold_x[ks_idx], (1 - w) * hold_x[ia] + w * hold_x[ib])
    z = np.where(in_stance, hold_z[ks_idx], (1 - w) * hold_z[ia] + w * hold_z[ib])
    yaw = np.where(in_stance, hold_yaw[ks_idx], (1 - w) * hold_yaw[ia] + w * hold_yaw[ib])
    y_lift = np.where(in_stance, 0.0, lift * np.sin(np.pi * s))
    # heel-off: over the second half of stance the heel rises about the ball of the foot, and
    # the foot rolls back to flat over the first half of the swing
    heel_up = np.where(in_stance, smoothstep((d - 0.1 * half) / (0.9 * half)), 1.0 - smoothstep(s / 0.5))
    pitch = heel_off * heel_up + np.where(in_stance, 0.0, heel_pitch * np.sin(np.pi * s))
    rise, ahead = heel_roll_offset(rig, heel_off * heel_up)
    rest_y = rig.ground_y + rig.ankle_height
    ankle = np.stack([x + ahead * np.sin(yaw), np.full(T, rest_y) + y_lift + rise, z + ahead * np.cos(yaw)], axis=-1)
    return Footsteps(ankle=ankle, yaw=yaw, contact=in_stance, pitch=pitch)


def heel_roll_offset(rig: Rig, pitch) -> tuple[np.ndarray, np.ndarray]:
    """How far the ankle rises and moves ahead (m) when the foot pitches toe-down by ``pitch``
    (rad) about the ball of the foot, which stays put: ``o - R_x(pitch) o`` for the rest offset
    ``o`` from the ankle to the ball (the foot joint)."""
    o = rig.rest_joints[J["left_foot"]] - rig.rest_joints[J["left_ankle"]]
    oy, oz = float(o[1]), float(o[2])
    pitch = np.asarray(pitch, dtype=np.float64)
    c, s = np.cos(pitch), np.sin(pitch)
    return oy * (1.0 - c) + oz * s, oz * (1.0 - c) - oy * s


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotations [T, 3, 3] taking directions ``a`` [T, 3] to ``b`` [T, 3]."""
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    axis = np.cross(a, b)
    s = np.linalg.norm(axis, axis=-1)
    c = np.sum(a * b, axis=-1)
    angle = np.arctan2(s, c)
    axis = axis / np.maximum(s, 1e-12)[:, None]
    return Rotation.from_rotvec(axis * angle[:, None]).as_matrix()


def solve_leg_ik(rig: Rig, side: str, hip_pos: np.ndarray, pelvis_rot: np.ndarray, ankle_target: np.ndarray,
                 knee_forward: np.ndarray, foot_rot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Analytic two-bone IK: local hip, knee and ankle rotations [T, 3, 3] reaching ``ankle_target``.

    The knee is a hinge about its local X (flexion >= 0). Its flexion sets the hip-ankle distance;
    the hip rotation points the leg at the target and turns it about the hip-ankle axis so that the
    thigh's forward axis lies in the plane of that axis and ``knee_forward`` [T, 3]. A target out
    of reach is approached smoothly (the leg stops just short of straight), so the knee never
    snaps. The ankle's local rotation makes the foot's world orientation ``foot_rot``.
    """
    hip, knee, ankle = J[f"{side}_hip"], J[f"{side}_knee"], J[f"{side}_ankle"]
    thigh = rig.rest_joints[knee] - rig.rest_joints[hip]
    shin = rig.rest_joints[ankle] - rig.rest_joints[knee]
    l1, l2 = np.linalg.norm(thigh), np.linalg.norm(shin)
    c0 = thigh[0] * shin[0]
    A = thigh[1] * shin[1] + thigh[2] * shin[2]
    B = thigh[2] * shin[1] - thigh[1] * shin[2]
    R, delta = np.hypot(A, B), np.arctan2(B, A)
    d_max = np.linalg.norm(thigh + shin)  # reach at zero flexion (the rest leg)
    v = ankle_target - hip_pos
    d = np.linalg.norm(v, axis=-1)
    soft = 0.015  # m: the smooth approach to full reach (keeps the knee off its singularity)
    dm = d_max - 1e-3
    d_eff = dm - soft * np.logaddexp(0.0, (dm - d) / soft)
    d_eff = np.maximum(d_eff, abs(l1 - l2) + 0.05)
    cos_arg = np.clip(((d_eff**2 - l1**2 - l2**2) / 2.0 - c0) / R, -1.0, 1.0)
    phi = np.maximum(delta + np.arccos(cos_arg), 0.0)  # knee flexion
    R_knee = rot_x(phi)
    reach = thigh[None] + np.einsum("tij,j->ti", R_knee, shin)  # ankle in the hip frame
    R1 = _rotation_between(reach, v)
    u = v / np.linalg.norm(v, axis=-1, keepdims=True)
    fwd1 = R1[:, :, 2]  # the thigh's forward axis after R1
    # a leg raised toward knee_forward (a kick) has its knee pointing up, not along the leg
    ahead = np.clip(np.sum(knee_forward * u, -1, keepdims=True), 0.0, None)
    ref = knee_forward + 2.0 * ahead * np.array([0.0, 1.0, 0.0])
    f_ref = ref - np.sum(ref * u, -1, keepdims=True) * u
    f_cur = fwd1 - np.sum(fwd1 * u, -1, keepdims=True) * u
    swivel = np.arctan2(np.sum(np.cross(f_cur, f_ref) * u, -1), np.sum(f_cur * f_ref, -1))
    R_hip_world = Rotation.from_rotvec(u * swivel[:, None]).as_matrix() @ R1
    R_hip_local = np.swapaxes(pelvis_rot, -1, -2) @ R_hip_world
    R_shin_world = R_hip_world @ R_knee
    R_ankle_local = np.swapaxes(R_shin_world, -1, -2) @ foot_rot
    return R_hip_local, R_knee, R_ankle_local


def assemble(rig: Rig, track: PoseTrack) -> tuple[np.ndarray, np.ndarray]:
    """Solve the legs with targets and return SMPL poses [T, 24, 3] (axis-angle) and trans [T, 3].

    ``trans`` is the pelvis displacement from its rest position, as SMPL's LBS adds it.
    """
    local = track.local.copy()
    local[:, 0] = track.pelvis_rot
    for side, target in track.ankle_target.items():
        hip_pos = track.pelvis_pos + track.pelvis_rot @ rig.offset(J[f"{side}_hip"])
        # knees point along the foot's forward direction (a walker's knees follow the feet)
        knee_fwd = track.foot_rot[side][:, :, 2].copy()
        knee_fwd[:, 1] = 0.0
        knee_fwd /= np.linalg.norm(knee_fwd, axis=-1, keepdims=True)
        h, k, a = solve_leg_ik(rig, side, hip_pos, track.pelvis_rot, target, knee_fwd, track.foot_rot[side])
        local[:, J[f"{side}_hip"]] = h
        local[:, J[f"{side}_knee"]] = k
        # keep the ankle inside its range (flexion -45..60 degrees): a runner's foot at toe-off
        # would otherwise over-point; squashed smoothly, identity over most of the range
        ang = euler_angles(f"{side}_ankle", a)
        ang[:, 0] = soft_clip(ang[:, 0], np.radians(-45.0), np.radians(60.0))
        local[:, J[f"{side}_ankle"]] = euler(f"{side}_ankle", ang[:, 0], ang[:, 1], ang[:, 2])
        # with the heel up (toe-down pitch) the toes bend back to lie flat on the ground
        fwd = track.foot_rot[side][:, :, 2]
        flat = rot_y(np.arctan2(fwd[:, 0], fwd[:, 2]))
        toe_local = np.swapaxes(track.foot_rot[side], -1, -2) @ flat
        heel_up = fwd[:, 1] < 0.0
        local[heel_up, J[f"{side}_foot"]] = toe_local[heel_up]
    poses = matrix_to_axis_angle_np(local)
    trans = track.pelvis_pos - rig.rest_joints[0]
    return poses, trans


def foot_orientation(yaw: np.ndarray, pitch: np.ndarray | None = None) -> np.ndarray:
    """Foot world orientations [T, 3, 3]: turned by ``yaw`` about Y, pitched toe-down by ``pitch``."""
    R = rot_y(yaw)
    if pitch is not None:
        R = R @ rot_x(pitch)
    return R
