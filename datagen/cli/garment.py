"""``drape garment``: list the garment types, make one on a body, look at it."""

from __future__ import annotations

import json
from pathlib import Path

from datagen.errors import InputError


def register(sub, formatter) -> None:
    g = sub.add_parser("garment", formatter_class=formatter, help="procedural garments made to be simulated",
                       description="Procedural garments: level sets around the body in its rest pose, cut open at "
                       "neck, sleeves, waist and hems, remeshed isotropically, checked (manifold, openings, no "
                       "self-intersection, no body penetration).",
                       epilog="examples:\n  drape garment list\n  drape garment make --type dress --seed 4 --body regular "
                       "--out dress.obj --show dress.png")
    gsub = g.add_subparsers(dest="garment_command", metavar="GARMENT_COMMAND")
    gsub.required = True
    p = gsub.add_parser("list", formatter_class=formatter, help="garment types, their style parameters and materials",
                        epilog="example:\n  drape garment list --json")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.set_defaults(func=_cmd_list)
    p = gsub.add_parser("make", formatter_class=formatter, help="build one garment on a body and check it",
                        description="Build a garment of a type, styled by a seed, on a body shape in its rest pose; "
                        "every check runs and its figures are printed. .obj/.ply hold the mesh, .npz everything "
                        "(labels, UVs, material, metadata).",
                        epilog="examples:\n  drape garment make --type dress --seed 4 --body regular --out dress.obj\n"
                        "  drape garment make --type pants --param hem=0.05 --material denim --out pants.npz --show pants.png")
    p.add_argument("--type", required=True, help="a type from `drape garment list`")
    p.add_argument("--seed", type=int, default=0, help="draws the style parameters")
    p.add_argument("--body", default="regular", help="body shape preset: thin, regular, fat")
    p.add_argument("--edge-length", type=float, default=None, help="target edge length (m); default the type's")
    p.add_argument("--material", help="material preset (default: the type's)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="fix a style parameter (repeatable)")
    p.add_argument("--out", required=True, help="output file (.obj, .ply or .npz)")
    p.add_argument("--show", help="also render the garment on the body, front and side, to this PNG")
    p.set_defaults(func=_cmd_make)


def _cmd_list(args) -> int:
    from datagen.materials import MATERIALS
    from datagen.garment.types import GARMENT_TYPES

    if args.json:
        print(json.dumps({k: {"code": v.code, "material": v.material, "boundary_loops": v.boundary_loops,
                              "edge_length": v.edge_length,
                              "params": {n: {"low": s.low, "high": s.high, "doc": s.doc} for n, s in v.params.items()}}
                          for k, v in GARMENT_TYPES.items()}, indent=2))
        return 0
    for k, v in GARMENT_TYPES.items():
        print(f"{k} (code {v.code}, material {v.material}, {v.boundary_loops} openings, edge {1000 * v.edge_length:g} mm)")
        for n, s in v.params.items():
            print(f"    {n:14s} [{s.low:g}, {s.high:g}]  {s.doc}")
    print("materials: " + ", ".join(MATERIALS))
    return 0


def _cmd_make(args) -> int:
    import numpy as np

    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.garment.checks import check_garment
    from datagen.garment.types import make_garment
    from datagen.params import parse_param_args

    from datagen.garment.registry import EDGE_LENGTH_RANGE, garment_type
    from datagen.materials import material

    out = Path(args.out)
    if out.suffix.lower() not in (".obj", ".ply", ".npz"):
        raise InputError(f"--out {out}: write .obj, .ply or .npz")
    if not out.parent.is_dir():
        raise InputError(f"--out {out}: the folder {out.parent} does not exist; create it first")
    if args.show and not Path(args.show).parent.is_dir():
        raise InputError(f"--show {args.show}: the folder {Path(args.show).parent} does not exist; create it first")
    lo, hi = EDGE_LENGTH_RANGE
    if args.edge_length is not None and not lo <= args.edge_length <= hi:
        raise InputError(f"--edge-length must be between {lo} and {hi} m (the types' defaults are 13-20 mm), got "
                         f"{args.edge_length:g}")
    if args.seed < 0:
        raise InputError(f"--seed must be 0 or more, got {args.seed}")
    garment_type(args.type)  # an unknown type or material is refused before the body is loaded
    if args.material:
        material(args.material)
    params = parse_param_args(args.param)
    model = default_body()
    betas = resolve_betas(model, body=args.body)[0]
    try:
        garment = make_garment(args.type, model, betas, seed=args.seed, params=params,
                               target_edge_length=args.edge_length, material_name=args.material)
    except Exception as exc:
        if type(exc).__module__.startswith("pymeshlab"):
            raise InputError(f"building the {args.type} failed in pymeshlab ({' '.join(str(exc).split())}); try the "
                             "type's default --edge-length or another --seed") from None
        raise
    c = check_garment(garment, np.asarray(model.shaped(betas))[0], model.faces)
    if not c["ok"]:
        raise InputError(f"the {args.type} (seed {args.seed}, {garment.metadata.vertex_count} vertices) fails its "
                         f"checks: {'; '.join(c['failures'])}; nothing was written. Try the type's default "
                         "--edge-length, another --seed or --param values")
    garment.save(out)
    m = garment.metadata
    print(f"wrote {out}: {args.type} seed {args.seed} on {args.body}: {m.vertex_count} vertices, {m.face_count} faces, "
          f"{m.rest_area_m2:.2f} m², {m.boundary_loops} openings, material {garment.material.name} "
          f"({m.build_seconds:.1f} s)")
    print(f"checks: {'ok' if c['ok'] else 'FAILED: ' + '; '.join(c['failures'])}; min angle {c['min_angle_deg']:.1f}° "
          f"(1st percentile {c['angle_p1_deg']:.1f}°), edge spread {c['edge_spread']:.2f}, clearance "
          f"{c['min_clearance'] * 1000:.1f} mm, self-intersecting faces {c['self_intersecting_faces']}")
    if args.show:
        from datagen.garment.render import render_garment

        render_garment(garment, np.asarray(model.shaped(betas))[0], model.faces, args.show)
        print(f"wrote {args.show}")
    return 0
