"""Garments on moving bodies: the run from a rest drape to recorded frames, for a batch of scenes.

Every scene starts with its garment at rest on its body in the rest pose. Then:

1. ``settle_rest`` frames in the rest pose (the drape falls onto the body);
2. a lead-in of ``lead_in`` seconds that moves the body from the rest pose to the motion's first
   pose (:meth:`~datagen.motion.motion.Motion.with_lead_in`);
3. ``settle_pose`` frames holding the first pose;
4. the motion's frames, which are recorded.

Metrics are measured every frame of every phase; a scene that passes a failure threshold in any
frame is flagged with the reason (and kept running, so the batch goes on).
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from datagen.errors import InputError
from datagen.sim.metrics import METRIC_NAMES, FailureThresholds, Metrics
from datagen.sim.model import ClothModelBuilder
from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState

log = logging.getLogger(__name__)


@dataclass(frozen=True, kw_only=True)
class RunConfig:
    """How a scene is run (frames at the motion's frame rate)."""

    settle_rest: int = 15
    lead_in: float = 0.5
    settle_pose: int = 10
    solver: SolverConfig = field(default_factory=SolverConfig)
    thresholds: FailureThresholds = field(default_factory=FailureThresholds)

    def __post_init__(self):
        if self.settle_rest < 1 or self.settle_pose < 0 or self.lead_in < 0:
            raise InputError(f"settle_rest must be >= 1 and settle_pose, lead_in >= 0; got {self.settle_rest}, "
                             f"{self.settle_pose}, {self.lead_in}")

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass
class Scene:
    """One garment on one body doing one motion.

    Attributes:
        garment: a :class:`~datagen.garment.mesh.GarmentMesh` placed on the body in its rest pose.
        body: the :class:`~datagen.body.model.BodyModel`.
        betas: shape coefficients of the body [shape_dim].
        motion: a :class:`~datagen.motion.motion.Motion` (SMPL poses at its frame rate).
    """

    garment: object
    body: object
    betas: np.ndarray
    motion: object


@dataclass
class SceneResult:
    """What one scene produced.

    Attributes:
        positions: garment vertices of the recorded frames [m], [T, V, 3] float32.
        faces: garment triangles [F, 3].
        metrics: name -> per-frame values over every simulated frame [settle + lead-in + T].
        recorded_from: index of the first recorded frame in ``metrics``.
        failure: the reason the scene failed, or None.
        failure_frame: the frame (index into ``metrics``) where it first failed, or -1.
        seconds: wall time of the batch this scene was in.
    """

    positions: np.ndarray
    faces: np.ndarray
    metrics: dict
    recorded_from: int
    failure: str | None
    failure_frame: int
    seconds: float

    def save(self, path, **extra) -> None:
        np.savez_compressed(path, positions=self.positions, faces=self.faces, recorded_from=self.recorded_from,
                            failure="" if self.failure is None else self.failure, failure_frame=self.failure_frame,
                            **{f"metric_{k}": v for k, v in self.metrics.items()}, **extra)

    def summary(self) -> dict:
        rec = {k: np.asarray(v)[self.recorded_from:] for k, v in self.metrics.items()}
        frames = len(rec["nan"])
        return {
            "recorded_frames": frames,
            "stretch_max": float(np.max(rec["stretch_max"])),
            "stretch_mean": float(np.mean(rec["stretch_mean"])),
            "frames_with_penetration": int((rec["penetration_count"] > 0).sum()),
            "share_frames_without_penetration": float((rec["penetration_count"] == 0).mean()) if frames else 1.0,
            "penetration_count_max": int(np.max(rec["penetration_count"])),
            "penetration_depth_max_mm": float(np.max(rec["penetration_depth"]) * 1000),
            "self_intersections_max": int(np.max(rec["self_intersections"])),
            "kinetic_energy_max": float(np.max(rec["kinetic_energy"])),
            "nan": bool(np.any(rec["nan"])),
            "failure": self.failure,
        }


def simulate(scenes: list[Scene], config: RunConfig = RunConfig(), device: str | None = None,
             progress=None) -> list[SceneResult]:
    """Run a batch of scenes in one model (one set of launches); see the module doc for the phases.

    All scenes' motions must have the same frame count and frame rate (batch them by length).
    ``progress(frame, frame_count)`` is called after every frame.
    """
    if not scenes:
        raise InputError("no scenes to simulate")
    fps = {float(s.motion.fps) for s in scenes}
    lengths = {s.motion.frame_count for s in scenes}
    if len(fps) > 1 or len(lengths) > 1:
        raise InputError(f"a batch needs one frame rate and one length; got fps {sorted(fps)}, frames {sorted(lengths)}")
    fps = fps.pop()
    builder = ClothModelBuilder()
    body_frames = []
    lead = 0
    for k, s in enumerate(scenes):
        motion, lead = s.motion.with_lead_in(config.lead_in)
        betas = np.asarray(s.betas, dtype=np.float64).reshape(1, -1)
        poses = motion.poses.reshape(motion.frame_count, -1)
        verts, _ = s.body.pose(np.repeat(betas, motion.frame_count, 0), poses, motion.trans)
        rest = np.asarray(s.body.shaped(betas))[0]
        shift = verts[0] - rest  # the lead-in's frame 0 is the rest pose at the first frame's translation
        if np.abs(shift - shift.mean(0)).max() > 1e-6:
            raise InputError("the motion's lead-in does not start in the body's rest pose")
        g = s.garment
        builder.add_cloth(g.vertices + shift.mean(0), g.faces, material_name=g.material, scene=k,
                          material_frames=g.material_frames())
        builder.add_body(verts[0], s.body.faces, scene=k)
        body_frames.append(verts)
    model = builder.finalize(device)
    solver = SolverVBD(model, config.solver)
    metrics = Metrics(model)
    state_a, state_b = ClothState.from_model(model), ClothState.from_model(model)
    n_motion = lead + scenes[0].motion.frame_count
    schedule = [0] * config.settle_rest + list(range(1, lead + 1)) + [lead] * config.settle_pose + list(
        range(lead + 1, n_motion))
    # the motion's frame 0 is the last frame of the lead-in and pose settle
    recorded_from = config.settle_rest + lead + config.settle_pose - 1
    control = BodyControl.from_numpy(model, np.concatenate([b[0] for b in body_frames]))
    solver.reset_body(control)
    series = {k: [] for k in METRIC_NAMES}
    failure: list[str | None] = [None] * len(scenes)
    failure_frame = [-1] * len(scenes)
    positions = []
    start = time.perf_counter()
    dt = 1.0 / fps
    for f, src in enumerate(schedule):
        control.set(np.concatenate([b[src] for b in body_frames]))
        solver.step(state_a, state_b, control, dt)
        state_a, state_b = state_b, state_a
        frame = metrics.measure(state_a, solver)
        for k in METRIC_NAMES:
            series[k].append(frame[k])
        for s in range(len(scenes)):
            if failure[s] is None:
                why = metrics.failure(frame, s, config.thresholds)
                if why:
                    failure[s], failure_frame[s] = why, f
                    log.warning("scene %d failed at frame %d: %s", s, f, why)
        if f >= recorded_from:
            positions.append(state_a.positions.numpy())
        if progress:
            progress(f + 1, len(schedule))
    seconds = time.perf_counter() - start
    pos = np.stack(positions) if positions else np.zeros((0, model.particle_count, 3), np.float32)
    out = []
    scene_of = model.host["particle_scene"]
    for s in range(len(scenes)):
        sel = scene_of == s
        out.append(SceneResult(positions=pos[:, sel], faces=np.asarray(scenes[s].garment.faces), recorded_from=recorded_from,
                               metrics={k: np.array([v[s] for v in series[k]]) for k in METRIC_NAMES},
                               failure=failure[s], failure_frame=failure_frame[s], seconds=seconds))
    return out
