"""Garments on moving bodies: the run from a rest drape to recorded frames, for a batch of scenes.

Every scene starts with its garment at rest on its body in the rest pose. Then:

1. ``settle_rest`` frames in the rest pose (the drape falls onto the body);
2. a lead-in of ``lead_in`` seconds that moves the body from the rest pose to the motion's first
   pose (:meth:`~datagen.motion.motion.Motion.with_lead_in`);
3. ``settle_pose`` frames holding the first pose;
4. a ramp of ``ramp`` seconds (R frames) in which the motion starts from standstill: the motion's
   clock runs at a speed that grows linearly from 0 to 1, so the body accelerates smoothly into the
   motion instead of jumping to full speed in one frame (a walk starting at 1.2 m/s in 1/30 s is
   3.7 g: the cloth tears off the body). The ramp plays motion frames 0 to R/2 (the body between
   frames is interpolated linearly) and these are not recorded;
5. the motion's frames from R/2 on, which are recorded. Ask for R/2 frames more than you want
   recorded: :meth:`RunConfig.motion_frames` says how many a motion needs.

Metrics are measured every frame of every phase; a scene that passes a failure threshold in any
frame is flagged with the reason (and kept running, so the batch goes on).
"""

from __future__ import annotations

import logging
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field

import numpy as np

from datagen.body.skeleton import face_parts
from datagen.errors import InputError, SimulationError
from datagen.materials import Material
from datagen.sim.device import MEMORY_ADVICE, check_device_memory, torch_cuda, warp_device
from datagen.sim.interface import SOLVERS, make_solver, solver_class
from datagen.sim.metrics import METRIC_NAMES, Failure, FailureThresholds, Metrics
from datagen.sim.model import ClothModelBuilder
from datagen.sim.settings import SolverConfig
from datagen.sim.sewing import SewConfig
from datagen.sim.state import BodyControl, ClothState

log = logging.getLogger(__name__)


