"""``drape garment``: list the garment types, make one on a body, look at it."""

from __future__ import annotations

import json
from pathlib import Path

from datagen.cli import args as checks
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
                        description="Build a garment on a body shape in its rest pose, of a procedural type (--type, "
                        "an offset shell) or from a sewing pattern (--pattern, a program fitted to the body's "
                        "measurements; --spec, a GarmentCode specification JSON): flat panels meshed and placed "
                        "around the body, to be sewn by the simulator. Every check runs and its figures are printed. "
                        ".obj/.ply hold the mesh, .npz everything (labels, UVs, material, metadata; for a pattern "
                        "also the flat rest coordinates, stitches, grain and the pattern).",
                        epilog="examples:\n  drape garment make --type dress --seed 4 --body regular --out dress.obj\n"
                        "  drape garment make --type pants --param hem=0.05 --material denim --out pants.npz --show pants.png\n"
                        "  drape garment make --pattern skirt_circle --seed 3 --body fat --out skirt.npz --svg skirt.svg\n"
                        "  drape garment make --spec shirt_specification.json --body thin --out shirt.npz")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--type", help="a procedural type from `drape garment list`")
    src.add_argument("--pattern", help="a pattern program from `drape garment list`")
    src.add_argument("--spec", help="a GarmentCode specification JSON (GarmentCode's frame stands on the floor; "
                     "files drape wrote are in drape's)")
    p.add_argument("--seed", type=checks.seed, default=0, help="draws the style parameters (the design of a --pattern)")
    p.add_argument("--body", default="regular", help="body shape preset: thin, regular, fat")
    p.add_argument("--edge-length", type=checks.number(0, above=True), default=None, help="target edge length (m); default the type's")
    p.add_argument("--material", help="material preset (default: the type's)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="fix a style parameter, or a design parameter of a --pattern (repeatable)")
    p.add_argument("--placement", choices=("wrap", "flat"), default="wrap",
                   help="pattern panels bent around the body (wrap) or flat where the pattern puts them")
    p.add_argument("--out", required=True, type=checks.out_file(".obj", ".ply", ".npz"), help="output file (.obj, .ply or .npz)")
    p.add_argument("--show", type=checks.out_file(".png"), help="also render the garment on the body, front and side, to this PNG")
    p.add_argument("--svg", type=checks.out_file(".svg", ".png"), help="--pattern/--spec: draw the panels with their stitches numbered (.svg, or .png)")
    p.add_argument("--write-spec", type=checks.out_file(".json"), help="--pattern/--spec: also write the pattern as GarmentCode specification JSON")
    p.set_defaults(func=_cmd_make)


def _cmd_list(args) -> int:
    from datagen.materials import MATERIALS
    from datagen.garment.types import GARMENT_TYPES

    from datagen.garment.pattern.programs import PROGRAMS

    if args.json:
        def param(par) -> dict:
            out = {"doc": par.doc, **({"when": {k: list(v) for k, v in par.when.items()}} if par.when else {})}
            if hasattr(par, "options"):
                return {"options": list(par.options), **out}
            return {"low": par.low, "high": par.high, "step": par.step, "unit": par.unit, **out}

        print(json.dumps({
            "types": {k: {"code": v.code, "material": v.material, "boundary_loops": v.boundary_loops,
                          "edge_length": v.edge_length,
                          "params": {n: {"low": s.low, "high": s.high, "doc": s.doc} for n, s in v.params.items()}}
                      for k, v in GARMENT_TYPES.items()},
            "patterns": {k: {"family": prog.family, "doc": prog.doc,
                             "params": {par.name: param(par) for par in prog.space.params}}
                         for k, prog in PROGRAMS.items()},
            "materials": list(MATERIALS)}, indent=2))
        return 0

    print("procedural types (offset shells of the body): --type NAME")
    for k, v in GARMENT_TYPES.items():
        print(f"{k} (code {v.code}, material {v.material}, {v.boundary_loops} openings, edge {1000 * v.edge_length:g} mm)")
        for n, s in v.params.items():
            print(f"    {n:14s} [{s.low:g}, {s.high:g}]  {s.doc}")
    print("\nsewing-pattern programs (flat panels fitted to the body's measurements): --pattern NAME")
    for k, prog in PROGRAMS.items():
        print(f"{k} ({prog.family}): {prog.doc}")
        for par in prog.space.params:
            print(f"    {_describe_param(par)}")
    print("materials: " + ", ".join(MATERIALS))
    return 0


def _describe_param(par) -> str:
    when = getattr(par, "when", None)
    when = "  (when " + ", ".join(f"{k} in {'|'.join(map(str, v))}" for k, v in when.items()) + ")" if when else ""
    if hasattr(par, "options"):
        return f"{par.name:18s} {' | '.join(map(str, par.options))}  {par.doc}{when}"
    return f"{par.name:18s} [{par.low:g}, {par.high:g}] {getattr(par, 'unit', '') or ''}  {par.doc}{when}"


def _pattern_params(items: list[str]) -> dict:
    """``--param NAME=VALUE`` for a pattern's design: numbers, true/false, or words."""
    out: dict = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InputError(f"--param {item!r}: write it as NAME=VALUE, e.g. --param neckline=v")
        value = value.strip()
        if value.lower() in ("true", "false"):
            out[name.strip()] = value.lower() == "true"
            continue
        try:
            num = float(value)
            out[name.strip()] = int(num) if num.is_integer() and "." not in value else num
        except ValueError:
            out[name.strip()] = value
    return out


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
    if args.type is None:
        return _make_pattern(args, out)
    for flag in ("svg", "write_spec"):
        if getattr(args, flag):
            raise InputError(f"--{flag.replace('_', '-')} draws or writes a sewing pattern: use it with --pattern or --spec")
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


def _make_pattern(args, out: Path) -> int:
    import numpy as np

    from datagen.body.cache import default_body
    from datagen.body.shapes import resolve_betas
    from datagen.garment.pattern.garment import check_pattern_garment, pattern_garment, stand_on_floor
    from datagen.garment.pattern.mesh import MIN_EDGE_LENGTH
    from datagen.materials import material

    for flag, value in (("--svg", args.svg), ("--write-spec", args.write_spec)):
        if value and not Path(value).parent.is_dir():
            raise InputError(f"{flag} {value}: the folder {Path(value).parent} does not exist; create it first")
    if args.svg and Path(args.svg).suffix.lower() not in (".svg", ".png"):
        raise InputError(f"--svg {args.svg}: write .svg or .png")
    edge = 0.02 if args.edge_length is None else args.edge_length
    if not MIN_EDGE_LENGTH <= edge <= 0.1:
        raise InputError(f"--edge-length must be between {MIN_EDGE_LENGTH} and 0.1 m for a pattern, got {edge:g}")
    if args.material:
        material(args.material)
    overrides = _pattern_params(args.param)
    if args.spec and overrides:
        raise InputError("--param sets a program's design parameters; a --spec file has its own geometry")
    if args.pattern:
        from datagen.garment.pattern.programs import PROGRAMS, design_of

        if args.pattern not in PROGRAMS:
            raise InputError(f"--pattern {args.pattern!r} is not a pattern program; `drape garment list` shows them: "
                             f"{', '.join(PROGRAMS)}")
        design_of(args.pattern, args.seed, **overrides)  # a bad override is refused before the body is loaded
    else:
        from datagen.garment.pattern.spec import read_spec, spec_frame

        pattern = read_spec(args.spec)
    model = default_body()
    betas = resolve_betas(model, body=args.body)[0]
    body_v = np.asarray(model.shaped(betas))[0]
    body_f = np.asarray(model.faces)
    if args.pattern:
        from datagen.body.measurements import measure_body
        from datagen.garment.pattern.programs import make_pattern

        pattern = make_pattern(args.pattern, args.seed, measure_body(model, betas), **overrides)
        label = f"{args.pattern} seed {args.seed}"
    else:
        if spec_frame(args.spec) == "garmentcode":
            pattern = stand_on_floor(pattern, body_v)
            print(f"{args.spec}: GarmentCode's frame (standing on y = 0): moved down to the body's floor")
        label = f"{pattern.name} from {args.spec}"
    garment = pattern_garment(pattern, body_v, body_f, edge_length=edge, mode=args.placement,
                              material_name=args.material, seed=args.seed if args.pattern else None, betas=betas)
    c = check_pattern_garment(garment, body_v, body_f)
    if not c["ok"]:
        raise InputError(f"the {label} ({garment.metadata.vertex_count} vertices) fails its checks: "
                         f"{'; '.join(c['failures'])}; nothing was written. Try another --edge-length or --seed")
    garment.save(out)
    m = garment.metadata
    print(f"wrote {out}: {label} on {args.body}: {len(pattern.panels)} panels, {len(pattern.stitches)} stitches, "
          f"{m.vertex_count} vertices, {m.face_count} faces, {m.rest_area_m2:.2f} m², openings "
          f"{', '.join(garment.loops)}, material {garment.material.name} ({m.build_seconds:.1f} s)")
    if args.pattern:
        from datagen.garment.pattern.programs import design_of

        design = ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                           for k, v in design_of(args.pattern, args.seed, **overrides).items())
        print(f"design ({label}; a store keeps it in garments/design with the pattern): {design}")
    print(f"checks: ok; min angle {c['min_angle_deg']:.1f}° (1st percentile {c['angle_p1_deg']:.1f}°), edge spread "
          f"{c['edge_spread']:.2f}, longest edge {c['edge_max_ratio']:.2f} x median, clearance "
          f"{c['min_clearance'] * 1000:.1f} mm, {c['stitch_pairs']} sewn pairs {c['stitch_gap_mean'] * 100:.1f} cm apart "
          f"on average ({args.placement} placement)")
    if args.svg:
        from datagen.garment.pattern.svg import draw_svg

        draw_svg(pattern, args.svg)
        print(f"wrote {args.svg}")
    if args.write_spec:
        from datagen.garment.pattern.spec import write_spec

        write_spec(pattern, args.write_spec)
        print(f"wrote {args.write_spec}")
    if args.show:
        from datagen.garment.render import render_garment

        render_garment(garment, body_v, body_f, args.show)
        print(f"wrote {args.show}")
    return 0
