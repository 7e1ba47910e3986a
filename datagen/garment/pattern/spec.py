"""GarmentCode's specification JSON, read into a :class:`~datagen.garment.pattern.model.Pattern` and written back.

The format (GarmentCode, pygarment's ``BasicPattern``; MIT licence; this module is our own code):

```json
{"pattern": {"panels": {"<name>": {"vertices": [[x, y], ...],
                                    "edges": [{"endpoints": [i, j], "curvature": {...}, "label": "..."}],
                                    "translation": [x, y, z], "rotation": [rx, ry, rz]}},
             "stitches": [[{"panel": "<a>", "edge": k}, {"panel": "<b>", "edge": m}], ...],
             "panel_order": ["<name>", ...]},
 "properties": {"units_in_meter": 100, "curvature_coords": "relative", ...}}
```

- lengths are in ``1 / units_in_meter`` metres (GarmentCode writes centimetres, 100);
- ``curvature`` is ``{"type": "quadratic", "params": [[u, v]]}``, ``{"type": "cubic", "params":
  [[u1, v1], [u2, v2]]}`` with control points in the edge's RELATIVE frame: ``p = start + u (end -
  start) + v perp(end - start)``, ``perp(x, y) = (-y, x)`` (v > 0 is to the left of start -> end);
  an old-style bare list ``[u, v]`` is a quadratic; ``"curvature_coords": "absolute"`` gives the
  control points in panel coordinates instead; ``{"type": "circle", "params": [radius, large_arc,
  right]}`` is an SVG arc, ``radius`` in file units, ``right`` the side of start -> end it bulges to;
- ``rotation`` is XYZ Euler in degrees, ``R = Rz Ry Rx``; a panel point lands at ``R [x, y, 0] + t``;
- a stitch joins one edge to one edge; by default the start of one meets the end of the other
  (GarmentCode's ``swap``); a third element ``"right_wrong"`` makes start meet start.

drape's panel space is seen from outside the garment (outlines counter-clockwise), GarmentCode's is
the body's frame: its back panels run clockwise with no rotation. Such a panel is read mirrored
(``x -> -x``, a half turn about its y axis added to its rotation), which places every point where
GarmentCode puts it. drape writes counter-clockwise panels; GarmentCode reads them as they are.
Stitch sides of several edges are written as one stitch per edge pair; where the two sides have
different numbers of edges, edges are split first at the other side's corners
(:mod:`~datagen.garment.pattern.split`), each piece marked ``"drape_piece": [edge, t0, t1]``, and
drape joins them back on reading. Extra keys that GarmentCode ignores
keep what its format lacks: ``"grain"`` and ``"edge_groups"`` per panel, ``"ease"`` on a stitch's
first side (``"seam"`` there too when one stitch of several edges became several pairs), ``"name"``
and ``"design"`` at the top, ``"frame": "drape_rest"`` in the properties (:func:`spec_frame`).
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Mapping
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from datagen.errors import InputError
from datagen.garment.pattern.model import (STITCH_TOLERANCE, Arc, Cubic, Edge, Panel, Pattern, Quadratic,
                                           SeamSide, Stitch)
from datagen.garment.pattern.split import join_curve, pair_stitches

__all__ = ["DRAPE_FRAME", "abs_to_rel", "read_spec", "rel_to_abs", "spec_dict", "spec_frame", "write_spec"]

log = logging.getLogger(__name__)

UNITS_IN_METER = 100
"""Units drape writes: centimetres, as GarmentCode."""


DRAPE_FRAME = "drape_rest"
"""``properties.frame`` of the files drape writes: placed in drape's rest-pose body frame (the pelvis
near the origin). A file without it is in GarmentCode's frame, standing on the floor at y = 0."""


def spec_frame(source) -> str:
    """``"drape_rest"`` for a file drape wrote, ``"garmentcode"`` (standing on y = 0) otherwise."""
    data, _ = _load(source)
    props = data.get("properties") or {}
    return DRAPE_FRAME if props.get("frame") == DRAPE_FRAME else "garmentcode"