@dataclass(frozen=True, kw_only=True)
class RunConfig:
    """How a scene is run (frames at the motion's frame rate); see the module doc for the phases.

    Attributes:
        settle_rest: frames of rest in the rest pose before the lead-in.
        lead_in: seconds from the rest pose into the motion's first pose.
        settle_pose: frames holding the first pose after the lead-in.
        ramp: seconds over which the motion starts from standstill (not recorded).
        solver_name: which solver of :data:`datagen.sim.interface.SOLVERS` runs the scenes.
        solver: the solver's settings.
        thresholds: what makes a scene fail.
        sewing: how a pattern garment is sewn and settled on the body at rest before its scene
            (:func:`datagen.sim.sewing.sew`, with this run's solver settings and thresholds).
        freeze_failed: stop simulating a scene from the frame it fails (its vertices held where they
            are): a failed scene's frames are not stored, and a tangled scene is the most expensive
            kind. Its later metrics then describe the frozen cloth; its failure and failure frame do
            not change, nor does any other scene of the batch. False: simulate it to the end
            (diagnosis: what a failed scene goes on to do).
    """

    settle_rest: int = field(default=15, metadata={"min": 1, "max": 1000})
    lead_in: float = field(default=0.5, metadata={"min": 0.0, "max": 10.0})
    settle_pose: int = field(default=10, metadata={"min": 0, "max": 1000})
    ramp: float = field(default=1.0, metadata={"min": 0.0, "max": 10.0})
    solver_name: str = field(default="vbd", metadata={"choices": tuple(SOLVERS)})
    solver: SolverConfig = field(default_factory=SolverConfig)
    thresholds: FailureThresholds = field(default_factory=FailureThresholds)
    sewing: SewConfig = field(default_factory=SewConfig)
    freeze_failed: bool = True

    def __post_init__(self):
        if self.settle_rest < 1 or self.settle_pose < 0 or self.lead_in < 0 or self.ramp < 0:
            raise InputError(f"settle_rest must be >= 1 and settle_pose, lead_in, ramp >= 0; got {self.settle_rest}, "
                             f"{self.settle_pose}, {self.lead_in}, {self.ramp}")
        solver_class(self.solver_name)  # an unknown name is refused here, with the known ones

    def ramp_frames(self, fps: float) -> tuple[int, int]:
        """(R, K): simulated ramp frames (even) and the motion frames they play, K = R/2, which
        are not recorded."""
        r = 2 * int(round(self.ramp * fps / 2))
        return r, r // 2

    def motion_frames(self, recorded: int, fps: float) -> int:
        """Motion frames a scene needs to record ``recorded`` frames: those and the ramp's
        (the one place this is worked out: generate, ``drape simulate`` and the benchmarks ask)."""
        return int(recorded) + self.ramp_frames(fps)[1]

    def recorded_motion_frames(self, recorded: int, fps: float) -> slice:
        """The frames of a scene's motion (as :meth:`motion_frames` counts them) that its ``recorded``
        frames play: those after the ramp's (:func:`simulate` records the body at exactly these)."""
        first = self.ramp_frames(fps)[1]
        return slice(first, first + int(recorded))

    def phases(self, recorded: int, fps: float, *, sewn: bool = False) -> dict[str, int]:
        """Simulated frames of each phase of a scene recording ``recorded`` frames (as
        :func:`frame_schedule` runs them): ``settle_rest``, ``lead_in``, ``settle_pose``, ``ramp``
        (its last frame is the first recorded one, so not counted here) and ``recorded``; with
        ``sewn`` (a pattern garment) first ``sewing``: the most frames :func:`datagen.sim.sewing.sew`
        runs (sewing, relaxing, settling until static; it stops each stage early when done)."""
        ramp, _ = self.ramp_frames(fps)
        first = {"sewing": self.sewing.most_frames()} if sewn else {}
        return first | {"settle_rest": self.settle_rest, "lead_in": int(round(self.lead_in * fps)),
                "settle_pose": self.settle_pose, "ramp": max(ramp - 1, 0), "recorded": int(recorded)}

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
    """What one scene produced: the recorded frames of the garment and of what moved it.

    Attributes:
        positions: garment vertices of the recorded frames [m], [T, V, 3] float32.
        faces: garment triangles [F, 3].
        body_vertices: the body of the recorded frames [m], [T, B, 3] float32 (the collider the
            cloth saw: the scene's own body frames, not posed again).
        poses: SMPL axis-angle poses of the recorded frames [T, 24, 3] (rad), or None when the
            scene came as arrays without them.
        trans: root translations of the recorded frames [T, 3] (m), or None likewise.
        fps: frame rate [1/s].
        metrics: name -> per-frame values over every simulated frame [settle + lead-in + T].
        recorded_from: index of the first recorded frame in ``metrics``.
        motion_from: the motion frame of the first recorded frame (the ramp's frames before it).
        failure: why the scene failed, or None.
        failure_frame: the frame (index into ``metrics``) where it first failed, or -1.
        seconds: wall time of the batch this scene was in.
        settled: the garment at rest [V, 3] (m, float32): its positions at the end of the settle in
            the body's rest pose, before the lead-in and the motion, in the frame of the garment it
            was given (the lead-in's shift to the motion's first translation taken off): the
            garment's template (a store's ``garments/rest_vertices``; for a sewn pattern garment, the sewn
            and settled cloth).
    """

    positions: np.ndarray
    faces: np.ndarray
    body_vertices: np.ndarray
    poses: np.ndarray | None
    trans: np.ndarray | None
    fps: float
    metrics: dict
    recorded_from: int
    motion_from: int
    failure: Failure | None
    failure_frame: int
    seconds: float
    settled: np.ndarray | None = None

    def arrays(self) -> dict[str, np.ndarray]:
        """The result as named arrays (what :meth:`save` writes): ``garment_vertices``,
        ``garment_faces``, ``body_vertices``, ``fps``, ``pose``/``trans`` when known, the run's
        ``recorded_from``, ``motion_from``, ``failure`` (code, empty when none), ``failure_message``,
        ``failure_frame``, ``settled`` (the garment at rest) and ``metric_<name>`` per simulated frame."""
        out = {"garment_vertices": self.positions, "garment_faces": self.faces, "body_vertices": self.body_vertices,
               "fps": np.float64(self.fps), "recorded_from": self.recorded_from, "motion_from": self.motion_from,
               "failure": "" if self.failure is None else self.failure.code,
               "failure_message": "" if self.failure is None else self.failure.message,
               "failure_frame": self.failure_frame, **{f"metric_{k}": v for k, v in self.metrics.items()}}
        if self.settled is not None:
            out["settled"] = self.settled
        if self.poses is not None:
            out.update(pose=self.poses.astype(np.float32), trans=self.trans.astype(np.float32))
        return out

    def save(self, path, **extra) -> None:
        """Write :meth:`arrays` and ``extra`` to a compressed ``.npz``."""
        np.savez_compressed(path, **self.arrays(), **extra)

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
            "failure": None if self.failure is None else str(self.failure),
        }


