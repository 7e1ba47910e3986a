"""A :class:`~datagen.garment.mesh.GarmentMesh` of the pattern kind from a :class:`Pattern` and a body.

:func:`pattern_garment` meshes the flat panels (:mod:`~datagen.garment.pattern.mesh`), places them
around the body (:mod:`~datagen.garment.pattern.placement`), names the openings the free edges
leave once sewn, and records the rest state, stitches, grain and the pattern itself.
:func:`check_pattern_garment` runs the checks a pattern garment must pass before it is simulated.
"""

from __future__ import annotations

import json
import logging
import time
from collections import Counter

import numpy as np

from datagen.errors import InputError
from datagen.garment.mesh import GarmentMesh, boundary_loops
from datagen.garment.metadata import GarmentMetadata
from datagen.garment.pattern.mesh import FlatPatternMesh, mesh_pattern, mesh_quality
from datagen.garment.pattern.model import Pattern
from datagen.garment.pattern.placement import CLEARANCE, Mode, place
from datagen.garment.pattern.spec import spec_dict
from datagen.materials import material

__all__ = ["BUILDER_VERSION", "DEFAULT_MATERIAL", "MIN_ANGLE", "MAX_EDGE_RATIO", "check_pattern_garment",
           "pattern_garment", "sewn_openings", "stand_on_floor"]

log = logging.getLogger(__name__)

BUILDER_VERSION = 1

DEFAULT_MATERIAL = "cotton"

MIN_ANGLE = 12.0
"""Smallest triangle angle [degrees] a pattern garment's flat mesh may have (a check)."""
MAX_EDGE_RATIO = 2.0
"""Longest edge / median edge a pattern garment's flat mesh may have (a check)."""


def _weld(n: int, pairs: np.ndarray) -> np.ndarray:
    """Representative (smallest id) of every vertex once the stitched pairs are merged [n]."""
    parent = np.arange(n)

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for a, b in pairs:
        ra, rb = find(int(a)), find(int(b))
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    return np.array([find(i) for i in range(n)])


def sewn_openings(flat: FlatPatternMesh, positions: np.ndarray) -> dict[str, np.ndarray]:
    """The garment's openings once sewn: name -> vertex ids in order.

    The panels are welded along their stitches; each boundary loop of the welded mesh is named by
    the edge group most of its vertices come from (``hem``, ``waist``, ``neck``, ``cuff``, ...),
    with ``left_``/``right_`` in front when its centre is more than 6 cm off the midline, and
    ``opening`` when no group names it; a repeated name gets ``_2``, ``_3``."""
    rep = _weld(flat.vertex_count, flat.stitch_pairs)
    f = rep[flat.faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])]
    group_of: dict[int, list[str]] = {}
    for (pi, e), ids in flat.edge_vertices.items():
        for gname, edges in flat.pattern.panels[pi].edge_groups.items():
            if e in edges:
                for v in ids:
                    group_of.setdefault(int(rep[v]), []).append(gname)
    loops = boundary_loops(f) if len(f) else []
    named: dict[str, np.ndarray] = {}
    for lp in sorted(loops, key=lambda lp: -float(positions[lp, 1].mean())):
        votes = Counter(g for v in lp for g in group_of.get(int(v), []))
        base = votes.most_common(1)[0][0] if votes else "opening"
        cx = float(positions[lp, 0].mean())
        if abs(cx) > 0.06 and not base.startswith(("left", "right")):
            base = ("left_" if cx > 0 else "right_") + base
        name, k = base, 1
        while name in named:
            k += 1
            name = f"{base}_{k}"
        named[name] = lp
    return named


def _grain_uv(flat: FlatPatternMesh) -> np.ndarray:
    """``rest_uv`` in each panel's (weft, warp) frame [V, 2] [m]: u across the grain, v along it."""
    out = np.zeros_like(flat.rest_uv)
    for pi, p in enumerate(flat.pattern.panels):
        g = np.asarray(p.grain)
        weft = np.array([g[1], -g[0]])
        sel = flat.panel_id == pi
        out[sel, 0] = flat.rest_uv[sel] @ weft
        out[sel, 1] = flat.rest_uv[sel] @ g
    return out


