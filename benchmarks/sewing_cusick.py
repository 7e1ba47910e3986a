"""The Cusick drape test with the specimen cut as a flat circle panel: its rest state the 2D cut.

As ``python -m benchmarks cusick`` (30 cm disc on an 18 cm support, BS 5058 / ISO 9073-9), but the
disc is given to the simulator as a sewing-pattern panel: every face corner's 2D panel coordinate
(``ClothModelBuilder.add_cloth(rest_corners=..., grain=...)``, the warp along -Z as there), so its
reference shape, rest area, mass and flat hinges come from the cut, not from the 3D mesh it starts
as. The disc starts **bent** (a spherical bowl over the support, rim raised about ``--dome`` x its
radius, lengths along the surface kept), so a drape coefficient in range shows the cloth forgets its start shape.

    python -m benchmarks sewing-cusick [--presets cotton,denim] [--edge 0.015] [--seconds 3] [--dome 0.3]

Prints per preset: DC, nodes, the published range, whether it is in range, the largest vertex speed
at the end.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.cusick import SPECIMEN_RADIUS, SUPPORT_RADIUS, count_nodes, disc_mesh, drape_on_support, shadow
from datagen.materials import MATERIALS, drape_range
from datagen.sim.settings import SolverConfig


def domed(v: np.ndarray, dome: float) -> np.ndarray:
    """The flat disc ``v`` (in y = 0) bent into a spherical bowl (a sphere through the centre, rim up,
    its rim about ``dome`` x the disc's radius above the centre; every point keeps its distance
    along the surface from the centre, so the cloth is unstretched but curved)."""
    if dome <= 0:
        return v.copy()
    r = np.linalg.norm(v[:, [0, 2]], axis=1)
    # a sphere of radius R through the centre: arc length s = R θ; height R (1 - cos θ)
    R = SPECIMEN_RADIUS / (2 * dome) + SPECIMEN_RADIUS * dome / 2
    th = r / R
    scale = np.where(r > 0, R * np.sin(th) / np.maximum(r, 1e-12), 1.0)
    out = v.copy()
    out[:, 0] *= scale
    out[:, 2] *= scale
    out[:, 1] += R * (1 - np.cos(th))
    return out


def drape_flat(mat, edge: float, seconds: float, dome: float, config: SolverConfig | None = None):
    """The disc cut flat (2D rest state), started bent over the support, draped for ``seconds``:
    (positions [V, 3], faces, largest vertex speed at the end [m/s])."""
    config = SolverConfig() if config is None else config
    v, f = disc_mesh(SPECIMEN_RADIUS, edge)
    uv = np.stack([v[:, 0], -v[:, 2]], 1)  # panel coordinates: u along X (weft), v along -Z (warp)
    start = domed(v, dome)
    start[:, 1] += mat.thickness + config.body_margin + 0.001
    return drape_on_support(start, f, seconds, config, material_name=mat, rest_corners=uv[f],
                            grain=np.tile([0.0, 1.0], (len(f), 1)))


def drape_coefficient(x: np.ndarray, f: np.ndarray) -> tuple[float, int]:
    """(DC, nodes) of a draped specimen."""
    area, r = shadow(x, f)
    support, specimen = np.pi * SUPPORT_RADIUS**2, np.pi * SPECIMEN_RADIUS**2
    return (area - support) / (specimen - support), count_nodes(r)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--presets", default=",".join(MATERIALS))
    ap.add_argument("--edge", type=float, default=0.015, help="edge length of the disc mesh [m]")
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--dome", type=float, default=0.3, help="start height of the cap's rim over its radius (0: flat)")
    args = ap.parse_args(argv)
    print(f"Cusick drape, specimen cut as a flat panel (2D rest state), started bent into a bowl (--dome {args.dome:g}): edge "
          f"{args.edge * 100:g} cm, {args.seconds:g} s, production solver settings")
    print(f"{'preset':<10} {'DC':>6} {'nodes':>6} {'range':>11} {'in range':>9} {'max speed m/s':>14} {'s':>6}")
    for name in args.presets.split(","):
        t0 = time.perf_counter()
        x, f, speed = drape_flat(MATERIALS[name], args.edge, args.seconds, args.dome)
        dc, nodes = drape_coefficient(x, f)
        lo, hi = drape_range(name)
        print(f"{name:<10} {dc:6.3f} {nodes:6d} {f'{lo:.2f}-{hi:.2f}':>11} {str(lo <= dc <= hi):>9} {speed:14.4f} "
              f"{time.perf_counter() - t0:6.1f}", flush=True)


if __name__ == "__main__":
    main()