@dataclass(frozen=True, kw_only=True)
class SceneArrays:
    """A scene reduced to arrays and values: what the simulator needs, without the body model or
    motion code (so a scene can be prepared on one machine and simulated on another).

    Attributes:
        garment_vertices: the garment's rest drape [V, 3] (m), at the motion's first translation.
        garment_faces: triangles [F, 3].
        material: the cloth's :class:`~datagen.materials.Material` (a value: a custom material
            reaches the solver as given).
        material_frames: weft and warp directions per face [F, 2, 3].
        weft_scale: rest length along the weft relative to the built mesh, per face [F] (below 1
            on an elastic waistband).
        body_frames: posed body vertices of every motion frame, lead-in included [N, B, 3] (m).
        body_faces: body triangles [Fb, 3].
        fps: frame rate [1/s].
        lead_frames: lead-in frames at the start of ``body_frames`` (frame 0 is the rest pose).
        body_face_part: body part of every body face [Fb] (:func:`datagen.body.skeleton.face_parts`;
            None: the body is one part).
        poses: the pose of every body frame [N, 24, 3] (rad, axis-angle), or None.
        trans: the root translation of every body frame [N, 3] (m), or None.
        garment_shift: the translation [3] (m) added to the given garment's vertices to put it at the
            motion's first translation (taken off again for :attr:`SceneResult.settled`).
        rest_corners: the flat rest state of a sewn pattern garment: every face corner's 2D panel
            coordinate in its (weft, warp) frame [F, 3, 2] (m) (:func:`datagen.sim.sewing.rest_corners`);
            None: the garment rests as built (a shell).
    """

    garment_vertices: np.ndarray
    garment_faces: np.ndarray
    material: Material
    material_frames: np.ndarray
    weft_scale: np.ndarray
    body_frames: np.ndarray
    body_faces: np.ndarray
    fps: float
    lead_frames: int
    body_face_part: np.ndarray | None = None
    poses: np.ndarray | None = None
    trans: np.ndarray | None = None
    garment_shift: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rest_corners: np.ndarray | None = None

    def __post_init__(self):
        if not isinstance(self.material, Material):
            raise InputError(f"SceneArrays.material must be a Material (datagen.materials.material(name) gives a "
                             f"preset), got {self.material!r}")
        n = len(self.body_frames)
        if (self.poses is None) != (self.trans is None) or (
                self.poses is not None and (len(self.poses) != n or len(self.trans) != n)):
            raise InputError(f"poses and trans must both be given with one row per body frame ({n}), or neither")

    @property
    def frame_count(self) -> int:
        """Frames of the motion itself (without the lead-in)."""
        return len(self.body_frames) - self.lead_frames


