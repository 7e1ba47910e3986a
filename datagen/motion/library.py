"""The procedural motion library: every label in :data:`~datagen.motion.labels.LABELS`, seeded.

Each label is a family. Its style parameters (tempo, amplitude, phase, asymmetry, stride, arm
swing and a few of its own) are drawn from their ranges by the seed, so one label gives many
distinct sequences, and any of them can be fixed by hand. A generator writes a
:class:`~datagen.motion.procedural.PoseTrack` (pelvis path, upper-body curves, foot targets);
legs with foot targets are solved by two-bone IK, so planted feet neither slide nor sink.

    >>> from datagen.motion.library import make_motion
    >>> walk = make_motion("walk", seed=3, frames=120)      # doctest: +SKIP

Motions are generated on the rig of the default body (β = 0) unless another is given; on other
body shapes the same poses stand on the same ground to within the leg-length difference.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from datagen.errors import InputError
from datagen.motion.labels import LABELS, label_index
from datagen.motion.motion import Motion
from datagen.motion.procedural import (
    J,
    PoseTrack,
    Rig,
    assemble,
    euler,
    foot_orientation,
    heel_roll_offset,
    plan_footsteps,
    pulse,
    rot_x,
    rot_y,
    rot_z,
    smoothstep,
)
from datagen.params import ParamSpec, draw_params

__all__ = ["GENERATOR_VERSION", "LABEL_PARAMS", "ParamSpec", "default_rig", "make_motion", "style_params"]

log = logging.getLogger(__name__)

GENERATOR_VERSION = 2
"""Bumped whenever a generator changes what a (label, seed) gives."""

DEG = np.pi / 180.0


_COMMON: dict[str, ParamSpec] = {
    "tempo": ParamSpec(0.8, 1.25, "speed multiplier of the label's base rhythm"),
    "amplitude": ParamSpec(0.75, 1.15, "scale of the main movement"),
    "phase": ParamSpec(0.0, 1.0, "where in its cycle the motion starts (cycles)"),
    "asymmetry": ParamSpec(-1.0, 1.0, "left/right imbalance; its sign picks the leading side"),
    "arm_swing": ParamSpec(0.5, 1.3, "scale of secondary arm movement"),
    "stance": ParamSpec(0.9, 1.35, "feet apart, relative to the rest stance"),
}

_EXTRA: dict[str, dict[str, ParamSpec]] = {
    "walk": {"stride": ParamSpec(0.85, 1.1, "stride length (m, two steps)"),
             "cadence": ParamSpec(0.85, 1.0, "stride frequency (Hz)"),
             "turn": ParamSpec(-0.25, 0.25, "turning rate (rad/s)")},
    "run": {"stride": ParamSpec(1.1, 1.5, "stride length (m, two steps)"),
            "cadence": ParamSpec(1.3, 1.5, "stride frequency (Hz)"),
            "turn": ParamSpec(-0.2, 0.2, "turning rate (rad/s)")},
    "jump": {"height": ParamSpec(0.08, 0.22, "flight apex above the stance (m)"),
             "forward": ParamSpec(0.0, 0.25, "travel per jump (m)")},
    "squat": {"depth": ParamSpec(0.2, 0.38, "how far the pelvis drops (m)")},
    "lunge": {"stride": ParamSpec(0.45, 0.65, "how far the front foot steps (m)"),
              "depth": ParamSpec(0.12, 0.22, "how far the pelvis drops (m)")},
    "kick": {"height": ParamSpec(50.0, 85.0, "hip flexion at the top of the kick (deg)")},
    "wave": {"raise": ParamSpec(10.0, 45.0, "upper arm above horizontal (deg)"),
             "rate": ParamSpec(1.5, 2.8, "waves per second")},
    "raise_arms": {"plane": ParamSpec(0.0, 1.0, "0 raises sideways, 1 raises forward")},
    "arm_circles": {"radius": ParamSpec(15.0, 35.0, "circle half-angle at the shoulder (deg)"),
                    "direction": ParamSpec(-1.0, 1.0, "its sign: forward or backward circles")},
    "torso_twist": {"twist": ParamSpec(30.0, 55.0, "peak twist of the torso (deg)")},
    "bend_forward": {"bend": ParamSpec(45.0, 85.0, "peak forward bend of the trunk (deg)")},
    "side_bend": {"bend": ParamSpec(18.0, 35.0, "peak sideways bend (deg)")},
    "sit_stand": {"depth": ParamSpec(0.3, 0.42, "how far the pelvis drops (m)"),
                  "hold": ParamSpec(0.1, 0.35, "share of the cycle spent seated")},
    "turn_in_place": {"angle": ParamSpec(90.0, 180.0, "turn per half cycle (deg)")},
    "box": {"punch_rate": ParamSpec(0.8, 1.3, "punches per second")},
    "dance_sway": {"bpm": ParamSpec(95.0, 130.0, "beats per minute"),
                   "step": ParamSpec(0.15, 0.28, "side step length (m)")},
    "dance_disco": {"bpm": ParamSpec(100.0, 130.0, "beats per minute")},
}

LABEL_PARAMS: dict[str, dict[str, ParamSpec]] = {name: {**_COMMON, **_EXTRA.get(name, {})} for name in LABELS}
"""Every label's style parameters with their ranges."""