def rel_to_abs(start, end, rel) -> np.ndarray:
    """A point given in the edge's relative frame -> panel coordinates (same units as start/end)."""
    s, e, r = np.asarray(start, float), np.asarray(end, float), np.asarray(rel, float)
    v = e - s
    return s + r[0] * v + r[1] * np.array([-v[1], v[0]])


def abs_to_rel(start, end, point) -> np.ndarray:
    """Inverse of :func:`rel_to_abs`: panel coordinates -> the edge's relative frame [u, v]."""
    s, e, p = np.asarray(start, float), np.asarray(end, float), np.asarray(point, float)
    v = e - s
    d = p - s
    n2 = float(v @ v)
    return np.array([d @ v / n2, d @ np.array([-v[1], v[0]]) / n2])


def _mirror_rotation(rot) -> tuple[float, float, float]:
    """Euler angles of ``R(rot) @ Ry(180)`` (R = Rz Ry Rx): ``Rx(a) Ry(180) = Ry(180) Rx(-a)``."""
    a, b, c = (float(x) for x in rot)

    def wrap(x):
        x = math.fmod(x + 180.0, 360.0)
        return (x + 360.0 if x <= 0 else x) - 180.0
    return (wrap(-a) if a else 0.0, wrap(b + 180.0), c)