def _posed_body(scene: Scene, lead_in: float, torch_body=None) -> tuple:
    """The scene's motion with its lead-in, the lead-in's frames, the posed body vertices [T, B, 3]
    (float32), the shift of frame 0 from the rest pose, and the body's face parts.

    ``torch_body``: the body model as a float64 torch module (:meth:`~datagen.body.model.BodyModel.torch`)
    to pose with, e.g. on the GPU that is about to simulate; ``None``: numpy on the host. The two
    agree to float64 rounding (their float32 results to an ulp)."""
    s = scene
    motion, lead = s.motion.with_lead_in(lead_in)
    betas = np.asarray(s.betas, dtype=np.float64).reshape(1, -1)
    poses = motion.poses.reshape(motion.frame_count, -1)
    rest = np.asarray(s.body.shaped(betas))[0]
    if torch_body is None:
        verts, _ = s.body.pose(np.repeat(betas, motion.frame_count, 0), poses, motion.trans)
        first, verts = verts[0], verts.astype(np.float32)
    else:
        import torch

        dev = torch_body.v_template.device
        with torch.no_grad():
            v, _ = torch_body(*(torch.as_tensor(np.asarray(a, dtype=np.float64), device=dev)
                                for a in (betas, poses, motion.trans)))
            first, verts = v[0].cpu().numpy(), v.to(torch.float32).cpu().numpy()
    shift = first - rest  # the lead-in's frame 0 is the rest pose at the first frame's translation
    if np.abs(shift - shift.mean(0)).max() > 1e-6:
        raise InputError("the motion's lead-in does not start in the body's rest pose")
    return motion, int(lead), verts, shift.mean(0), face_parts(s.body.weights, s.body.faces)


def scene_arrays(scene: Scene, lead_in: float, posed: tuple | None = None) -> SceneArrays:
    """Pose the scene's body over its motion with a lead-in of ``lead_in`` seconds from the rest pose
    (``posed``: :func:`_posed_body`'s result for it, when already made)."""
    s = scene
    g = s.garment
    corners = None
    if getattr(g, "kind", "shell") == "pattern":
        from datagen.sim.sewing import rest_corners

        if g.stitch_pairs is not None and len(g.stitch_pairs):
            raise InputError("a pattern garment must be sewn before it is simulated: datagen.sim.sewing.sew(garment, "
                             "body_vertices, body_faces) gives the welded garment (`drape simulate --pattern` does it)")
        corners = rest_corners(g)
    motion, lead, verts, shift, parts = posed if posed is not None else _posed_body(s, lead_in)
    return SceneArrays(garment_vertices=g.vertices + shift, garment_faces=np.asarray(g.faces), rest_corners=corners,
                       material=g.material, material_frames=g.material_frames(), weft_scale=g.weft_rest_scale(),
                       body_frames=verts, body_faces=np.asarray(s.body.faces),
                       fps=float(s.motion.fps), lead_frames=lead, body_face_part=parts,
                       poses=np.asarray(motion.poses).reshape(motion.frame_count, 24, 3),
                       trans=np.asarray(motion.trans).reshape(motion.frame_count, 3), garment_shift=np.asarray(shift))


def batch_arrays(scenes: list, lead_in: float, device: str | None = None) -> list[SceneArrays]:
    """:func:`scene_arrays` of every scene (those given as :class:`SceneArrays` kept), with the body
    posed once per distinct (body model, shape, motion) (a dataset simulates each motion under
    several garments). On a CUDA ``device`` (with torch's CUDA) the posings run there in float64,
    one after another; else on host threads (numpy lets go of the interpreter lock), each with one
    BLAS thread: at 252 scenes of 309 frames the host took 22.7 s on 16 cores (2026-11-27, H200
    host) before the first frame, the GPU idle."""
    keys, todo = [], {}
    for s in scenes:
        if isinstance(s, SceneArrays):
            keys.append(None)
            continue
        key = (id(s.body), np.asarray(s.betas, dtype=np.float64).tobytes(), id(s.motion))
        keys.append(key)
        todo.setdefault(key, s)
    if todo and torch_cuda(device):
        import torch

        modules: dict[int, object] = {}
        posed = {}
        for k, sc in todo.items():
            if id(sc.body) not in modules:
                modules[id(sc.body)] = sc.body.torch(dtype=torch.float64, device=device)
            posed[k] = _posed_body(sc, lead_in, modules[id(sc.body)])
        del modules
        torch.cuda.empty_cache()  # give torch's cached blocks back before warp sizes the batch on free memory
    else:
        from threadpoolctl import threadpool_limits

        threads = max(1, min(16, os.cpu_count() or 1))
        with threadpool_limits(limits=1, user_api="blas"), ThreadPoolExecutor(threads) as pool:
            posed = dict(zip(todo, pool.map(lambda sc: _posed_body(sc, lead_in), todo.values()), strict=True))
    return [s if k is None else scene_arrays(s, lead_in, posed[k]) for s, k in zip(scenes, keys, strict=True)]