def style_params(label: str, seed: int, overrides: dict | None = None) -> dict[str, float]:
    """The style parameters of ``label`` drawn by ``seed``, with ``overrides`` applied (checked)."""
    return draw_params(LABEL_PARAMS[LABELS[label_index(label)]], seed, (LABELS.index(label), 7919), repr(label),
                       overrides)


_RIG_CACHE: dict[int, Rig] = {}


def default_rig() -> Rig:
    """The rig of drape's default body at β = 0 (built or loaded from the body cache once)."""
    if 0 not in _RIG_CACHE:
        from datagen.body.cache import default_body

        _RIG_CACHE[0] = Rig.from_body(default_body())
    return _RIG_CACHE[0]


def make_motion(label: str, seed: int = 0, frames: int = 120, fps: float = 30.0, *,
                params: dict | None = None, rig: Rig | None = None) -> Motion:
    """One procedural motion of ``label``: ``frames`` frames at ``fps``, styled by ``seed``.

    Args:
        label: a name from :data:`~datagen.motion.labels.LABELS` (``drape motion list``).
        seed: draws the style parameters; the same (label, seed, frames, fps) gives the same motion.
        frames: number of frames (>= 2).
        fps: frames per second (> 0).
        params: style parameters to fix instead of drawing (each within its range).
        rig: the skeleton to generate for; default :func:`default_rig`.
    """
    idx = label_index(label)
    if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or frames < 2:
        raise InputError(f"frames must be an integer >= 2, got {frames!r}")
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be a positive number, got {fps!r}")
    p = style_params(label, seed, params)
    rig = default_rig() if rig is None else rig
    times = np.arange(frames) / float(fps)
    ctx = _Ctx(rig=rig, t=times, p=p, track=PoseTrack(frame_count=frames))
    _GENERATORS[label](ctx)
    poses, trans = assemble(rig, ctx.track)
    source = {"kind": "procedural", "generator": label, "seed": int(seed), "version": GENERATOR_VERSION,
              "params": p}
    return Motion(poses=poses, trans=trans, fps=float(fps), label=idx, label_name=label, source=source)


# ----------------------------------------------------------------------------------- helpers


@dataclass
class _Ctx:
    rig: Rig
    t: np.ndarray
    p: dict
    track: PoseTrack

    @property
    def T(self) -> int:
        return len(self.t)

    @property
    def pelvis_rest(self) -> np.ndarray:
        return self.rig.rest_joints[0]

    def cycles(self, hz: float) -> np.ndarray:
        """Phase in cycles at ``hz`` (scaled by tempo), starting at the seeded phase."""
        return self.t * hz * self.p["tempo"] + self.p["phase"]

    @property
    def lead(self) -> str:
        return "left" if self.p["asymmetry"] >= 0 else "right"

    def side_gain(self, side: str) -> float:
        """1 +- 0.25 * asymmetry: the leading side moves a little more."""
        a = self.p["asymmetry"]
        return 1.0 + 0.25 * (a if side == "left" else -a)

    def plant(self, side: str, offset_xz=(0.0, 0.0), yaw: float = 0.0, heading=None) -> None:
        """Plant a foot at its rest spot (stance-scaled), shifted by ``offset_xz`` (m), turned by ``yaw``."""
        rest = self.rig.rest_joints[J[f"{side}_ankle"]]
        x = rest[0] * self.p["stance"] + offset_xz[0]
        z = rest[2] + offset_xz[1]
        target = np.tile([x, rest[1], z], (self.T, 1))
        self.track.ankle_target[side] = target
        self.track.foot_rot[side] = foot_orientation(np.full(self.T, yaw))

    def plant_both(self, stagger: float = 0.0) -> None:
        toe = 8 * DEG
        self.plant("left", (0.0, stagger), yaw=toe)
        self.plant("right", (0.0, -stagger), yaw=-toe)

    def spine(self, flex=0.0, twist=0.0, side=0.0, weights=(0.3, 0.3, 0.4)) -> None:
        """Spread a trunk bend (X), twist (Y) and side bend (Z) (rad) over spine1..3."""
        for name, w in zip(("spine1", "spine2", "spine3"), weights):
            self.track.set(name, euler(name, x=w * np.asarray(flex), y=w * np.asarray(twist),
                                       z=w * np.asarray(side)))

    def head(self, flex=0.0, twist=0.0, side=0.0) -> None:
        self.track.set("neck", euler("neck", x=0.5 * np.asarray(flex), y=0.5 * np.asarray(twist),
                                     z=0.5 * np.asarray(side)))
        self.track.set("head", euler("head", x=0.5 * np.asarray(flex), y=0.5 * np.asarray(twist),
                                     z=0.5 * np.asarray(side)))

    def arm(self, side: str, lower, swing=0.0, elbow=0.0, twist=0.0, horizontal=0.0, humeral=0.0) -> None:
        """Set an arm: ``lower`` (rad) down from the T-pose (negative raises it), then ``swing``
        forward (rad) about X, ``horizontal`` forward in the horizontal plane (rad, about Y), elbow
        flexion ``elbow`` (rad, >= 0) bending the forearm forward/up, and forearm ``twist``.
        ``humeral`` (rad) turns the upper arm about its own axis first (external rotation: at
        90 degrees a T-pose arm's elbow flexes upward instead of forward)."""
        s = 1.0 if side == "left" else -1.0
        shoulder = euler(f"{side}_shoulder", x=-np.asarray(swing), y=-s * np.asarray(horizontal),
                         z=-s * np.asarray(lower))
        if np.any(np.asarray(humeral) != 0.0):
            shoulder = shoulder @ rot_x(np.broadcast_to(-np.asarray(humeral, dtype=np.float64), (self.T,)))
        self.track.set(f"{side}_shoulder", shoulder)
        self.track.set(f"{side}_elbow", euler(f"{side}_elbow", x=s * np.asarray(twist), y=-s * np.asarray(elbow)))

    def pelvis(self, offset=None, yaw=0.0, pitch=0.0, roll=0.0) -> None:
        """Pelvis world position = rest + ``offset`` [T, 3]; orientation yaw (Y), pitch (X, forward), roll (Z)."""
        off = np.zeros((self.T, 3)) if offset is None else np.broadcast_to(offset, (self.T, 3))
        self.track.pelvis_pos = self.pelvis_rest + off
        n = self.T
        self.track.pelvis_rot = (rot_y(np.broadcast_to(yaw, (n,))) @ rot_x(np.broadcast_to(pitch, (n,)))
                                 @ rot_z(np.broadcast_to(roll, (n,))))