def pattern_garment(pattern: Pattern, body_vertices: np.ndarray, body_faces: np.ndarray, *,
                    edge_length: float = 0.02, mode: Mode = "wrap", material_name: str | None = None,
                    seed: int | None = None, betas=None) -> GarmentMesh:
    """Mesh ``pattern`` at ``edge_length`` [m] and place it around the body (rest pose, metres).

    ``seed`` and ``betas`` are recorded in the metadata (the program's seed, the body's shape)."""
    t0 = time.perf_counter()
    flat = mesh_pattern(pattern, edge_length)
    pos = place(flat, body_vertices, body_faces, mode=mode)
    mat = material(material_name or DEFAULT_MATERIAL)
    seam = np.zeros(flat.vertex_count, dtype=bool)
    seam[flat.stitch_pairs.ravel()] = True
    numeric = {k: float(v) for k, v in pattern.design.items()
               if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)}
    numeric |= {k: float(v) for k, v in pattern.design.items() if isinstance(v, bool)}
    loops = sewn_openings(flat, pos)
    meta = GarmentMetadata(type=f"pattern:{pattern.name}", params=numeric, seed=seed,
                           betas=None if betas is None else tuple(np.asarray(betas, float).ravel()),
                           target_edge_length=float(edge_length), builder_version=BUILDER_VERSION,
                           expected_boundary_loops=len(loops), build_seconds=time.perf_counter() - t0)
    uv = _grain_uv(flat)
    return GarmentMesh.create(pos, flat.faces, uv=uv, vertex_region=flat.panel_id,
                              region_names=[p.name for p in pattern.panels], material=mat, metadata=meta,
                              extra_seam=seam, loops=loops, rest_uv=flat.rest_uv, stitch_pairs=flat.stitch_pairs,
                              face_grain=flat.face_grain(), pattern=json.dumps(spec_dict(pattern)))


def stand_on_floor(pattern: Pattern, body_vertices: np.ndarray) -> Pattern:
    """``pattern`` in GarmentCode's frame (standing on y = 0) moved to drape's body frame: every
    panel's translation lowered to the body's floor (its lowest vertex)."""
    import dataclasses

    floor = float(np.asarray(body_vertices)[:, 1].min())
    return dataclasses.replace(pattern, panels=tuple(
        dataclasses.replace(p, translation=(p.translation[0], p.translation[1] + floor, p.translation[2]))
        for p in pattern.panels))


def check_pattern_garment(garment: GarmentMesh, body_vertices: np.ndarray, body_faces: np.ndarray) -> dict:
    """The checks of a pattern garment: flat mesh quality, seams, and no vertex inside the body.

    The outline (closed, not self-crossing) and the stitch lengths are checked when the pattern is
    built (:class:`~datagen.garment.pattern.model.Pattern` refuses them); here: the flat mesh's
    minimum angle (>= :data:`MIN_ANGLE`) and longest edge (<= :data:`MAX_EDGE_RATIO` x median), every
    panel a single disc, sewn pairs on the boundary, no vertex inside the body and none closer than
    half the placement clearance. Returns the figures, ``failures`` (messages) and ``ok``."""
    if garment.kind != "pattern":
        raise InputError("check_pattern_garment checks garments of the pattern kind (rest_uv set)")
    from datagen.geometry.queries import mesh_signed_distance, warp_mesh

    q = mesh_quality(garment.rest_uv, garment.faces)
    sd = mesh_signed_distance(warp_mesh(np.asarray(body_vertices, float), np.asarray(body_faces)), garment.vertices, 10.0)
    failures = []
    if q.min_angle < MIN_ANGLE:
        failures.append(f"minimum angle {q.min_angle:.1f} deg < {MIN_ANGLE:g}")
    if q.edge_max_ratio > MAX_EDGE_RATIO:
        failures.append(f"longest edge {q.edge_max_ratio:.2f} x the median > {MAX_EDGE_RATIO:g}")
    discs = 0
    for pi in range(len(garment.region_names)):
        f = garment.faces[garment.face_region == pi]
        if len(boundary_loops(f)) == 1:
            discs += 1
        else:
            failures.append(f"panel '{garment.region_names[pi]}' is not one disc")
    on_boundary = np.zeros(len(garment.vertices), bool)
    for pi in range(len(garment.region_names)):
        for lp in boundary_loops(garment.faces[garment.face_region == pi]):
            on_boundary[lp] = True
    pairs = garment.stitch_pairs if garment.stitch_pairs is not None else np.zeros((0, 2), np.int64)
    if len(pairs) and not on_boundary[pairs].all():
        failures.append("a sewn vertex is not on its panel's outline")
    inside = int((sd < 0).sum())
    if inside:
        failures.append(f"{inside} vertices inside the body")
    if float(sd.min()) < CLEARANCE / 2 and not inside:
        failures.append(f"a vertex {1000 * float(sd.min()):.1f} mm from the body (< {500 * CLEARANCE:g} mm)")
    gaps = np.linalg.norm(garment.vertices[pairs[:, 0]] - garment.vertices[pairs[:, 1]], axis=1) if len(pairs) else np.zeros(1)
    return {"ok": not failures, "failures": failures, "min_angle_deg": q.min_angle, "angle_p1_deg": q.angle_p1,
            "edge_spread": q.edge_spread, "edge_max_ratio": q.edge_max_ratio, "edge_min_ratio": q.edge_min_ratio,
            "vertices_inside": inside, "min_clearance": float(sd.min()), "stitch_gap_mean": float(gaps.mean()),
            "stitch_gap_max": float(gaps.max()), "panels": len(garment.region_names), "stitch_pairs": len(pairs),
            "openings": len(garment.loops)}