def frame_schedule(config: RunConfig, lead: int, n_motion: int, fps: float) -> tuple[list[float], int]:
    """The body source frame (fractional: interpolated) of every simulated frame, and the first
    recorded frame: settle at rest, lead-in, settle in the first pose, ramp, then the motion.

    Args:
        config: the run's phases.
        lead: lead-in frames at the start of the body frames.
        n_motion: body frames in all (lead-in included).
        fps: frame rate.
    """
    ramp, motion_from = config.ramp_frames(fps)
    schedule = ([0.0] * config.settle_rest + [float(i) for i in range(1, lead + 1)] + [float(lead)] * config.settle_pose
                + [lead + i * i / (2.0 * ramp) for i in range(1, ramp + 1)]
                + [float(i) for i in range(lead + motion_from + 1, n_motion)])
    # the first recorded frame is motion frame ``motion_from``: the last of the ramp (or of the pose settle)
    return schedule, config.settle_rest + lead + config.settle_pose + ramp - 1


def settled_frame(config: RunConfig) -> int:
    """The simulated frame at whose end the garment is at rest in the body's rest pose: the last frame
    before the lead-in (what :attr:`SceneResult.settled` holds)."""
    return config.settle_rest - 1


def body_at(frames: np.ndarray, src: float) -> np.ndarray:
    """Body vertices at fractional frame ``src`` of ``frames`` [N, B, 3] (linear between frames)."""
    i0 = int(np.floor(src))
    w = src - i0
    return frames[i0] if w == 0 else (1 - w) * frames[i0] + w * frames[i0 + 1]