def _hanging_arms(c: _Ctx, swing_l=0.0, swing_r=0.0, elbow=15 * DEG, lower=75 * DEG) -> None:
    c.arm("left", lower, swing_l, elbow)
    c.arm("right", lower, swing_r, elbow)


# ----------------------------------------------------------------------------------- locomotion


def _gait(c: _Ctx, *, stride: float, cadence: float, turn: float, duty: float, lift: float, drop: float,
          bob: float, lean: float, arm_gain: float, elbow: float, heading0: float = 0.0,
          flight_bob: bool = False, speed_scale: float = 1.0, heel_off: float = 0.0) -> None:
    p = c.p
    f = cadence * p["tempo"]  # stride (per-foot cycle) frequency, Hz
    speed = stride * f * speed_scale
    heading = heading0 + turn * c.t
    # integrate the path along the heading
    dt = np.diff(c.t, prepend=c.t[0])
    vx, vz = speed * np.sin(heading), speed * np.cos(heading)
    path = np.stack([np.cumsum(vx * dt), np.cumsum(vz * dt)], axis=-1)
    lateral = abs(c.rig.rest_joints[7, 0]) * 0.8 * p["stance"]
    toe = 7 * DEG
    phase_l = p["phase"]
    steps = {}
    for side, ph in (("left", phase_l), ("right", phase_l + 0.5)):
        fs = plan_footsteps(c.rig, c.t, path, heading, cycle_hz=f, duty=duty, phase=ph % 1.0, lateral=lateral,
                            lift=lift * c.side_gain(side), toe_out=toe, side=side, heel_pitch=10 * DEG,
                            heel_off=heel_off)
        steps[side] = fs
        c.track.ankle_target[side] = fs.ankle
        c.track.foot_rot[side] = foot_orientation(fs.yaw, fs.pitch)
    # phase of the left leg: 0 at left mid-stance; pelvis lowest after each foot strike
    u = (c.t - (-phase_l / f)) * f
    swing_l = np.sin(2 * np.pi * u)  # > 0 while the left leg swings forward
    if flight_bob:
        vertical = bob * np.abs(np.sin(2 * np.pi * u)) - drop
    else:
        vertical = bob * np.cos(4 * np.pi * u) * 0.5 - drop  # high at mid-stance, low in double support
    sway = 0.025 * p["amplitude"] * np.cos(2 * np.pi * u) * (1.0 - duty)
    ox, oz = np.cos(heading), -np.sin(heading)
    off = np.stack([path[:, 0] + sway * ox, vertical, path[:, 1] + sway * oz], axis=-1)
    pelvis_yaw = heading - 6 * DEG * p["amplitude"] * swing_l
    c.pelvis(off, yaw=pelvis_yaw, pitch=lean, roll=3 * DEG * np.sin(2 * np.pi * u))
    c.spine(flex=0.3 * lean, twist=+8 * DEG * p["amplitude"] * swing_l)
    c.head(flex=-lean)
    arm = 25 * DEG * p["arm_swing"] * arm_gain
    c.arm("left", 72 * DEG, -arm * swing_l, elbow + 10 * DEG * (1 - swing_l))
    c.arm("right", 72 * DEG, arm * swing_l, elbow + 10 * DEG * (1 + swing_l))


