"""The Cusick drape test of every material preset, at the production solver settings.

A 30 cm disc of the fabric lies flat, centred over an 18 cm support disc (BS 5058 / ISO 9073-9;
Cusick, J. Textile Inst. 59, 1968), and drapes under gravity. The drape coefficient is the share of
the annulus outside the support that the draped fabric's shadow (seen from above) still covers:
DC = (S - S_support) / (S_specimen - S_support); nodes are the folds around the rim (the maxima
of the shadow's radius over the angle). The support is a cylinder whose top rim is rounded by 5 mm
(a sharp rim is an edge of zero radius, which a penalty contact cannot hold cloth on).

    python -m benchmarks cusick [--presets cotton,denim] [--edge 0.015] [--seconds 3] [--picture docs/cusick.png]

Prints per preset: DC, nodes, the published range it is checked against, and whether it settled
(the largest vertex speed in the last frame).
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from datagen.materials import MATERIALS, drape_range
from datagen.sim.model import ClothModelBuilder
from datagen.sim.solver import SolverConfig, SolverVBD
from datagen.sim.state import BodyControl, ClothState

SPECIMEN_RADIUS = 0.15
SUPPORT_RADIUS = 0.09
RIM_ROUNDING = 0.005
FPS = 30


def disc_mesh(radius: float, edge: float):
    """A flat disc in y = 0 (normals +Y) with edges of about ``edge``: rings of points, Delaunay."""
    from scipy.spatial import Delaunay

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
    # orient every face's normal to +Y
    n = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    tri[n[:, 1] < 0] = tri[n[:, 1] < 0][:, [0, 2, 1]]
    return v, tri


def support_mesh(top: float = 0.0, height: float = 0.4):
    """A closed cylinder of radius SUPPORT_RADIUS with its top at ``top`` and a rounded top rim."""
    import trimesh

    rr = RIM_ROUNDING
    prof = [[0.0, top]]
    for a in np.linspace(0.5 * np.pi, 0.0, 9):
        prof.append([SUPPORT_RADIUS - rr + rr * np.cos(a), top - rr + rr * np.sin(a)])
    prof += [[SUPPORT_RADIUS, top - height], [0.0, top - height]]
    mesh = trimesh.creation.revolve(np.array(prof)[::-1], sections=96)
    v = np.asarray(mesh.vertices)[:, [0, 2, 1]]  # revolve is about Z: make Y the axis
    f = np.asarray(mesh.faces)
    mesh = trimesh.Trimesh(v, f, process=True)
    if mesh.volume < 0:
        mesh.invert()
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def shadow(x: np.ndarray, faces: np.ndarray, pixel: float = 0.001):
    """The area [m²] of the cloth's shadow on the XZ plane (its triangles rasterised), and the
    shadow's radius at 720 angles."""
    from matplotlib.path import Path

    n = int(np.ceil(2 * SPECIMEN_RADIUS / pixel)) + 2
    g = (np.arange(n) - n / 2 + 0.5) * pixel
    X, Z = np.meshgrid(g, g, indexing="ij")
    grid = np.stack([X.ravel(), Z.ravel()], 1)
    covered = np.zeros(len(grid), dtype=bool)
    p2 = x[:, [0, 2]]
    for t in faces:
        tri = p2[t]
        lo, hi = tri.min(0), tri.max(0)
        sel = np.flatnonzero((grid[:, 0] >= lo[0]) & (grid[:, 0] <= hi[0]) & (grid[:, 1] >= lo[1]) &
                             (grid[:, 1] <= hi[1]) & ~covered)
        if len(sel):
            covered[sel[Path(tri).contains_points(grid[sel], radius=1e-9)]] = True
    area = covered.sum() * pixel**2
    pts = grid[covered]
    ang = np.arctan2(pts[:, 1], pts[:, 0])
    rad = np.linalg.norm(pts, axis=1)
    bins = ((ang + np.pi) / (2 * np.pi) * 720).astype(int) % 720
    r = np.zeros(720)
    np.maximum.at(r, bins, rad)
    return area, r


def count_nodes(r: np.ndarray) -> int:
    """Folds around the rim: maxima of the shadow radius over the angle (smoothed over 10°,
    prominence 5 mm)."""
    from scipy.signal import find_peaks

    k = 10
    rs = np.convolve(np.concatenate([r[-k:], r, r[:k]]), np.ones(2 * k + 1) / (2 * k + 1), mode="same")[k:-k]
    peaks, _ = find_peaks(np.concatenate([rs, rs[:60]]), prominence=0.005)
    return int(len({p % 720 for p in peaks}))


def drape(mat, edge: float, seconds: float, config: SolverConfig):
    v, f = disc_mesh(SPECIMEN_RADIUS, edge)
    clearance = mat.thickness + config.body_margin
    v[:, 1] += clearance + 0.001
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]), (len(f), 1, 1))  # weft X, warp -Z
    return drape_on_support(v, f, seconds, config, material_name=mat, material_frames=frames)


