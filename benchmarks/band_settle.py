"""Where a waist garment's band goes while the body stands still in its rest pose: per frame, the
band's (top 3 cm) mean height change, its slip (the store's measure: distance from the body points
that carry it, less the rest distance) and the hem's height change. The check that found the global
step sliding skirts up the hips (2026-11-26: +44 mm in 15 frames, 8.5 cm by the end of the lead-in).

    python benchmarks/band_settle.py [--garment skirt] [--body regular] [--frames 15] [--mu 0.45]
        [--band-scale 0.9] [--set global_iterations=0 --set friction_pressure=3000 ...]
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np
from scipy.spatial import cKDTree


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--garment", default="skirt")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--body", default="regular")
    ap.add_argument("--frames", type=int, default=15)
    ap.add_argument("--mu", type=float, default=None, help="the material's friction instead of the preset's")
    ap.add_argument("--band-scale", type=float, default=None, help="the band's weft scale instead of the built one")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="a SolverConfig field")
    ap.add_argument("--device", default="cpu")
    args = ap.parse_args()

    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.config import load_config, parse_assignments
    from datagen.garment.types import make_garment
    from datagen.materials import material
    from datagen.motion.library import make_motion
    from datagen.sim import scene as S
    from datagen.sim.model import ClothModelBuilder
    from datagen.sim.solver import SolverConfig, SolverVBD
    from datagen.sim.state import BodyControl, ClothState

    overrides = parse_assignments(args.set)
    load_config(SolverConfig, overrides)  # unknown fields, wrong types and limits are refused here
    model = default_body()
    betas = resolve_betas(model, body=args.body)[0]
    g = make_garment(args.garment, model, betas, seed=args.seed)
    cfg = S.RunConfig()
    motion = make_motion("walk", seed=0, frames=cfg.motion_frames(10, 30.0), fps=30.0)
    a = S.scene_arrays(S.Scene(garment=g, body=model, betas=betas, motion=motion), cfg.lead_in)
    mat = material(a.material)
    if args.mu is not None:
        mat = dataclasses.replace(mat, friction=args.mu)
    weft = a.weft_scale
    if args.band_scale is not None and weft is not None:
        weft = np.where(np.asarray(weft) < 1.0, args.band_scale, 1.0)
    b = ClothModelBuilder()
    b.add_cloth(a.garment_vertices, a.garment_faces, material_name=mat, scene=0, material_frames=a.material_frames,
                weft_scale=weft)
    b.add_body(a.body_frames[0], a.body_faces, scene=0, face_part=a.body_face_part)
    m = b.finalize(args.device)
    solver = SolverVBD(m, SolverConfig(**overrides))
    st_a, st_b = ClothState.from_model(m), ClothState.from_model(m)
    control = BodyControl.from_numpy(m, a.body_frames[0])
    solver.reset_body(control)
    X, B0 = a.garment_vertices, a.body_frames[0]
    band = X[:, 1] > X[:, 1].max() - 0.03
    hem = X[:, 1] < X[:, 1].min() + 0.02
    dist, anchor = cKDTree(B0).query(X)
    print(f"{args.garment}:{args.seed} on {args.body}: {g.vertex_count} vertices, {mat.name} (μ {mat.friction:g}), "
          f"band weft scale {None if weft is None else float(np.min(weft)):.3f}, solver overrides {overrides or 'none'}")
    for f in range(args.frames):
        solver.step(st_a, st_b, control, 1.0 / 30.0)
        st_a, st_b = st_b, st_a
        x = st_a.positions.numpy()
        slip = (np.linalg.norm(x - B0[anchor], axis=1) - dist)[band].mean()
        print(f"frame {f:3d}: band height {1e3 * (x[band, 1] - X[band, 1]).mean():+7.1f} mm, slip {1e3 * slip:+6.1f} mm, "
              f"hem height {1e3 * (x[hem, 1] - X[hem, 1]).mean():+7.1f} mm", flush=True)


if __name__ == "__main__":
    main()