def _walk(c: _Ctx) -> None:
    p = c.p
    _gait(c, stride=p["stride"], cadence=p["cadence"], turn=p["turn"], duty=0.62, lift=0.07, drop=0.055 + 0.08 * (p["stride"] - 0.85),
          bob=0.015, lean=3 * DEG, arm_gain=1.0, elbow=12 * DEG, heel_off=30 * DEG)


def _run(c: _Ctx) -> None:
    p = c.p
    _gait(c, stride=p["stride"], cadence=p["cadence"], turn=p["turn"], duty=0.38, lift=0.16, drop=0.1,
          bob=0.045, lean=10 * DEG, arm_gain=1.5, elbow=75 * DEG, flight_bob=True,
          heel_off=30 * DEG)


def _turn_in_place(c: _Ctx) -> None:
    p = c.p
    f = 1.4 * p["tempo"]  # quick steps, so the planted foot never lags the turn by much
    angle = p["angle"] * DEG * p["amplitude"] * (1 if p["asymmetry"] >= 0 else -1)
    # turn one way over half a 4 s cycle, then back
    u = c.t / (4.0 / p["tempo"]) + p["phase"]
    heading = angle * (0.5 - 0.5 * np.cos(2 * np.pi * u))
    heading = heading - heading[0]
    path = np.zeros((c.T, 2))
    lateral = abs(c.rig.rest_joints[7, 0]) * p["stance"]
    for side, ph in (("left", 0.0), ("right", 0.5)):
        fs = plan_footsteps(c.rig, c.t, path, heading, cycle_hz=f, duty=0.6, phase=ph, lateral=lateral,
                            lift=0.05, toe_out=8 * DEG, side=side)
        c.track.ankle_target[side] = fs.ankle
        c.track.foot_rot[side] = foot_orientation(fs.yaw)
    c.pelvis(np.array([0.0, -0.04, 0.0]), yaw=heading)
    c.spine(twist=0.0 * heading)
    _hanging_arms(c, elbow=20 * DEG)


# ----------------------------------------------------------------------------------- whole body


def _jump(c: _Ctx) -> None:
    p = c.p
    period = 1.6 / p["tempo"]
    u = (c.t / period + p["phase"]) % 1.0
    k = np.floor(c.t / period + p["phase"])
    g = 9.81
    h = p["height"] * p["amplitude"]
    v0 = np.sqrt(2 * g * h)
    t_air = 2 * v0 / g
    a_air = t_air / period  # share of the cycle in the air
    crouch_start, takeoff = 0.15, 0.45
    land = takeoff + a_air
    depth = 0.12 + 0.5 * h
    # pelvis height: crouch down, extend, fly, absorb, recover
    y = np.zeros(c.T)
    down = (u >= crouch_start) & (u < takeoff)
    s = (u[down] - crouch_start) / (takeoff - crouch_start)
    y[down] = -depth * np.sin(np.pi * np.clip(s * 1.15, 0, 1)) ** 2  # down and back up to full extension
    air = (u >= takeoff) & (u < land)
    ta = (u[air] - takeoff) * period
    y[air] = v0 * ta - 0.5 * g * ta**2
    rec = u >= land
    s = np.clip((u[rec] - land) / (1.0 - land), 0.0, 1.0)
    y[rec] = -0.6 * depth * np.sin(np.pi * s) * (1 - s) ** 0.5
    y -= 0.02
    # forward travel happens in the air
    fwd_step = p["forward"]
    travel = (k + np.clip((u - takeoff) / a_air, 0.0, 1.0)) * fwd_step
    travel -= travel[0]
    c.pelvis(np.stack([np.zeros(c.T), y, travel], -1), pitch=1.2 * np.clip(-y, 0.0, None))
    crouch = np.clip(-y / depth, 0.0, 1.0)
    c.spine(flex=25 * DEG * crouch)
    c.head(flex=-15 * DEG * crouch)
    # feet: planted at the take-off and landing spots, tucked under the hips in the air
    feet_z = (k + smoothstep((u - takeoff) / a_air)) * fwd_step
    feet_z = feet_z - k[0] * fwd_step
    lift = np.where(air, y + 0.02 - 0.06 * np.sin(np.pi * np.clip((u - takeoff) / a_air, 0, 1)), 0.0)
    lift = np.maximum(lift, 0.0)
    for side in ("left", "right"):
        rest = c.rig.rest_joints[J[f"{side}_ankle"]]
        x = rest[0] * c.p["stance"]
        c.track.ankle_target[side] = np.stack([np.full(c.T, x), rest[1] + lift, rest[2] + feet_z], -1)
        yaw = 8 * DEG * (1 if side == "left" else -1)
        c.track.foot_rot[side] = foot_orientation(np.full(c.T, yaw), 20 * DEG * np.clip(lift / 0.1, 0, 1))
    swing = 60 * DEG * p["arm_swing"] * (np.sin(2 * np.pi * (u - 0.2)))
    _hanging_arms(c, swing_l=swing, swing_r=swing, elbow=25 * DEG)