def _read_panel(name: str, spec: Mapping, scale: float, absolute: bool) -> tuple[Panel, bool]:
    """One panel of the file (and whether it was mirrored to run counter-clockwise)."""
    who = f"panel '{name}'"
    try:
        verts = np.asarray(spec["vertices"], dtype=float) * scale
        edge_specs = list(spec["edges"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{who}: needs 'vertices' (a list of [x, y]) and 'edges' ({exc})") from None
    if verts.ndim != 2 or verts.shape[1] != 2:
        raise InputError(f"{who}: 'vertices' must be a list of [x, y] pairs, got shape {verts.shape}")
    ends = []
    for k, e in enumerate(edge_specs):
        try:
            i, j = (int(x) for x in e["endpoints"])
        except (KeyError, TypeError, ValueError):
            raise InputError(f"{who}: edge {k} needs 'endpoints': [start, end]") from None
        if not (0 <= i < len(verts) and 0 <= j < len(verts)):
            raise InputError(f"{who}: edge {k} joins vertices {i} and {j}, but the panel has {len(verts)} vertices")
        ends.append((i, j))
    curves: list[object] = []
    for k, (e, (i, j)) in enumerate(zip(edge_specs, ends)):
        c = e.get("curvature")
        s, t = verts[i], verts[j]
        if c is None:
            curves.append(None)
            continue
        if isinstance(c, (list, tuple)):  # GarmentCode's old bare quadratic
            c = {"type": "quadratic", "params": [c]}
        kind, params = c.get("type"), c.get("params")
        try:
            if kind in ("quadratic", "cubic"):
                pts = np.asarray(params, dtype=float).reshape(-1, 2)
                if len(pts) != (1 if kind == "quadratic" else 2):
                    raise ValueError(f"{len(pts)} control points")
                ctrl = pts * scale if absolute else np.stack([rel_to_abs(s, t, p) for p in pts])
                curves.append(("bezier", ctrl))
            elif kind == "circle":
                radius, large, right = params
                curves.append(("arc", float(radius) * scale, bool(large), bool(right)))
            else:
                raise ValueError(f"unknown curvature type {kind!r} (quadratic, cubic or circle)")
        except (TypeError, ValueError) as exc:
            raise InputError(f"{who}: edge {k}: bad curvature {c!r}: {exc}") from None
    ends, curves, file_to_edge = _join_pieces(verts, ends, curves, [e.get("drape_piece") for e in edge_specs])
    if len(file_to_edge) != len(edge_specs) or max(file_to_edge, default=-1) + 1 != len(ends):
        raise InputError(f"{who}: its 'drape_piece' marks do not describe consecutive pieces of edges")
    used = sorted({i for i, _ in ends})
    if used and used[-1] + 1 < len(verts):  # the points drape inserted to split edges come last
        verts = verts[: used[-1] + 1]

    def build_edges(flip: np.ndarray, mirror: bool) -> list[Edge]:
        edges = []
        for (i, j), c in zip(ends, curves):
            if c is None:
                curve = None
            elif c[0] == "bezier":
                ctrl = c[1] * flip
                curve = (Quadratic(control=tuple(ctrl[0])) if len(ctrl) == 1
                         else Cubic(control1=tuple(ctrl[0]), control2=tuple(ctrl[1])))
            else:
                curve = Arc(radius=c[1], large_arc=c[2], right=c[3] != mirror)
            edges.append(Edge(start=i, end=j, curve=curve))
        return edges

    # clockwise in the body's frame (a panel seen from behind): the sampled outline's signed area
    try:
        plain = SimpleNamespace(vertices=[tuple(x) for x in verts])
        outline = np.concatenate([e.sample(plain, 17)[:-1] for e in build_edges(np.ones(2), False)])
    except InputError as exc:
        raise InputError(f"{who}: {exc}") from None
    nxt = np.roll(outline, -1, axis=0)
    mirrored = float(np.sum(outline[:, 0] * nxt[:, 1] - nxt[:, 0] * outline[:, 1])) < 0
    flip = np.array([-1.0, 1.0]) if mirrored else np.array([1.0, 1.0])
    edges = build_edges(flip, mirrored)
    groups: dict[str, tuple[int, ...]] = {}
    if isinstance(spec.get("edge_groups"), Mapping):
        groups = {str(k): tuple(dict.fromkeys(file_to_edge[int(x)] for x in v)) for k, v in spec["edge_groups"].items()}
    else:  # GarmentCode's edge labels become groups
        for k, e in enumerate(edge_specs):
            if e.get("label") and file_to_edge[k] not in groups.get(str(e["label"]), ()):
                groups.setdefault(str(e["label"]), ())
                groups[str(e["label"])] += (file_to_edge[k],)
    grain = np.asarray(spec.get("grain", (0.0, 1.0)), dtype=float) * flip
    rotation = tuple(float(x) for x in spec.get("rotation", (0, 0, 0)))
    translation = tuple(float(x) * scale for x in spec.get("translation", (0, 0, 0)))
    panel = Panel(name=name, vertices=[tuple(v) for v in verts * flip], edges=edges,
                  translation=translation, rotation=_mirror_rotation(rotation) if mirrored else rotation,
                  grain=tuple(grain / max(np.linalg.norm(grain), 1e-12)), edge_groups=groups,
                  limb=bool(spec.get("drape_limb", False)))
    return panel, mirrored, file_to_edge


def _join_pieces(verts, ends, curves, marks):
    """Edges drape split to write a stitch (marked ``drape_piece: [edge, t0, t1]``) joined back.

    Returns the joined ends and curves, and the joined index of every edge of the file."""
    if not any(m is not None for m in marks):
        return ends, curves, list(range(len(ends)))
    out_ends, out_curves, index = [], [], []
    k = 0
    while k < len(ends):
        m = marks[k]
        run = [k]
        while (m is not None and run[-1] + 1 < len(ends) and marks[run[-1] + 1] is not None
               and int(marks[run[-1] + 1][0]) == int(m[0])):
            run.append(run[-1] + 1)
        i, j = ends[run[0]][0], ends[run[-1]][1]
        c = curves[run[0]]
        if len(run) > 1 and c is not None:
            t0, t1 = float(m[1]), float(m[2])
            a, b = verts[ends[run[0]][0]], verts[ends[run[0]][1]]
            if c[0] == "arc":
                joined = join_curve(a, b, [(Arc(radius=c[1], large_arc=c[2], right=c[3]), t0, t1)], a, b)
                c = ("arc", joined.radius, joined.large_arc, joined.right)
            else:
                obj = Quadratic(control=tuple(c[1][0])) if len(c[1]) == 1 else Cubic(control1=tuple(c[1][0]),
                                                                                     control2=tuple(c[1][1]))
                joined = join_curve(a, b, [(obj, t0, t1)], a, b)
                c = ("bezier", np.array([joined.control]) if isinstance(joined, Quadratic)
                     else np.array([joined.control1, joined.control2]))
        out_ends.append((i, j))
        out_curves.append(c)
        index += [len(out_ends) - 1] * len(run)
        k = run[-1] + 1
    return out_ends, out_curves, index


def _load(source) -> tuple[dict, str]:
    if isinstance(source, Mapping):
        return dict(source), str(source.get("name") or "pattern")
    path = Path(source)
    try:
        text = path.read_text()
    except OSError as exc:
        raise InputError(f"cannot read the pattern specification {path}: {exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path} is not JSON ({exc}); a GarmentCode specification is a JSON file") from None
    stem = path.stem[: -len("_specification")] if path.stem.endswith("_specification") else path.stem
    if not isinstance(data, dict):
        raise InputError(f"{path}: a GarmentCode specification is a JSON object with 'pattern' and 'properties'")
    return data, str(data.get("name") or stem)


def read_spec(source) -> Pattern:
    """A :class:`Pattern` from GarmentCode's specification JSON: a path or the parsed dict.

    Lengths are converted to metres; clockwise panels are mirrored (module docstring); a stitch
    whose two edges differ in length gets the ease that admits them (logged)."""
    data, name = _load(source)
    try:
        pat = data["pattern"]
        panel_specs = pat["panels"]
    except (KeyError, TypeError):
        raise InputError("a GarmentCode specification needs 'pattern': {'panels': {...}, 'stitches': [...]}") from None
    props = data.get("properties") or {}
    units = float(props.get("units_in_meter", UNITS_IN_METER))
    if not units > 0:
        raise InputError(f"properties.units_in_meter must be positive, got {units}")
    if "units_in_meter" not in props:
        log.warning("%s: no properties.units_in_meter; reading centimetres as GarmentCode does", name)
    absolute = props.get("curvature_coords", "relative") == "absolute"
    order = [n for n in pat.get("panel_order", []) if n in panel_specs]
    order += [n for n in panel_specs if n not in order]
    panels, mirrored, edge_of = [], {}, {}
    for pname in order:
        p, m, idx = _read_panel(str(pname), panel_specs[pname], 1.0 / units, absolute)
        panels.append(p)
        mirrored[p.name] = m
        edge_of[p.name] = idx
    by_name = {p.name: p for p in panels}
    stitches, seam_of = [], {}
    for k, st in enumerate(pat.get("stitches", [])):
        try:
            sides = [(str(s["panel"]), s["edge"]) for s in st[:2]]
            sides = [(pn, edge_of[pn][int(e)] if pn in edge_of and 0 <= int(e) < len(edge_of[pn]) else int(e))
                     for pn, e in sides]
        except (KeyError, TypeError, IndexError, ValueError):
            raise InputError(f"stitch {k}: expected [{{'panel': name, 'edge': index}}, {{...}}], got {st!r}") from None
        if len(sides) != 2:
            raise InputError(f"stitch {k} has {len(sides)} sides; a stitch joins two edges")
        right_wrong = len(st) > 2 and "right_wrong" in st[2:]
        seam = st[0].get("seam") if isinstance(st[0], Mapping) else None
        if seam is not None and seam in seam_of:  # drape wrote one stitch of several edges as pairs
            prev = stitches[seam_of[seam]]
            ea, eb = int(sides[0][1]), int(sides[1][1])
            a = SeamSide(panel=prev.a.panel, edges=prev.a.edges + ((ea,) if ea not in prev.a.edges else ()))
            if eb in prev.b.edges:
                b_edges = prev.b.edges
            else:
                b_edges = (eb,) + prev.b.edges if prev.reversed else prev.b.edges + (eb,)
            stitches[seam_of[seam]] = Stitch(a=a, b=SeamSide(panel=prev.b.panel, edges=b_edges),
                                             reversed=prev.reversed, ease=prev.ease)
            continue
        if seam is not None:
            seam_of[seam] = len(stitches)
        a, b = (SeamSide(panel=p, edges=e) for p, e in sides)
        ease = st[0].get("ease") if isinstance(st[0], Mapping) else None
        if ease is None:
            la, lb = (sum(by_name[s.panel].edge_length(i) for i in s.edges) if s.panel in by_name else 0.0
                      for s in (a, b))
            diff = abs(la - lb) / max(la, lb, 1e-12)
            ease = 0.0 if diff <= STITCH_TOLERANCE else math.ceil((diff - STITCH_TOLERANCE) * 1e4 + 1) / 1e4
            if ease:
                log.info("%s: stitch %d's sides differ by %.1f %%: read with ease %.4f", name, k, 100 * diff, ease)
        stitches.append(Stitch(a=a, b=b, reversed=not right_wrong, ease=float(ease)))
    design = data.get("design") or {}
    return Pattern(name=name, panels=tuple(panels), stitches=tuple(stitches), design=dict(design))


def _json_value(v):
    if isinstance(v, Mapping):
        return {str(k): _json_value(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_value(x) for x in v]
    if isinstance(v, np.ndarray):
        return _json_value(v.tolist())
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    return v


def spec_dict(pattern: Pattern, units_in_meter: float = UNITS_IN_METER) -> dict:
    """The GarmentCode specification of ``pattern`` as a JSON-able dict (see :func:`write_spec`)."""
    s = float(units_in_meter)
    pattern, pieces = pair_stitches(pattern)
    panels = {}
    for p in pattern.panels:
        v = np.asarray(p.vertices)
        edges = []
        labels = {}
        for gname, ids in p.edge_groups.items():
            for i in ids:
                labels.setdefault(i, gname)
        for k, e in enumerate(p.edges):
            d: dict = {"endpoints": [e.start, e.end]}
            a, b = v[e.start], v[e.end]
            c = e.curve
            if isinstance(c, Quadratic):
                d["curvature"] = {"type": "quadratic", "params": [abs_to_rel(a, b, c.control).tolist()]}
            elif isinstance(c, Cubic):
                d["curvature"] = {"type": "cubic", "params": [abs_to_rel(a, b, c.control1).tolist(),
                                                              abs_to_rel(a, b, c.control2).tolist()]}
            elif isinstance(c, Arc):
                d["curvature"] = {"type": "circle", "params": [c.radius * s, int(c.large_arc), int(c.right)]}
            if k in labels:
                d["label"] = labels[k]
            if (p.name, k) in pieces:
                d["drape_piece"] = list(pieces[(p.name, k)])
            edges.append(d)
        panels[p.name] = {
            "vertices": (v * s).tolist(), "edges": edges,
            "translation": [x * s for x in p.translation], "rotation": list(p.rotation),
            "grain": list(p.grain), "edge_groups": {k: list(ids) for k, ids in p.edge_groups.items()},
        }
        if p.limb:
            panels[p.name]["drape_limb"] = True
    stitches = []
    for k, st in enumerate(pattern.stitches):
        ea, eb = st.a.edges, st.b.edges
        # sewn order: a's edges in loop order meet b's in reverse loop order when the stitch is reversed
        pairs = zip(ea, reversed(eb) if st.reversed else eb)
        for n, (i, j) in enumerate(pairs):
            first = {"panel": st.a.panel, "edge": int(i)}
            if len(ea) > 1:
                first["seam"] = k
            if n == 0:
                first["ease"] = st.ease
            entry = [first, {"panel": st.b.panel, "edge": int(j)}]
            if not st.reversed:
                entry.append("right_wrong")
            stitches.append(entry)
    return {
        "name": pattern.name,
        "pattern": {"panels": panels, "stitches": stitches, "panel_order": [p.name for p in pattern.panels]},
        "parameters": {}, "parameter_order": [],
        "properties": {"curvature_coords": "relative", "normalize_panel_translation": False,
                       "normalized_edge_loops": True, "units_in_meter": s, "frame": DRAPE_FRAME},
        "design": _json_value(dict(pattern.design)),
    }


def write_spec(pattern: Pattern, path, units_in_meter: float = UNITS_IN_METER) -> Path:
    """Write ``pattern`` as GarmentCode's specification JSON (centimetres by default) to ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(spec_dict(pattern, units_in_meter), indent=1))
    return path