def simulate(scenes: list[Scene | SceneArrays], config: RunConfig = RunConfig(), device: str | None = None,
             progress=None, probes: tuple = ()) -> list[SceneResult]:
    """Run a batch of scenes in one model (one set of launches); see the module doc for the phases.

    All scenes' motions must have the same frame count, lead-in and frame rate (batch them by
    length). ``progress(frame, frame_count)`` is called after every frame; ``probes``
    (:mod:`datagen.sim.probes`) are given to the solver.
    """
    if not scenes:
        raise InputError("no scenes to simulate")
    t_setup = time.perf_counter()
    arrays = batch_arrays(list(scenes), config.lead_in, warp_device(device))
    t_posed = time.perf_counter()
    fps = {a.fps for a in arrays}
    lengths = {(len(a.body_frames), a.lead_frames) for a in arrays}
    if len(fps) > 1 or len(lengths) > 1:
        raise InputError(f"a batch needs one frame rate and one length; got fps {sorted(fps)}, "
                         f"(frames, lead-in frames) {sorted(lengths)}")
    fps = fps.pop()
    check_device_memory(arrays, device)
    builder = ClothModelBuilder()
    body_frames = []
    for k, a in enumerate(arrays):
        builder.add_cloth(a.garment_vertices, a.garment_faces, material_name=a.material, scene=k,
                          material_frames=a.material_frames, weft_scale=a.weft_scale, rest_corners=a.rest_corners)
        builder.add_body(a.body_frames[0], a.body_faces, scene=k, face_part=a.body_face_part)
        body_frames.append(a.body_frames)
    lead = arrays[0].lead_frames
    try:
        t_built = time.perf_counter()
        model = builder.finalize(device)
        t_model = time.perf_counter()
        solver = make_solver(config.solver_name, model, config.solver, probes=probes)
        metrics = Metrics(model)
    except RuntimeError as exc:  # warp: "Failed to allocate ..." when the estimate was too low
        if "alloc" not in str(exc).lower() and "memory" not in str(exc).lower():
            raise
        raise SimulationError(f"the device ran out of memory building a batch of {len(arrays)} scenes "
                              f"({sum(len(a.garment_vertices) for a in arrays):,} garment vertices): {exc}. "
                              f"{MEMORY_ADVICE}") from exc
    log.info("set-up of %d scenes: %d bodies posed in %.1f s, the model in %.1f s, the solver and metrics in %.1f s",
             len(arrays), len({id(a.body_frames) for a in arrays}), t_posed - t_setup, t_model - t_built,
             time.perf_counter() - t_model)
    state_a, state_b = ClothState.from_model(model), ClothState.from_model(model)
    n_motion = len(body_frames[0])
    ramp, motion_from = config.ramp_frames(fps)
    if lead + motion_from >= n_motion:
        raise InputError(f"the motion has {n_motion - lead} frames; the ramp of {config.ramp:g} s plays {motion_from} "
                         f"of them before recording starts: give it more frames or a shorter ramp")
    schedule, recorded_from = frame_schedule(config, lead, n_motion, fps)
    control = BodyControl.from_numpy(model, np.concatenate([b[0] for b in body_frames]))
    solver.reset_body(control)
    series = {k: [] for k in METRIC_NAMES}
    failure: list[Failure | None] = [None] * len(scenes)
    failure_frame = [-1] * len(scenes)
    positions = []
    settled_at, settled = settled_frame(config), None
    start = time.perf_counter()
    dt = 1.0 / fps

    def posed(src: float) -> np.ndarray:
        return np.concatenate([body_at(b, src) for b in body_frames])

    # the next frame's bodies are interpolated on a thread while the device steps this one (numpy
    # lets go of the interpreter lock for it): at 252 scenes that is 40 MB and tens of ms a frame
    prefetch = ThreadPoolExecutor(1)
    upcoming = prefetch.submit(posed, schedule[0]) if schedule else None
    try:
        frame_seconds: list[float] = []
        for f, _src in enumerate(schedule):
            t_frame = time.perf_counter()
            control.set(upcoming.result())
            if f + 1 < len(schedule):
                upcoming = prefetch.submit(posed, schedule[f + 1])
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
                        if config.freeze_failed:
                            solver.freeze(state_a, s)
            if f == settled_at:
                settled = state_a.positions.numpy().copy()
            if f >= recorded_from:
                positions.append(state_a.positions.numpy().copy())  # on the CPU .numpy() is a view of the buffer
            frame_seconds.append(time.perf_counter() - t_frame)
            typical = float(np.median(frame_seconds[-30:]))
            if f >= 10 and frame_seconds[-1] > max(10.0, 10.0 * typical):
                log.warning("frame %d took %.1f s (typical %.2f s; cloth-cloth contact lists %d per element, grown %d "
                            "times)", f, frame_seconds[-1], typical, getattr(solver, "capacity", 0),
                            getattr(solver, "contact_growths", 0))
            if progress:
                progress(f + 1, len(schedule))
    finally:
        prefetch.shutdown(cancel_futures=True)
    seconds = time.perf_counter() - start
    pos = np.stack(positions) if positions else np.zeros((0, model.particle_count, 3), np.float32)
    out = []
    scene_of = model.host.particle_scene
    first = lead + motion_from  # the body frame of the first recorded frame (a whole frame: no interpolation)
    for s, a in enumerate(arrays):
        sel = scene_of == s
        rec = slice(first, first + len(pos))
        out.append(SceneResult(positions=pos[:, sel], faces=np.asarray(a.garment_faces),
                               body_vertices=np.asarray(a.body_frames[rec], np.float32),
                               poses=None if a.poses is None else np.asarray(a.poses[rec]),
                               trans=None if a.trans is None else np.asarray(a.trans[rec]), fps=fps,
                               recorded_from=recorded_from, motion_from=motion_from,
                               metrics={k: np.array([v[s] for v in series[k]]) for k in METRIC_NAMES},
                               failure=failure[s], failure_frame=failure_frame[s], seconds=seconds,
                               settled=None if settled is None else
                               (settled[sel] - a.garment_shift).astype(np.float32)))
    return out