def _squat(c: _Ctx) -> None:
    p = c.p
    u = c.cycles(0.4)
    s = 0.5 - 0.5 * np.cos(2 * np.pi * u)
    depth = p["depth"] * p["amplitude"]
    c.plant("left", yaw=15 * DEG)
    c.plant("right", yaw=-15 * DEG)
    c.track.ankle_target["left"][:, 0] += 0.03
    c.track.ankle_target["right"][:, 0] -= 0.03
    c.pelvis(np.stack([np.zeros(c.T), -depth * s, -0.5 * depth * s], -1), pitch=35 * DEG * s * depth / 0.35)
    c.spine(flex=20 * DEG * s)
    c.head(flex=-30 * DEG * s)
    # arms forward as a counterbalance, 65-95 degrees at the bottom: hanging lower (generator
    # version 1 swung them 31-80 degrees) the forearms came down onto the thighs, where the skinned
    # body's parts overlap and cloth caught between them tears
    raise_ = s * (65 + 30 * (p["arm_swing"] - 0.5) / 0.8) * DEG
    c.arm("left", 75 * DEG, raise_, 10 * DEG)
    c.arm("right", 75 * DEG, raise_, 10 * DEG)


def _lunge(c: _Ctx) -> None:
    p = c.p
    period = 3.0 / p["tempo"]
    u = (c.t / period + p["phase"]) % 2.0  # two lunges: lead leg, then the other
    k = np.floor(u).astype(int)
    s = u - k
    # step out (0-0.3), down and up (0.3-0.7), step back (0.7-1)
    out = smoothstep(s / 0.3) * (1 - smoothstep((s - 0.7) / 0.3))
    dip = np.sin(np.pi * np.clip((s - 0.25) / 0.5, 0, 1)) ** 2
    lift = 0.06 * (np.sin(np.pi * np.clip(s / 0.3, 0, 1)) + np.sin(np.pi * np.clip((s - 0.7) / 0.3, 0, 1)))
    stride = p["stride"] * p["amplitude"]
    depth = p["depth"] * p["amplitude"]
    lead = c.lead
    other = "right" if lead == "left" else "left"
    front = np.where(k == 0, 0, 1)  # 0: lead leg steps, 1: the other
    c.plant("left", yaw=6 * DEG)
    c.plant("right", yaw=-6 * DEG)
    for side, idx in ((lead, 0), (other, 1)):
        active = front == idx
        c.track.ankle_target[side][:, 2] += np.where(active, stride * out, 0.0)
        c.track.ankle_target[side][:, 1] += np.where(active, lift, 0.0)
        # the back foot's heel rises in the dip (toe-down pitch)
        back_pitch = np.where(~active, 30 * DEG * dip, 0.0)
        yaw = 6 * DEG if side == "left" else -6 * DEG
        c.track.foot_rot[side] = foot_orientation(np.full(c.T, yaw), back_pitch)
        rise, ahead = heel_roll_offset(c.rig, back_pitch)
        c.track.ankle_target[side][:, 1] += rise
        c.track.ankle_target[side][:, 2] += ahead
    c.pelvis(np.stack([np.zeros(c.T), -depth * dip - 0.02, 0.45 * stride * out], -1))
    c.spine(flex=5 * DEG * dip)
    hands = 30 * DEG * p["arm_swing"] * dip
    _hanging_arms(c, swing_l=hands, swing_r=hands, elbow=20 * DEG + hands)


