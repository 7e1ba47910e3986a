"""``drape simulate``: one garment on one body doing one motion, with per-frame metrics."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from datagen.cli import args as checks
from datagen.cli.motion import MOTION_BYTES_PER_FRAME
from datagen.errors import InputError
from datagen.geometry.topology import unique_edges


GARMENT_BYTES_PER_FRAME = 20_000 * 3 * 4 * 2
"""Host memory of a recorded garment frame [bytes]: up to 20,000 vertices (the largest garment drape
builds), float32 positions, a copy when they are stacked."""


def register(sub, formatter) -> None:
    p = sub.add_parser("simulate", formatter_class=formatter, help="drape a garment on a moving body (warp VBD)",
                       description="Make a garment on a body in its rest pose, let it settle, move the body into "
                       "the motion's first pose, and simulate the motion with body and self-collision. Prints "
                       "progress and the per-frame metrics summary; writes positions and metrics to an .npz.",
                       epilog="examples:\n  drape simulate --garment tshirt --body regular --motion walk --frames 120 "
                       "--out run.npz\n  drape simulate --pattern top:3 --body regular --motion walk --frames 60 --out top.npz")
    p.add_argument("--garment", default="tshirt", help="garment type (`drape garment list`)")
    p.add_argument("--pattern", default=None, metavar="NAME[:SEED]",
                   help="a sewing-pattern program instead of --garment (`drape garment list`), its design drawn by "
                   "SEED (default 0): placed around the body, sewn and settled at rest, then simulated")
    p.add_argument("--garment-seed", type=checks.seed, default=0, help="seed of the garment's style parameters")
    p.add_argument("--body", default="regular", help="body shape preset: thin, regular, fat")
    p.add_argument("--motion", default="walk", help="motion label (`drape motion list`)")
    p.add_argument("--motion-seed", type=checks.seed, default=0, help="seed of the motion's style parameters")
    p.add_argument("--frames", type=checks.count, default=120, help="recorded frames")
    p.add_argument("--fps", type=checks.fps, default=30.0, help="frame rate")
    p.add_argument("--substeps", type=checks.integer(1, 1000), default=None, help="substeps per frame (default: the solver's, 10)")
    p.add_argument("--iterations", type=checks.integer(1, 1000), default=None, help="sweeps per substep (default: the solver's, 20)")
    p.add_argument("--no-self-collision", action="store_true", help="turn cloth self-collision off")
    p.add_argument("--device", default="cpu", help="warp device: cpu or cuda (cuda:N)")
    p.add_argument("--out", required=True, type=checks.out_file(".npz"), help="output .npz: the garment and body of every recorded frame, the garment's rest mesh "
                   "and panels, the body's rig, metric_* per simulated frame (`drape export usd` and `drape preview` "
                   "read it as it is)")
    p.set_defaults(func=_cmd_simulate)


def _cmd_simulate(args) -> int:
    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.garment.types import make_garment
    from datagen.motion.library import make_motion
    from datagen.sim.device import warp_device
    from datagen.sim.scene import RunConfig, Scene, simulate
    from datagen.sim.settings import SelfContactConfig, SolverConfig, StepConfig

    out = Path(args.out)
    if out.suffix != ".npz":
        raise InputError(f"--out must end in .npz, got {out.name!r}")
    if not out.parent.exists():
        raise InputError(f"the folder {out.parent} does not exist")
    if args.frames < 1:
        raise InputError(f"--frames must be >= 1, got {args.frames}")
    if not 1 <= args.fps <= 240:
        raise InputError(f"--fps must be between 1 and 240 frames per second, got {args.fps:g}")
    device = warp_device(args.device)
    model = default_body()
    betas = resolve_betas(model, body=args.body)[0]
    given = {k: v for k, v in (("substeps", args.substeps), ("iterations", args.iterations)) if v is not None}
    config = RunConfig(solver=SolverConfig(steps=StepConfig(**given),
                                           self_contact=SelfContactConfig(enabled=not args.no_self_collision)))
    frames = config.motion_frames(args.frames, args.fps)  # simulated: the lead-in and settling included
    # the posed body of every frame (float64 with the skinning's copies), the motion, the recorded garment
    checks.check_memory(frames * (model.vertex_count * 3 * 8 * 4 + MOTION_BYTES_PER_FRAME + GARMENT_BYTES_PER_FRAME),
                        f"--frames {args.frames} ({frames} simulated)", "simulate fewer frames")
    sewn = None
    if args.pattern:
        garment, sewn, name = _sewn_pattern(args.pattern, model, betas, config, device)
        if sewn.failure is not None:
            print(f"the {name} pattern could not be sewn: {sewn.failure}")
            return 1
        garment = sewn.garment
    else:
        name = args.garment
        garment = make_garment(args.garment, model, betas, seed=args.garment_seed)
    motion = make_motion(args.motion, seed=args.motion_seed, frames=config.motion_frames(args.frames, args.fps),
                         fps=args.fps)
    edges = unique_edges(garment.faces)
    edge = float(np.median(np.linalg.norm(garment.vertices[edges[:, 0]] - garment.vertices[edges[:, 1]], axis=1)))
    substeps = config.solver.steps.substeps_for(1.0 / args.fps, edge)  # what the solver runs per frame
    print(f"{name} ({garment.vertex_count} vertices, {garment.material.name}) on {args.body}, "
          f"{args.motion} {args.frames} frames at {args.fps:g} fps, {substeps} substeps x "
          f"{config.solver.steps.iterations} "
          f"iterations, self-collision {'off' if args.no_self_collision else 'on'}, device {device}", flush=True)
    t0 = time.perf_counter()

    def progress(done: int, total: int) -> None:
        if done % 10 == 0 or done == total:
            el = time.perf_counter() - t0
            print(f"  frame {done}/{total}  {el:.1f} s  {1000 * el / done:.0f} ms/frame", flush=True)

    result = simulate([Scene(garment=garment, body=model, betas=betas, motion=motion)], config, device=device,
                      progress=progress)[0]
    summary = result.summary()
    # the file is a whole animation (what `drape export` and `drape preview` read, nothing made again):
    # the run's arrays, the garment's rest mesh and panels, the body's rig and what the run was made of
    extra = {} if sewn is None else {"garment_face_uv": garment.face_uv.astype(np.float32),
                                     "garment_rest_uv": garment.rest_uv.astype(np.float32),
                                     "sewing_gap": sewn.gap.astype(np.float32), "pattern": garment.pattern or ""}
    result.save(out, garment_rest=garment.vertices.astype(np.float32), region=garment.vertex_region,
                region_names=np.array(garment.region_names), body_faces=np.asarray(model.faces),
                rest_joints=np.asarray(model.rest_joints(betas))[0], parents=np.asarray(model.parents),
                rest_body_vertices=np.asarray(model.shaped(betas))[0].astype(np.float32),
                skin_weights=np.asarray(model.weights, np.float32), config=json.dumps(config.as_dict()),
                garment=name, garment_seed=args.garment_seed, motion=args.motion, **extra,
                motion_seed=args.motion_seed, body=args.body, material=json.dumps(garment.material.as_dict()))
    frames = len(result.metrics["nan"])
    print(f"wrote {out}: {result.positions.shape[0]} recorded frames of {frames} simulated, "
          f"{1000 * result.seconds / frames:.0f} ms/frame")
    for k, v in summary.items():
        print(f"  {k:34s} {v}")
    return 0 if result.failure is None else 1


def _sewn_pattern(spec: str, model, betas, config, device):
    """The pattern garment ``NAME[:SEED]`` made on the body at rest and sewn there: (the placed
    garment, its :class:`~datagen.sim.sewing.SewResult`, the name printed)."""
    from datagen.body.measurements import measure_body
    from datagen.body.skeleton import face_parts
    from datagen.garment.pattern.garment import pattern_garment
    from datagen.garment.pattern.programs import make_pattern
    from datagen.sim.sewing import PLACEMENT, sew

    name, _, seed = spec.partition(":")
    try:
        seed = int(seed or 0)
    except ValueError:
        raise InputError(f"--pattern takes NAME[:SEED] with an integer seed, got {spec!r}") from None
    rest = np.asarray(model.shaped(betas))[0]
    placed = pattern_garment(make_pattern(name, seed, measure_body(model, betas)), rest, np.asarray(model.faces),
                             mode=PLACEMENT, seed=seed, betas=betas)
    print(f"pattern {name}:{seed}: {placed.vertex_count} vertices in {len(placed.region_names)} panels, "
          f"{len(placed.stitch_pairs)} stitched pairs; sewing on the body at rest", flush=True)
    r = sew(placed, rest, np.asarray(model.faces), body_face_part=face_parts(model.weights, model.faces),
            config=config.sewing, solver=config.solver, thresholds=config.thresholds, device=device)
    print(f"  sewn in {r.sew_frames} frames (largest gap {1000 * r.gap[0]:.0f} mm placed, "
          f"{1000 * r.gap[max(r.sew_frames, 0)]:.2f} mm sewn), static after {r.settle_frames} frames of settling, "
          f"{r.garment.vertex_count} vertices welded, {r.seconds:.1f} s", flush=True)
    return placed, r, f"pattern:{name}:{seed}"
