"""SHA-256 digests of the cloth solver's final positions and velocities on the physics tests' scenes (CPU).

A refactoring of the simulator that must not change a single bit (the kernels' interface, the
solver's configuration, its probes) is checked by running this before and after and comparing the
JSON: every digest equal. The scenes are those of ``tests/sim/test_physics.py`` (free fall, the
hanging strips, a woven preset strip with the global step, rest on a plane, the slopes, the belt,
the sphere drop, overlapping body parts, the crease, the cloth folding on itself with growing
contact buffers, the band on a pole, Cusick's drape) plus a short walking T-shirt on the default
body (self-contact, body contact, projection, untangling) run through ``datagen.sim.scene.simulate``,
some with fewer frames than the tests so that all run in a few minutes on one CPU core. Every
scene uses the production solver settings but for what its test changes.

    python -m benchmarks sim-positions-digest [--out digests.json] [--against before.json] [--only NAME,NAME] [--skip-tshirt]

Prints one line per scene (name, frames, seconds, digests) and the JSON of {scene: {positions,
velocities (the T-shirt: metrics), frames, vertices}}; ``--out`` writes that JSON too; ``--against``
compares with an earlier run's JSON and exits 1 when a digest differs.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time

import numpy as np

FPS = 30
DT = 1.0 / FPS


def _config(**overrides):
    """The production :class:`~datagen.sim.solver.SolverConfig` with ``overrides`` (flat, historical names)."""
    from datagen.sim.solver import SolverConfig

    return SolverConfig(**overrides)


def _digest(a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    return hashlib.sha256(a.dtype.str.encode() + str(a.shape).encode() + a.tobytes()).hexdigest()


def _grid(nx: int, nz: int, dx: float, *, y: float = 0.0, centre=(0.0, 0.0)):
    xs = centre[0] + (np.arange(nx) - (nx - 1) / 2) * dx
    zs = centre[1] + (np.arange(nz) - (nz - 1) / 2) * dx
    X, Z = np.meshgrid(xs, zs, indexing="ij")
    v = np.stack([X.ravel(), np.full(X.size, float(y)), Z.ravel()], 1)
    faces = []
    for i in range(nx - 1):
        for j in range(nz - 1):
            a, b, c, d = i * nz + j, (i + 1) * nz + j, (i + 1) * nz + j + 1, i * nz + j + 1
            faces += [[a, d, c], [a, c, b]]
    return v, np.array(faces)


def _plane(half: float):
    v = np.array([[-half, 0.0, -half], [-half, 0.0, half], [half, 0.0, half], [half, 0.0, -half]])
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def _rot_z(deg: float) -> np.ndarray:
    a = np.radians(deg)
    return np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])


def _icosphere(radius: float):
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=3, radius=radius)
    return np.asarray(s.vertices, dtype=np.float64), np.asarray(s.faces, dtype=np.int64)


def _materials():
    from datagen.materials import Material

    cotton = Material(name="cotton-test", density=0.13, stretch_warp=1800.0, stretch_weft=1200.0, shear=60.0,
                      poisson=0.3, bending=1.2e-5, friction=0.45, thickness=0.0015)
    strip = Material(name="strip", density=0.18, stretch_warp=60.0, stretch_weft=60.0, shear=15.0, poisson=0.0,
                     bending=1e-7, friction=0.0, thickness=0.0015, damping=0.002)
    rough = Material(name="rough", density=0.13, stretch_warp=1800.0, stretch_weft=1200.0, shear=60.0,
                     poisson=0.3, bending=1.2e-5, friction=0.5, thickness=0.0015)
    belt = Material(name="belt-test", density=0.2, stretch_warp=120.0, stretch_weft=120.0, shear=20.0, poisson=0.3,
                    bending=1e-6, friction=0.5, thickness=0.0015)
    band = Material(name="band", density=0.13, stretch_warp=1800.0, stretch_weft=1200.0, shear=60.0,
                    poisson=0.3, bending=1.2e-5, friction=0.45, thickness=0.0015)
    return {"cotton": cotton, "strip": strip, "rough": rough, "belt": belt, "band": band}


def _build(cloth, material, *, body=None, pinned=None, frames=None, weft_scale=None, body_parts=None):
    from datagen.sim.model import ClothModelBuilder

    b = ClothModelBuilder()
    b.add_cloth(cloth[0], cloth[1], material_name=material, pinned=pinned, material_frames=frames,
                weft_scale=weft_scale)
    if body is not None:
        b.add_body(body[0], body[1], face_part=body_parts)
    return b.finalize("cpu")


def _run(model, config, frames: int, *, positions=None, body_at=None):
    """``frames`` steps of 1/30 s (the body static, or at ``body_at(frame)`` [B, 3] each frame):
    the final positions and velocities (float32) and the contact growths."""
    from datagen.sim.solver import SolverVBD
    from datagen.sim.state import BodyControl, ClothState

    s0, s1 = ClothState.from_model(model, positions), ClothState.from_model(model, positions)
    control = BodyControl.from_numpy(model, model.host.body_rest)
    solver = SolverVBD(model, config)
    for k in range(frames):
        if body_at is not None:
            control.set(body_at(k).astype(np.float32))
        solver.step(s0, s1, control, DT)
        s0, s1 = s1, s0
    x, v = s0.numpy()
    return np.array(x, np.float32), np.array(v, np.float32)


# --------------------------------------------------------------------------------------------------
# the scenes: name -> () -> (positions, velocities, frames)


def free_fall():
    M = _materials()
    return (*_run(_build(_grid(3, 3, 0.05), M["cotton"]), _config(air_drag=0.0, self_collision=True), FPS), FPS)


def _strip_mesh(nx, ny, dx):
    X, Y = np.meshgrid(np.arange(nx) * dx, -np.arange(ny) * dx, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)
    faces = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, c, d = i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1
            faces += [[a, b, c], [a, c, d]]
    return v, np.array(faces)


def hanging_strip(weft_scale: float = 1.0, frames: int = 45):
    M = _materials()
    v, f = _strip_mesh(6, 51, 0.02)
    top = np.flatnonzero(np.isclose(v[:, 1], 0.0))
    if weft_scale == 1.0:
        fr = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), (len(f), 1, 1))
        model, start = _build((v, f), M["strip"], pinned=top, frames=fr), None
    else:
        fr = np.tile(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]), (len(f), 1, 1))
        model = _build((v, f), M["strip"], pinned=top, frames=fr, weft_scale=np.full(len(f), weft_scale))
        start = v * np.array([1.0, weft_scale, 1.0])
    return (*_run(model, _config(self_collision=False), frames, positions=start), frames)


def strip_weft_scaled():
    return hanging_strip(0.8, 30)


def _preset_strip(name: str, frames: int, **overrides):
    from datagen.materials import MATERIALS

    nx, ny, dx = 6, 51, 0.01
    X, Y = np.meshgrid(np.arange(nx) * dx, -np.arange(ny) * dx, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)
    f = np.array([[i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1] for i in range(nx - 1) for j in range(ny - 1)]
                 + [[i * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1] for i in range(nx - 1) for j in range(ny - 1)])
    top = np.flatnonzero(np.isclose(v[:, 1], 0.0))
    fr = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), (len(f), 1, 1))
    model = _build((v, f), MATERIALS[name], pinned=top, frames=fr)
    return (*_run(model, _config(self_collision=False, air_drag=0.0, **overrides), frames), frames)


def preset_strip_denim():
    return _preset_strip("denim", 30)


def preset_strip_cotton_sweeps_alone():
    return _preset_strip("cotton", 20, global_iterations=0)


def rest_on_plane():
    M = _materials()
    r = M["cotton"].thickness + _config().body_margin
    return (*_run(_build(_grid(5, 5, 0.03, y=r), M["cotton"], body=_plane(3.0)), _config(), 45), 45)


def tilted_plane(angle: float = 35.0, frames: int = 30, **overrides):
    M = _materials()
    r = M["rough"].thickness + _config().body_margin
    R = _rot_z(angle)
    v0, f = _grid(5, 5, 0.03, y=r)
    pv, pf = _plane(3.0)
    model = _build((v0 @ R.T, f), M["rough"], body=(pv @ R.T, pf))
    return (*_run(model, _config(**overrides), frames), frames)


def tilted_plane_20():
    return tilted_plane(20.0)


def friction_pressure_cap():
    return tilted_plane(20.0, 30, friction_pressure=0.5)


def belt():
    M = _materials()
    r = M["belt"].thickness + _config().body_margin
    nx, nz, dx, L, speed = 51, 6, 0.01, 0.5, 0.003
    X, Z = np.meshgrid(np.arange(nx) * dx, np.arange(nz) * dx, indexing="ij")
    v = np.stack([X.ravel(), np.full(X.size, r), Z.ravel()], 1)
    f = np.array([[i * nz + j, i * nz + j + 1, (i + 1) * nz + j + 1] for i in range(nx - 1) for j in range(nz - 1)]
                 + [[i * nz + j, (i + 1) * nz + j + 1, (i + 1) * nz + j] for i in range(nx - 1) for j in range(nz - 1)])
    pinned = np.flatnonzero(np.isclose(v[:, 0], 0.0))
    fr = np.tile(np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]), (len(f), 1, 1))
    model = _build((v, f), M["belt"], body=_plane(3.0), pinned=pinned, frames=fr)
    rest = model.host.body_rest
    frames = 30
    return (*_run(model, _config(self_collision=False), frames,
                  body_at=lambda k: rest + np.array([speed * (k + 1) * DT, 0.0, 0.0])), frames)


def sphere_drop():
    M = _materials()
    return (*_run(_build(_grid(21, 21, 0.025, y=0.21), M["cotton"], body=_icosphere(0.2)), _config(), 30), 30)


def overlapping_spheres():
    M = _materials()
    v, f = _icosphere(0.2)
    body = (np.concatenate([v - [0.1, 0.0, 0.0], v + [0.1, 0.0, 0.0]]), np.concatenate([f, f + len(v)]))
    crease = np.sqrt(0.2 ** 2 - 0.1 ** 2)
    model = _build(_grid(3, 3, 0.004, y=crease - 0.012), M["cotton"], body=body)
    return (*_run(model, _config(gravity=(0.0, 0.0, 0.0), body_stiffness=1.0e-4), 1), 1)


def crease_two_parts():
    M = _materials()
    v, f = _icosphere(0.2)
    body = (np.concatenate([v - [0.15, 0.0, 0.0], v + [0.15, 0.0, 0.0]]), np.concatenate([f, f + len(v)]))
    crease = np.sqrt(0.2 ** 2 - 0.15 ** 2)
    model = _build(_grid(9, 3, 0.01, y=crease + 0.03), M["cotton"], body=body, body_parts=np.repeat([0, 1], len(f)))
    return (*_run(model, _config(), 30), 30)


def _small_sphere_model():
    M = _materials()
    v0, f = _grid(25, 25, 0.025, y=0.105)
    centre = [int(np.argmin(np.linalg.norm(v0[:, [0, 2]], axis=1)))]
    return _build((v0, f), M["cotton"], body=_icosphere(0.1), pinned=centre)


def fold_on_itself():
    """The cloth folding onto itself around a small sphere, from contact buffers of 1 (grown and redone)."""
    return (*_run(_small_sphere_model(), _config(contact_capacity=1), 20), 20)


def fold_on_itself_20_substeps():
    return (*_run(_small_sphere_model(), _config(substeps=20), 10), 10)


def band_on_cone():
    import trimesh

    M = _materials()
    taper, band_scale = 0.2, 0.81
    pole = trimesh.creation.cylinder(radius=0.05, height=0.6, sections=48)
    a = np.radians(-90)
    Rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    pv = np.asarray(pole.vertices) @ Rx.T
    y_band = 0.18
    pv[:, [0, 2]] *= ((0.05 - taper * (pv[:, 1] - y_band)) / 0.05)[:, None]
    n_around, n_up, R = 32, 11, 0.06
    th = np.arange(n_around) * 2 * np.pi / n_around
    ys = np.linspace(0.0, 0.2, n_up)
    v = np.array([[(R - taper * (y - y_band)) * np.cos(t), y, (R - taper * (y - y_band)) * np.sin(t)]
                  for y in ys for t in th])
    faces = []
    for j in range(n_up - 1):
        for i in range(n_around):
            a0, b0 = j * n_around + i, j * n_around + (i + 1) % n_around
            faces += [[a0, b0 + n_around, b0], [a0, a0 + n_around, b0 + n_around]]
    faces = np.array(faces)
    centre = v[faces].mean(1)
    ang = np.arctan2(centre[:, 2], centre[:, 0])
    weft = np.stack([-np.sin(ang), np.zeros(len(faces)), np.cos(ang)], 1)
    fr = np.stack([weft, np.tile([0.0, 1.0, 0.0], (len(faces), 1))], 1)
    band = centre[:, 1] > 0.16
    model = _build((v, faces), M["band"], body=(pv, np.asarray(pole.faces)), frames=fr,
                   weft_scale=np.where(band, band_scale, 1.0))
    return (*_run(model, _config(), 20), 20)


def cusick():
    """Cusick's drape (``benchmarks/cusick.py``'s set-up: a 30 cm disc over an 18 cm support with
    a rounded rim), cotton, 2.5 cm edges, 0.5 s."""
    import trimesh
    from scipy.spatial import Delaunay

    from datagen.materials import MATERIALS

    radius, edge, support, rr = 0.15, 0.025, 0.09, 0.005
    pts = [np.zeros((1, 2))]
    rings = int(np.ceil(radius / edge))
    for k in range(1, rings + 1):
        r = radius * k / rings
        n = max(6, int(round(2 * np.pi * r / edge)))
        a = (np.arange(n) + 0.5 * (k % 2)) * 2 * np.pi / n
        pts.append(np.stack([r * np.cos(a), r * np.sin(a)], 1))
    p = np.concatenate(pts)
    tri = Delaunay(p).simplices
    v = np.stack([p[:, 0], np.zeros(len(p)), p[:, 1]], 1)
    nrm = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    tri[nrm[:, 1] < 0] = tri[nrm[:, 1] < 0][:, [0, 2, 1]]
    mat = MATERIALS["cotton"]
    v[:, 1] += mat.thickness + _config().body_margin + 0.001
    prof = [[0.0, 0.0]]
    for a in np.linspace(0.5 * np.pi, 0.0, 9):
        prof.append([support - rr + rr * np.cos(a), -rr + rr * np.sin(a)])
    prof += [[support, -0.4], [0.0, -0.4]]
    mesh = trimesh.creation.revolve(np.array(prof)[::-1], sections=96)
    mesh = trimesh.Trimesh(np.asarray(mesh.vertices)[:, [0, 2, 1]], np.asarray(mesh.faces), process=True)
    if mesh.volume < 0:
        mesh.invert()
    fr = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]), (len(tri), 1, 1))
    model = _build((v, tri), mat, body=(np.asarray(mesh.vertices), np.asarray(mesh.faces)), frames=fr)
    return (*_run(model, _config(), 15), 15)


def walking_tshirt():
    """A T-shirt (4 cm edges) on the default body, regular shape, walking: ``scene.simulate`` with
    2 frames of rest, a 0.1 s lead-in, a 0.2 s ramp and 3 recorded frames; the digests are of the
    recorded frames' positions and of every metric over every frame (no velocities: the driver
    does not return them)."""
    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.garment.types import make_garment
    from datagen.motion.library import make_motion
    from datagen.sim.scene import RunConfig, Scene, simulate

    body = default_body()
    betas = resolve_betas(body, body="regular")[0]
    garment = make_garment("tshirt", body, betas, seed=0, target_edge_length=0.04)
    config = RunConfig(settle_rest=2, lead_in=0.1, settle_pose=0, ramp=0.2, solver=_config())
    motion = make_motion("walk", seed=0, frames=config.motion_frames(3, FPS), fps=FPS)
    (res,) = simulate([Scene(garment=garment, body=body, betas=betas, motion=motion)], config, device="cpu")
    metrics = np.concatenate([np.asarray(res.metrics[k], np.float64).ravel() for k in sorted(res.metrics)])
    return res.positions.astype(np.float32), metrics, len(res.metrics["nan"]), "metrics"


SCENES = {f.__name__: f for f in (
    free_fall, hanging_strip, strip_weft_scaled, preset_strip_denim, preset_strip_cotton_sweeps_alone, rest_on_plane,
    tilted_plane, tilted_plane_20, friction_pressure_cap, belt, sphere_drop, overlapping_spheres, crease_two_parts,
    fold_on_itself, fold_on_itself_20_substeps, band_on_cone, cusick, walking_tshirt)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="", help="write the digests as JSON here too")
    ap.add_argument("--only", default="", help="comma-separated scene names (default: all)")
    ap.add_argument("--against", default="", help="an earlier run's JSON: print which scenes differ, exit 1 if any")
    ap.add_argument("--skip-tshirt", action="store_true", help="leave out the walking T-shirt (the slowest)")
    args = ap.parse_args(argv)
    import warp as wp

    if hasattr(wp.config, "log_level"):  # warp's per-module load lines off the console
        wp.config.log_level = max(wp.config.log_level, 30)
    else:
        wp.config.quiet = True
    names = [n for n in (args.only.split(",") if args.only else SCENES) if n]
    unknown = sorted(set(names) - set(SCENES))
    if unknown:
        raise SystemExit(f"unknown scene(s) {', '.join(unknown)}; known: {', '.join(SCENES)}")
    if args.skip_tshirt and "walking_tshirt" in names:
        names.remove("walking_tshirt")
    out = {}
    for name in names:
        t = time.perf_counter()
        x, v, frames, *second = SCENES[name]()
        second = second[0] if second else "velocities"
        out[name] = {"positions": _digest(x), second: _digest(v), "frames": int(frames), "vertices": int(x.shape[-2])}
        print(f"{name:36s} {frames:3d} frames {time.perf_counter() - t:7.1f} s  x {out[name]['positions'][:16]}  "
              f"{second[0]} {out[name][second][:16]}", flush=True)
    text = json.dumps(out, indent=1, sort_keys=True)
    print(text)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text + "\n")
    if args.against:
        with open(args.against) as fh:
            before = json.load(fh)
        differ = [n for n in out if n in before and before[n] != out[n]]
        missing = [n for n in out if n not in before]
        print(f"against {args.against}: {len(out) - len(differ) - len(missing)} of {len(out)} scenes bitwise equal"
              + (f"; differ: {', '.join(differ)}" if differ else "") + (f"; not in it: {', '.join(missing)}" if missing else ""))
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