def _kick(c: _Ctx) -> None:
    p = c.p
    u = c.cycles(0.55)
    s = u % 1.0
    kick = np.sin(np.pi * np.clip((s - 0.1) / 0.6, 0, 1)) ** 2  # 0 -> 1 -> 0
    snap = np.sin(np.pi * np.clip((s - 0.25) / 0.35, 0, 1)) ** 2  # knee extends mid-kick
    side = c.lead
    stand = "right" if side == "left" else "left"
    sgn = 1.0 if side == "left" else -1.0
    c.plant(stand, (sgn * 0.02, 0.0), yaw=-sgn * 10 * DEG)
    c.plant(side, yaw=sgn * 6 * DEG)
    # weight over the standing leg, trunk leans back as the leg rises
    c.pelvis(np.stack([-sgn * 0.05 * np.ones(c.T), -0.03 * np.ones(c.T), np.zeros(c.T)], -1),
             pitch=-8 * DEG * kick, roll=sgn * 3 * DEG * kick)
    # the kicking ankle follows a virtual leg (hip flexion, knee that chambers then snaps
    # straight), kept above the ground; IK then bends the real leg to reach it
    flex = p["height"] * DEG * p["amplitude"] * kick
    knee = 90 * DEG * kick**0.75 * (1 - 0.85 * snap)
    hip, j_knee, j_ankle = J[f"{side}_hip"], J[f"{side}_knee"], J[f"{side}_ankle"]
    thigh = c.rig.rest_joints[j_knee] - c.rig.rest_joints[hip]
    shin = c.rig.rest_joints[j_ankle] - c.rig.rest_joints[j_knee]
    leg = rot_x(-flex) @ (thigh[None, :, None] + rot_x(knee) @ shin[None, :, None])
    hip_pos = c.track.pelvis_pos + c.track.pelvis_rot @ c.rig.offset(hip)
    target = hip_pos + (c.track.pelvis_rot @ leg)[..., 0]
    planted = c.track.ankle_target[side]
    w = smoothstep(kick / 0.2)[:, None]
    w_xz = smoothstep((kick - 0.08) / 0.25)[:, None]  # lift first, then travel
    target = np.concatenate([(1 - w_xz) * planted[:, :1] + w_xz * target[:, :1],
                             (1 - w) * planted[:, 1:2] + w * target[:, 1:2],
                             (1 - w_xz) * planted[:, 2:] + w_xz * target[:, 2:]], axis=1)
    target[:, 1] = np.maximum(target[:, 1], planted[:, 1])
    c.track.ankle_target[side] = target
    # the foot follows the virtual shin and points with the snap; the ankle is raised where a
    # pointed foot would otherwise put its ball below the floor
    shin_pitch = knee - flex - 8 * DEG * kick  # the virtual shin's pitch (world, toe-down > 0)
    pitch = w[:, 0] * (shin_pitch + 25 * DEG * snap)
    # a toe-down foot pivots on its ball, a toe-up one on its heel (about 7 cm behind the ankle)
    lift = np.where(pitch > 0, heel_roll_offset(c.rig, np.clip(pitch, 0, None))[0], 0.07 * np.sin(np.clip(-pitch, 0, None)))
    target[:, 1] = np.maximum(target[:, 1], planted[:, 1] + lift)
    c.track.foot_rot[side] = foot_orientation(np.full(c.T, sgn * 6 * DEG), pitch)
    c.spine(flex=-6 * DEG * kick)
    c.head(flex=10 * DEG * kick)
    guard = 40 * DEG * p["arm_swing"] * kick
    c.arm("left", 70 * DEG, guard * (1 if side == "right" else -0.5), 60 * DEG)
    c.arm("right", 70 * DEG, guard * (1 if side == "left" else -0.5), 60 * DEG)


# ----------------------------------------------------------------------------------- upper body


def _idle_legs(c: _Ctx, sway: float = 0.01) -> None:
    """Both feet planted; a slow weight shift so the legs never freeze."""
    c.plant_both()
    u = c.t * 0.25 + c.p["phase"]
    c.pelvis(np.stack([sway * np.sin(2 * np.pi * u), -0.02 * np.ones(c.T), np.zeros(c.T)], -1))


def _wave(c: _Ctx) -> None:
    p = c.p
    _idle_legs(c)
    side = c.lead
    other = "right" if side == "left" else "left"
    rate = p["rate"] * p["tempo"]
    osc = np.sin(2 * np.pi * (c.t * rate + p["phase"]))
    onset = smoothstep(c.t / 0.8)
    raise_ = (90 * DEG + p["raise"] * DEG) * onset  # from hanging (lower 75) to above horizontal
    lower = 75 * DEG - raise_ * (165 / 180)
    c.arm(side, lower, 0.0, (65 * DEG + 22 * DEG * osc * p["amplitude"]) * onset,
          horizontal=10 * DEG * onset, humeral=80 * DEG * onset)
    c.arm(other, 75 * DEG, 5 * DEG, 15 * DEG)
    s = 1.0 if side == "left" else -1.0
    c.spine(side=-s * 4 * DEG * onset, twist=s * 5 * DEG * onset)
    c.head(twist=s * 10 * DEG * onset)


def _raise_arms(c: _Ctx) -> None:
    p = c.p
    _idle_legs(c)
    u = c.cycles(0.35)
    s = 0.5 - 0.5 * np.cos(2 * np.pi * u)  # 0 down, 1 up
    top = 165 * DEG * p["amplitude"] / 1.15
    plane = p["plane"]
    for side in ("left", "right"):
        g = c.side_gain(side)
        lift = np.minimum(s * top * g, 170 * DEG)
        # sideways: reduce "lower"; forward: swing about X with the arm hanging
        c.arm(side, 75 * DEG - (1 - plane) * lift, plane * lift, 10 * DEG)
    c.spine(flex=-4 * DEG * s)
    c.head(flex=-10 * DEG * s)


def _arm_circles(c: _Ctx) -> None:
    p = c.p
    _idle_legs(c)
    u = c.cycles(1.0)
    r = p["radius"] * DEG * p["amplitude"]
    d = 1.0 if p["direction"] >= 0 else -1.0
    onset = smoothstep(c.t / 0.6)
    for side in ("left", "right"):
        a = 2 * np.pi * u
        c.arm(side, (5 * DEG - r * np.cos(a)) * onset + 75 * DEG * (1 - onset), d * r * np.sin(a) * onset, 5 * DEG)