def drape_on_support(start: np.ndarray, f: np.ndarray, seconds: float, config: SolverConfig, **cloth):
    """Cloth ``start`` [V, 3] / ``f`` on the support (``cloth``: ``add_cloth``'s keywords) draped for
    ``seconds``: (positions [V, 3], faces, largest vertex speed at the end [m/s])."""
    bv, bf = support_mesh()
    b = ClothModelBuilder()
    b.add_cloth(start, f, **cloth)
    b.add_body(bv, bf)
    model = b.finalize("cpu")
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    control = BodyControl.from_numpy(model, model.host.body_rest)
    solver = SolverVBD(model, config)
    for _ in range(int(seconds * FPS)):
        solver.step(s0, s1, control, 1.0 / FPS)
        s0, s1 = s1, s0
    x, vel = s0.numpy()
    return x.astype(np.float64), f, float(np.linalg.norm(vel, axis=1).max())


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--presets", default=",".join(MATERIALS))
    ap.add_argument("--edge", type=float, default=0.015, help="edge length of the disc mesh [m] (garments: 1.3-2 cm)")
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--variant", default="", help="SolverConfig KEY=VALUE[,KEY=VALUE] for this run")
    ap.add_argument("--material", default="", help="Material KEY=VALUE[,...] applied to every preset (a sweep)")
    ap.add_argument("--picture", default="", help="write the settled shapes as a PNG")
    args = ap.parse_args(argv)

    def kv(spec, base):
        kw = {}
        for item in filter(None, spec.split(",")):
            k, _, val = item.partition("=")
            kind = type(getattr(base, k))
            kw[k] = (val.lower() in ("1", "true", "on")) if kind is bool else kind(val)
        return kw

    config = dataclasses.replace(SolverConfig(), **kv(args.variant, SolverConfig()))
    support = np.pi * SUPPORT_RADIUS**2
    specimen = np.pi * SPECIMEN_RADIUS**2
    print(f"Cusick drape: {2 * SPECIMEN_RADIUS * 100:g} cm specimen on a {2 * SUPPORT_RADIUS * 100:g} cm support "
          f"(rim rounded {RIM_ROUNDING * 1000:g} mm), edge {args.edge * 100:g} cm, {args.seconds:g} s, "
          f"{config.substeps} substeps x {config.iterations} sweeps, global step {config.global_iterations} CG "
          f"iterations, self-collision {'on' if config.self_collision else 'off'}")
    print(f"{'preset':<10} {'DC':>6} {'nodes':>6} {'range':>11} {'in range':>9} {'max speed m/s':>14} {'s':>6}")
    shapes = []
    for name in args.presets.split(","):
        mat = MATERIALS[name]
        mat = dataclasses.replace(mat, **kv(args.material, mat))
        t0 = time.perf_counter()
        x, f, speed = drape(mat, args.edge, args.seconds, config)
        area, r = shadow(x, f)
        dc = (area - support) / (specimen - support)
        lo, hi = drape_range(name)
        print(f"{name:<10} {dc:6.3f} {count_nodes(r):6d} {f'{lo:.2f}-{hi:.2f}':>11} {str(lo <= dc <= hi):>9} "
              f"{speed:14.4f} {time.perf_counter() - t0:6.1f}", flush=True)
        shapes.append((name, x, f, dc))
    if args.picture:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(3.0 * len(shapes), 6.0))
        for k, (name, x, f, dc) in enumerate(shapes):
            ax = fig.add_subplot(2, len(shapes), k + 1, projection="3d")
            ax.plot_trisurf(x[:, 0], x[:, 2], x[:, 1], triangles=f, color="#8fb3d9", edgecolor="none", shade=True)
            ax.set_box_aspect((1, 1, 0.6))
            ax.set_axis_off()
            ax.view_init(elev=25, azim=30)
            ax.set_title(f"{name}: DC {dc:.2f}")
            ax2 = fig.add_subplot(2, len(shapes), len(shapes) + k + 1)
            ax2.tripcolor(x[:, 0], x[:, 2], f, np.zeros(len(f)), cmap="Blues", vmin=-1, vmax=1)
            ax2.add_patch(plt.Circle((0, 0), SUPPORT_RADIUS, fill=False, ls="--", color="k"))
            ax2.add_patch(plt.Circle((0, 0), SPECIMEN_RADIUS, fill=False, ls=":", color="k"))
            ax2.set_aspect("equal")
            ax2.set_xlim(-0.16, 0.16)
            ax2.set_ylim(-0.16, 0.16)
            ax2.set_axis_off()
        fig.tight_layout()
        fig.savefig(args.picture, dpi=90)
        print(f"wrote {args.picture}")