def _torso_twist(c: _Ctx) -> None:
    p = c.p
    _idle_legs(c, sway=0.0)
    u = c.cycles(0.45)
    tw = p["twist"] * DEG * p["amplitude"] * np.sin(2 * np.pi * u) + 3 * DEG * p["asymmetry"]
    c.spine(twist=tw)
    c.head(twist=-0.3 * tw)
    c.track.pelvis_rot = rot_y(0.2 * tw)
    arms = 55 * DEG
    c.arm("left", arms, 30 * DEG, 80 * DEG * p["arm_swing"] / 1.3)
    c.arm("right", arms, 30 * DEG, 80 * DEG * p["arm_swing"] / 1.3)


def _bend_forward(c: _Ctx) -> None:
    p = c.p
    c.plant_both()
    u = c.cycles(0.3)
    s = 0.5 - 0.5 * np.cos(2 * np.pi * u)
    bend = p["bend"] * DEG * p["amplitude"] * s
    hip = 0.55 * bend
    c.pelvis(np.stack([np.zeros(c.T), -0.02 - 0.02 * s, -0.12 * np.sin(hip)], -1), pitch=hip)
    c.spine(flex=bend - hip)
    c.head(flex=-0.3 * bend)
    # arms hang toward the floor: swing forward by the trunk's pitch
    swing = 0.9 * bend * p["arm_swing"] / 1.3
    _hanging_arms(c, swing_l=swing, swing_r=swing, elbow=10 * DEG)


def _side_bend(c: _Ctx) -> None:
    p = c.p
    c.plant_both()
    u = c.cycles(0.35)
    b = p["bend"] * DEG * p["amplitude"] * np.sin(2 * np.pi * u)  # > 0 bends to the right
    c.pelvis(np.stack([0.04 * b, -0.02 * np.ones(c.T), np.zeros(c.T)], -1), roll=-0.15 * b)
    c.spine(side=-b)
    c.head(side=0.3 * b)
    up_l = np.clip(b, 0, None) / (35 * DEG)  # the arm on the convex side reaches over
    up_r = np.clip(-b, 0, None) / (35 * DEG)
    c.arm("left", 75 * DEG - 150 * DEG * up_l * p["arm_swing"] / 1.3, 0.0, 20 * DEG)
    c.arm("right", 75 * DEG - 150 * DEG * up_r * p["arm_swing"] / 1.3, 0.0, 20 * DEG)


def _sit_stand(c: _Ctx) -> None:
    p = c.p
    u = c.cycles(0.25) % 1.0
    hold = p["hold"]
    # down over (1 - hold) / 2, hold, up over (1 - hold) / 2
    ramp = (1 - hold) / 2
    s = smoothstep(u / ramp) * (1 - smoothstep((u - ramp - hold) / ramp))
    depth = p["depth"] * p["amplitude"]
    c.plant("left", (0.02, 0.0), yaw=12 * DEG)
    c.plant("right", (-0.02, 0.0), yaw=-12 * DEG)
    transit = np.sin(np.pi * s)  # lean forward most while moving
    back = -0.55 * depth * s
    c.pelvis(np.stack([np.zeros(c.T), -depth * s, back], -1), pitch=(15 * DEG * s + 20 * DEG * transit))
    c.spine(flex=15 * DEG * transit)
    c.head(flex=-20 * DEG * transit)
    reach = 50 * DEG * transit * p["arm_swing"] / 1.3 + 25 * DEG * s
    _hanging_arms(c, swing_l=reach, swing_r=reach, elbow=30 * DEG)


def _box(c: _Ctx) -> None:
    p = c.p
    lead = c.lead
    rear = "right" if lead == "left" else "left"
    sl = 1.0 if lead == "left" else -1.0
    c.plant(lead, (0.0, 0.13), yaw=sl * 20 * DEG)
    c.plant(rear, (0.0, -0.13), yaw=-sl * 35 * DEG)
    bounce = c.cycles(1.8)
    y = -0.06 - 0.02 * p["amplitude"] * (0.5 + 0.5 * np.cos(2 * np.pi * bounce))
    rate = p["punch_rate"] * p["tempo"]
    u = c.t * rate + p["phase"]
    jab = pulse(u, 0.8) ** 2 * (np.floor(u + 0.5) % 2 == 0)  # squared: smooth to the 2nd derivative
    cross = pulse(u, 0.8) ** 2 * (np.floor(u + 0.5) % 2 == 1)
    turn = sl * (-25 * DEG + 20 * DEG * cross - 5 * DEG * jab)
    c.pelvis(np.stack([np.zeros(c.T), y, 0.03 * cross], -1), yaw=turn * 0.4)
    c.spine(flex=8 * DEG * np.ones(c.T), twist=turn * 0.6)
    c.head(flex=5 * DEG * np.ones(c.T), twist=-turn * 0.9)
    amp = p["amplitude"]
    for side, punch in ((lead, jab), (rear, cross)):
        # guard: arm down and forward, elbow folded; punch: arm straight forward at shoulder height
        c.arm(side, lower=55 * DEG * (1 - punch) + 8 * DEG * punch, swing=35 * DEG * (1 - punch),
              horizontal=85 * DEG * punch * amp / 1.15, elbow=125 * DEG * (1 - punch) + 8 * DEG * punch,
              twist=60 * DEG * punch)


def _dance_sway(c: _Ctx) -> None:
    p = c.p
    beat = p["bpm"] / 60.0 * p["tempo"] ** 0.5
    f = beat / 2.0  # one step-touch to each side per two beats
    step = p["step"] * p["amplitude"]
    u = c.t * f / 2.0 + p["phase"]  # one full left-right cycle per 4 beats
    x = step * np.sin(2 * np.pi * u)
    # feet step sideways with the pelvis: each foot travels while it is the trailing one
    path = np.stack([x, np.zeros(c.T)], -1)
    heading = np.zeros(c.T)
    lateral = abs(c.rig.rest_joints[7, 0]) * p["stance"]
    for side, ph in (("left", 0.25), ("right", 0.75)):
        fs = plan_footsteps(c.rig, c.t, path, heading, cycle_hz=f, duty=0.55, phase=(p["phase"] * 2 + ph) % 1,
                            lateral=lateral, lift=0.05, toe_out=10 * DEG, side=side)
        c.track.ankle_target[side] = fs.ankle
        c.track.foot_rot[side] = foot_orientation(fs.yaw)
    groove = np.sin(2 * np.pi * beat * c.t)
    c.pelvis(np.stack([x, -0.05 - 0.02 * np.abs(groove), np.zeros(c.T)], -1),
             roll=6 * DEG * np.cos(2 * np.pi * u), yaw=10 * DEG * np.sin(2 * np.pi * u))
    c.spine(side=-8 * DEG * np.cos(2 * np.pi * u), twist=-8 * DEG * np.sin(2 * np.pi * u))
    c.head(side=4 * DEG * np.cos(2 * np.pi * u))
    arm = 35 * DEG * p["arm_swing"]
    c.arm("left", 60 * DEG - arm * (0.5 + 0.5 * np.sin(2 * np.pi * u)), 25 * DEG, 70 * DEG + 20 * DEG * groove)
    c.arm("right", 60 * DEG - arm * (0.5 - 0.5 * np.sin(2 * np.pi * u)), 25 * DEG, 70 * DEG - 20 * DEG * groove)


def _dance_disco(c: _Ctx) -> None:
    p = c.p
    beat = p["bpm"] / 60.0 * p["tempo"] ** 0.5
    c.plant("left", (0.06, 0.0), yaw=15 * DEG)
    c.plant("right", (-0.06, 0.0), yaw=-15 * DEG)
    b = c.t * beat + p["phase"] * 4
    bounce = 0.5 + 0.5 * np.cos(2 * np.pi * b)
    bar = b / 4.0  # the point goes up on beats 1 and 3 of every bar
    up = 0.5 - 0.5 * np.cos(2 * np.pi * 2 * bar)  # 0..1 twice per bar
    side = c.lead
    other = "right" if side == "left" else "left"
    s = 1.0 if side == "left" else -1.0
    hip_sway = 0.04 * p["amplitude"] * np.sin(2 * np.pi * b / 2)
    c.pelvis(np.stack([hip_sway, -0.06 - 0.03 * bounce, np.zeros(c.T)], -1),
             roll=-5 * DEG * np.sin(2 * np.pi * b / 2), yaw=s * 10 * DEG * (up - 0.5))
    c.spine(side=s * 8 * DEG * (up - 0.5), twist=s * 10 * DEG * (up - 0.5))
    c.head(side=-s * 6 * DEG * (up - 0.5))
    # the pointing arm sweeps from across the body (down) to up and out
    c.arm(side, lower=75 * DEG - 130 * DEG * up * p["amplitude"] / 1.15, swing=40 * DEG * (1 - up),
          elbow=15 * DEG, horizontal=-10 * DEG)
    c.arm(other, 65 * DEG, 20 * DEG * p["arm_swing"], 90 * DEG)


_GENERATORS: dict[str, Callable[[_Ctx], None]] = {
    "walk": _walk, "run": _run, "jump": _jump, "squat": _squat, "lunge": _lunge, "kick": _kick,
    "wave": _wave, "raise_arms": _raise_arms, "arm_circles": _arm_circles, "torso_twist": _torso_twist,
    "bend_forward": _bend_forward, "side_bend": _side_bend, "sit_stand": _sit_stand,
    "turn_in_place": _turn_in_place, "box": _box, "dance_sway": _dance_sway, "dance_disco": _dance_disco,
}

