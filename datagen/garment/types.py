"""Procedural garment types with seeded style parameters, built on a body in its rest pose.

Every type is a level set around the body (:mod:`datagen.garment.levelset`): a clearance
(``ease``) that varies from chest to waist to hips to cuffs and hems, a cone for the parts that
leave the body (skirts, dresses, coats), and cuts that open the neck, armholes or sleeve ends,
waist, hems and, for jackets and coats, the front. All lengths are in metres and measured from
the body's own joints, so one parameter set fits every body shape.

What a type is lives in its record (:class:`~datagen.garment.registry.GarmentType`, in
:data:`GARMENT_TYPES`): the construction reads the record's silhouette fields (hangs from the
shoulders or the waist, sleeves, skirt, separate legs, open front, hem measured from, panels), never
the type's name or the names of its parameters. Adding a type = one record in
:mod:`datagen.garment.registry` (and its code in ``schemas/garment_types.py``) plus, for a piece no
type has yet, its geometry in :func:`_design`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from datagen.errors import InputError
from datagen.garment import levelset
from datagen.materials import Material, material
from datagen.garment.mesh import GarmentMesh
from datagen.garment.metadata import GarmentMetadata, Waistband
from datagen.garment.registry import EDGE_LENGTH_RANGE, GARMENT_TYPES, GarmentType, garment_type
from datagen.params import ParamSpec, draw_params

__all__ = ["GARMENT_TYPES", "GarmentType", "MAX_VERTICES", "MIN_CLEARANCE", "ParamSpec", "default_edge_length",
           "garment_params", "make_garment"]

log = logging.getLogger(__name__)

MIN_CLEARANCE = 0.008
"""Smallest distance (m) between the constructed garment surface and the body."""

SHOULDER_CLEARANCE = 0.01
"""Clearance (m) of a top over the shoulders, where it rests: the chest's clearance narrows to this
at the shoulder joints' height."""

MAX_VERTICES = 200_000
"""Largest garment drape builds; a smaller edge length is refused with the memory it would take."""

BUILDER_VERSION = 9


def default_edge_length(kind: str) -> float:
    """The remeshing target of ``kind`` when none is given [m]."""
    return float(garment_type(kind).edge_length)


def garment_params(kind: str, seed: int, overrides: dict | None = None) -> dict[str, float]:
    """Style parameters of ``kind`` drawn by ``seed``, with ``overrides`` applied (range-checked).

    The draw is seeded by ``(seed, code, 104729)`` with the type's frozen code, so it does not
    depend on where the type's record sits in :data:`GARMENT_TYPES`."""
    t = garment_type(kind)
    return draw_params(t.params, seed, (t.code, 104729), repr(kind), overrides)


@dataclass
class _Body:
    verts: np.ndarray
    faces: np.ndarray
    joints: np.ndarray

    def j(self, name: str) -> np.ndarray:
        from datagen.body.skeleton import SMPL_JOINT_NAMES

        return self.joints[SMPL_JOINT_NAMES.index(name)]

    def half_extent(self, y: float, band: float = 0.02) -> tuple[float, float, float]:
        """Half width (x), half depth (z) and centre z of the torso cross-section near height y."""
        v = self.verts
        sel = (np.abs(v[:, 1] - y) < band) & (np.abs(v[:, 0]) < self.j("left_shoulder")[0] + 0.05)
        pts = v[sel]
        return float(np.abs(pts[:, 0]).max()), float(0.5 * np.ptp(pts[:, 2])), float(0.5 * (pts[:, 2].max() + pts[:, 2].min()))


def _interp(y, ys, vals):
    order = np.argsort(ys)
    return np.interp(y, np.asarray(ys)[order], np.asarray(vals)[order])



def make_garment(kind: str, body_model, betas=None, *, seed: int = 0, params: dict | None = None,
                 target_edge_length: float | None = None, material_name: str | Material | None = None,
                 grid_spacing: float | None = None) -> GarmentMesh:
    """Build a garment of type ``kind`` on ``body_model`` (shape ``betas``) in its rest pose.

    Args:
        kind: a type from :data:`GARMENT_TYPES` (``drape garment list``).
        body_model: a :class:`~datagen.body.model.BodyModel`.
        betas: body shape [shape_dim] (default zeros).
        seed: draws the style parameters.
        params: style parameters to fix (each within its range).
        target_edge_length: remeshing target (m); default the type's (2,000-8,000 vertices).
        material_name: a preset name or a :class:`Material`; default the type's.
        grid_spacing: marching-cubes grid step (m); default ``min(0.01, max(edge / 1.3, 0.004))``:
            1 cm for every type's default edge length (the remeshing reprojects onto the extracted
            surface, which is smooth at that scale), finer for finer meshes.
    """
    t0 = time.perf_counter()
    spec = garment_type(kind)
    p = garment_params(kind, seed, params)
    mat = material(material_name or spec.material)
    if target_edge_length is None:
        target_edge_length = default_edge_length(kind)
    lo, hi = EDGE_LENGTH_RANGE
    if not (np.isfinite(target_edge_length) and lo <= target_edge_length <= hi):
        raise InputError(f"target edge length must be between {lo} and {hi} m (the types' defaults are 13-20 mm; "
                         f"coarser meshes cannot hold a garment's openings), got {target_edge_length!r}")
    if int(seed) < 0:
        raise InputError(f"a garment's seed must be 0 or more, got {seed}")
    betas = np.zeros(body_model.shape_dim) if betas is None else np.asarray(betas, dtype=np.float64).reshape(-1)
    verts = np.asarray(body_model.shaped(betas))[0]
    body = _Body(verts=verts, faces=np.asarray(body_model.faces), joints=np.asarray(body_model.rest_joints(betas))[0])
    if spec.sleeve_above_elbow is not None:  # a short sleeve stops short of the elbow's fold (recorded so)
        reach = abs(body.j("left_elbow")[0]) - abs(body.j("left_shoulder")[0]) - spec.sleeve_above_elbow
        if p["sleeve_length"] > max(reach, 0.05):
            if params and "sleeve_length" in params:
                log.warning("%s sleeve_length %.3f m shortened to %.3f m: a %s's sleeve ends %.0f cm above the elbow",
                            kind, p["sleeve_length"], max(reach, 0.05), kind, 100 * spec.sleeve_above_elbow)
            p["sleeve_length"] = float(max(reach, 0.05))
    area_guess = spec.area_guess
    est_vertices = int(area_guess / (np.sqrt(3) / 4 * target_edge_length**2) / 2)
    if est_vertices > MAX_VERTICES:
        smallest = np.sqrt(area_guess / (2 * MAX_VERTICES * np.sqrt(3) / 4))
        raise InputError(f"edge length {target_edge_length:g} m would give a {kind} of about {est_vertices:,} vertices "
                         f"(~{est_vertices * 2 * 3 * 8 * 40 / 1e9:.1f} GB to simulate); the smallest allowed is "
                         f"{smallest:.4f} m ({MAX_VERTICES:,} vertices)")
    h = grid_spacing or min(0.01, max(target_edge_length / 1.3, 0.004))
    field, keep, lo, hi, regions, waist_top = _design(spec, p, body, h)
    rough_v, rough_f = levelset.extract_surface(field, lo, hi, h)
    # remesh the closed surface first, so the cut meets edges of the target length and leaves a
    # boundary spaced like the rest; then cut, and remesh again to even out the cut's neighbourhood
    v, f = levelset.remesh(rough_v, rough_f, target_edge_length, iterations=5)
    v, f = levelset.cut_mesh(v, f, keep(v), snap=0.3 * target_edge_length)
    v, f = levelset.largest_component(v, f)
    # the remesher keeps the boundary, so even out the cut's spacing first: short edges on the
    # boundary make triangles that a millimetre of motion stretches by 100 %
    v, f = levelset.collapse_short_edges(v, f, MIN_EDGE_FRACTION * target_edge_length)
    v, f = levelset.remesh(v, f, target_edge_length, iterations=5)
    v, f = levelset.largest_component(v, f)
    v, f = levelset.split_pinched_vertices(v, f)
    v, f = levelset.close_small_holes(v, f, 8)
    v, f = levelset.collapse_short_edges(v, f, MIN_EDGE_FRACTION * target_edge_length)
    region_names, vertex_region, chart = regions(v)
    waistband = None if waist_top is None else _waistband(v, body, waist_top)
    uv, face_uv, wrap_seam = _panel_uvs(v, f, vertex_region, region_names, chart)
    seconds = time.perf_counter() - t0
    meta = GarmentMetadata(type=kind, params=p, seed=int(seed), betas=betas.tolist(),
                           target_edge_length=target_edge_length, expected_boundary_loops=spec.boundary_loops,
                           builder_version=BUILDER_VERSION, build_seconds=seconds, waistband=waistband)
    return GarmentMesh.create(v, f, uv=uv, vertex_region=vertex_region, region_names=region_names, material=mat,
                              metadata=meta, face_uv=face_uv, extra_seam=wrap_seam)


MIN_EDGE_FRACTION = 0.5
"""Edges touching a garment's open boundary shorter than this share of the target edge length are
collapsed after the cut (:func:`~datagen.garment.levelset.collapse_short_edges`)."""

WAISTBAND_WIDTH = 0.04
"""Height of the elastic band below the waist opening of skirts, pants and shorts (m)."""

WAISTBAND_GRIP = 0.9
"""The band's rest length around the body as a share of the body's girth under it: fitted, the band
is stretched by about 1/0.9 - 1 = 11 %, and the friction of that tension holds the garment up. (At
0.95 the denim pants on the regular body crept down 6 cm in the first 150 frames of a 300-frame
walk, H100, 2026-11-25; at 0.9 they stay within 1.4 cm.)"""


def _hull_perimeter(points_xz: np.ndarray) -> float:
    from scipy.spatial import ConvexHull

    hull = points_xz[ConvexHull(points_xz).vertices]
    return float(np.linalg.norm(hull - np.roll(hull, 1, axis=0), axis=1).sum())


def _waistband(v: np.ndarray, body: _Body, top: float) -> Waistband:
    """The elastic band of a garment that hangs from the waist: its faces are those within
    :data:`WAISTBAND_WIDTH` below ``top``, their rest length along the weft (around the body) is
    ``weft_scale`` times the built one (a shrinkage, as cloth tools call it).

    A band built with the garment's clearance is longer than the body's girth, and nothing but
    friction holds such a skirt or pair of pants up: they slid down off the body (denim pants 30 cm
    in half a second of settling). The scale is the body's girth (the convex hull of its cross
    section, which a taut band spans) times :data:`WAISTBAND_GRIP` over the garment's girth, both at
    the band (the hull of its vertices seen from above).
    """
    def band(p):
        return p[(p[:, 1] > top - WAISTBAND_WIDTH) & (p[:, 1] < top + 0.002)]

    bv = band(body.verts)
    bv = bv[np.abs(bv[:, 0]) < body.j("left_shoulder")[0] + 0.05]  # the trunk, not a hand
    gv = band(v)
    if len(bv) < 8 or len(gv) < 8:
        raise InputError(f"the waistband below {top:.3f} m meets too few body ({len(bv)}) or garment ({len(gv)}) "
                         "vertices to measure its girth: the garment's waist parameter puts it off the body")
    girth_body, girth_garment = _hull_perimeter(bv[:, [0, 2]]), _hull_perimeter(gv[:, [0, 2]])
    return Waistband(top=float(top), width=WAISTBAND_WIDTH,
                     weft_scale=float(min(1.0, WAISTBAND_GRIP * girth_body / girth_garment)),
                     girth_body=girth_body, girth_garment=girth_garment)


def _panel_uvs(v: np.ndarray, f: np.ndarray, vertex_region: np.ndarray, names, chart):
    """Per-vertex UVs [V, 2] (each vertex in its own panel's chart), per-face-corner UVs
    [F, 3, 2] (every corner in its face's panel's chart, angles unwrapped within the face, so
    each face has a valid material frame even on a seam or where a sleeve's angle wraps), and a
    [V] mask of the vertices along such a wrap (a sleeve's underarm seam).

    u = angle × the panel's mean radius (metres around the body or limb), v = height or distance
    along the arm (metres). A panel whose chart would be mirrored against the outward normal has
    its u negated, so every face's (u, v) frame has the orientation of its normal.
    """
    corner = vertex_region[f]
    face_region = np.where(corner[:, 1] == corner[:, 2], corner[:, 1], corner[:, 0])
    uv = np.zeros((len(v), 2))
    face_uv = np.zeros((len(f), 3, 2))
    seam = np.zeros(len(v), dtype=bool)
    for r, name in enumerate(names):
        fs = np.flatnonzero(face_region == r)
        vs = np.flatnonzero(vertex_region == r)
        if len(fs) == 0 and len(vs) == 0:
            continue
        pts = v[f[fs]].reshape(-1, 3)
        ang, vv = chart(pts, name)
        ang, vv = ang.reshape(-1, 3), vv.reshape(-1, 3)
        wraps = np.ptp(ang, axis=1) > np.pi  # faces across the angle's wrap (a sleeve's underarm seam)
        seam[f[fs][wraps][ang[wraps] < 0]] = True
        ang = ang[:, :1] + (ang - ang[:, :1] + np.pi) % (2 * np.pi) - np.pi  # unwrap within each face
        # the panel's mean distance from its chart's axis, from how far its corners' angles are apart
        tri = v[f[fs]]
        edge3d = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2)
        dang = np.abs(ang - np.roll(ang, 1, axis=1))
        dv = np.abs(vv - np.roll(vv, 1, axis=1))
        horizontal = dang > 1e-9
        radius = float(np.median(np.sqrt(np.maximum(edge3d**2 - dv**2, 0.0))[horizontal] / dang[horizontal])) if horizontal.any() else 0.1
        fu = np.stack([radius * ang, vv], axis=-1)
        # orientation: faces wind around their outward normal, so a non-mirrored chart gives
        # each face a positive signed area in (u, v)
        du = fu[:, 1:] - fu[:, :1]
        det = du[:, 0, 0] * du[:, 1, 1] - du[:, 0, 1] * du[:, 1, 0]
        sign = -1.0 if np.sum(det < 0) > np.sum(det > 0) else 1.0
        fu[..., 0] *= sign
        face_uv[fs] = fu
        if len(vs):
            a, b = chart(v[vs], name)
            uv[vs] = np.stack([sign * radius * a, b], axis=1)
    return uv, face_uv, seam


def _design(spec: GarmentType, p: dict, body: _Body, spacing: float):
    """The implicit field, the keep (cut) field, the grid box, the region labeller of a garment of
    type ``spec`` with style parameters ``p`` and the height of its waist opening (None for a top,
    which hangs from the shoulders). The pieces come from the record's fields."""
    sh = body.j("left_shoulder")
    neck = body.j("neck")
    chest_y = body.j("spine3")[1]
    waist_y = body.j("spine1")[1] + 0.02
    hip_y = body.j("left_hip")[1]
    knee_y = body.j("left_knee")[1]
    ankle_y = body.j("left_ankle")[1]
    top = spec.hangs_from == "shoulders"
    sleeve = spec.sleeves
    cone = spec.skirt
    legs = spec.separate_legs
    from_ankles = spec.hem_from == "ankles"
    hw, hd, hzc = body.half_extent(hip_y - 0.03)
    nw, nd, _ = body.half_extent(neck[1], band=0.01)
    if top:
        grow = p["ease_chest"] + 0.015 + p["neck_width"]
        # the neck opening stops short of the shoulder joint, so shoulders (and straps) stay; a
        # sleeveless top's strap runs from 7 cm to 2 cm inside the joint, on the trapezius: with
        # the strap out on the shoulder tip, a silk dress slid off the lowered shoulders (its top
        # fell 30 cm in the first 1.5 s of a walk) and its hem dragged under the feet
        neck_rx, neck_rz = min(nw + grow, sh[0] - (0.05 if sleeve else 0.07)), nd + grow

    # --- clearance (ease) over the body
    def ease(pts):
        y = pts[:, 1]
        if top:
            e = _interp(y, [chest_y, waist_y, hip_y], [p["ease_chest"], p["ease_waist"], p["ease_hip"]])
            if sleeve:
                along = np.clip((np.abs(pts[:, 0]) - sh[0]) / max(p["sleeve_length"], 1e-3), 0.0, 1.0)
                e = np.where(np.abs(pts[:, 0]) > sh[0], (1 - along) * p["ease_chest"] + along * p["cuff_ease"], e)
            # a top rests on the shoulders: the clearance narrows from the chest's to the least at
            # the shoulder joints' height. With the chest's clearance there (up to 5 cm), a dress
            # fell freely for 5 frames before its straps met the shoulders, and the weight of its
            # skirt, caught at once, stretched the chest by 100 % in the rest settle
            e = np.minimum(e, _interp(y, [chest_y, sh[1]], [p["ease_chest"], SHOULDER_CLEARANCE]))
        else:
            e = _interp(y, [waist_y, hip_y], [p["ease_waist"], p["ease_hip"]])
            if legs:
                hem_y = (ankle_y + p["hem"]) if from_ankles else (hip_y - p["hem"])
                u = np.clip((hip_y - 0.08 - y) / max(hip_y - 0.08 - hem_y, 1e-3), 0.0, 1.0)
                e = np.where(y < hip_y - 0.08, (1 - u) * p["leg_ease"] + u * p["hem_ease"], e)
        return np.maximum(e, MIN_CLEARANCE)

    # --- cone for skirts, dresses and coats (from the hips down)
    def cone_field(pts):
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        below = np.clip(hip_y - y, 0.0, None)
        above = np.clip(y - hip_y, 0.0, None)
        e = p["ease_hip"]
        a = hw + e + p["flare"] * below - 1.5 * above
        b = hd + e + p["flare"] * below - 1.5 * above
        a, b = np.maximum(a, 0.02), np.maximum(b, 0.02)
        r = np.sqrt((x / a) ** 2 + ((z - hzc) / b) ** 2)
        return (r - 1.0) * np.minimum(a, b)

    # pants and shorts: the legs are separate tubes below the crotch, even where the clearances
    # around two close thighs would merge: a slot at the body's mid-plane, 1.2 grid steps wide so
    # marching cubes resolves it
    inner = body.verts[(np.abs(body.verts[:, 0]) < 0.015) & (body.verts[:, 1] < hip_y)]
    crotch_y = float(inner[:, 1].min()) if len(inner) else hip_y - 0.1

    def field(pts):
        f = levelset.body_sdf(body.verts, body.faces, pts) - ease(pts)
        if cone:
            f = levelset.smin(f, cone_field(pts), 0.03)
        if legs:
            # from below the garment's own crotch (the body's crotch less the clearance)
            below = np.clip(crotch_y - p["ease_hip"] - 0.015 - pts[:, 1], 0.0, None)
            slot = np.minimum(0.6 * spacing, below) - np.abs(pts[:, 0])
            f = np.maximum(f, slot)
        return f

    # --- cuts (keep > 0)
    hem_y = (ankle_y + p["hem"]) if from_ankles else (hip_y - p["hem"])
    if spec.hem_floor_below_knee is not None and hem_y < knee_y - spec.hem_floor_below_knee:
        hem_y = knee_y - spec.hem_floor_below_knee
    if top and not cone:
        # a top without a skirt part ends above the crotch: below it the clearance around the
        # legs splits in two and the hem would become two openings (thin bodies, long hems)
        hem_y = max(hem_y, crotch_y + 0.015)

    slit_top = min(hem_y + p["slit"], hip_y - 0.1) if spec.back_slit else hem_y

    def keep(pts):
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        cuts = [y - hem_y]
        if top:
            front = np.clip((z - neck[2]) / 0.08, 0.0, 1.0)
            # the neck tube above the neckline goes, the shoulders beside it stay
            # the opening widens upward (a cone around the neck), so the head is inside it
            rise = 1.5 * np.clip(y - (neck[1] + 0.03), 0.0, None)
            r = np.hypot(x / (neck_rx + rise), (z - neck[2]) / (neck_rz + rise))
            cuts.append(np.maximum((neck[1] - 0.035 - p["neck_drop"] - p["neck_depth"] * front) - y, r - 1.0))
            cuts.append((neck[1] + 0.1) - y)
            if sleeve:
                cuts.append((sh[0] + p["sleeve_length"]) - np.abs(x))
            else:  # armholes: the arm, the shoulder tip and the side wall down to the armhole line
                armpit = sh[1] - 0.07 - p["armhole_drop"]
                cuts.append(np.maximum((sh[0] - 0.02) - np.abs(x), armpit - y))
            if spec.open_front:
                # at least 2 grid steps either side of the mid-plane: a narrower slot is not
                # resolved by marching cubes everywhere and a bridge of cloth closes the front.
                # The front is open from the neckline down to the top button and closed below:
                # a front open down to the hem slid off the shoulders of a walking body (the
                # neckline spread and slid down the back; only a friction of 1.0 held it)
                half = max(p["opening"] / 2, 2.0 * spacing)
                button_y = neck[1] - 0.035 - p["neck_drop"] - p["neck_depth"] - p["lapel_depth"]
                cuts.append(np.maximum.reduce([np.abs(x) - half, (hzc + 0.02) - z, button_y - y]))
        else:
            cuts.append((waist_y - p["waist"]) - y)
        if spec.back_slit and slit_top > hem_y + 0.03:
            # as wide as the open front's slot (2 grid steps either side), behind the hips' centre
            half = 2.0 * spacing
            cuts.append(np.maximum.reduce([np.abs(x) - half, z - hzc, y - slit_top]))
        return np.minimum.reduce(cuts)

    # --- grid box
    xr = (sh[0] + p["sleeve_length"] + 0.08) if (top and sleeve) else (hw + 0.3 if cone else sh[0] + 0.12)
    top_y = neck[1] + 0.12 if top else waist_y + 0.05
    bottom_y = hem_y - 0.05
    lo = np.array([-xr, bottom_y, body.verts[:, 2].min() - 0.12 - (0.15 if cone else 0.0)])
    hi = np.array([xr, top_y, body.verts[:, 2].max() + 0.12 + (0.15 if cone else 0.0)])

    # --- regions and UVs (u along the weft, v along the warp; metres)
    # Each panel has a cylindrical chart: an angle around an axis (the trunk's vertical centre
    # line, an arm's shoulder line, a leg's hip-ankle line) times the panel's mean radius gives u
    # (around the body or limb), and the height (trunk, legs) or the distance along the arm gives
    # v. Torso panels measure their angle from their own centre (front from the front, back from
    # the back), so no panel wraps; a sleeve's angle is measured from its top and wraps at the
    # underarm, its seam. ``chart`` returns (angle [N], v [N]) for points [N, 3] of one panel.
    hip_l, ankle_l = body.j("left_hip"), body.j("left_ankle")
    leg_axis = (ankle_l - hip_l) / np.linalg.norm(ankle_l - hip_l)

    def chart(pts, name):
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        if name.endswith("sleeve"):
            side = 1.0 if name.startswith("left") else -1.0
            return np.arctan2(z - sh[2], y - sh[1]), side * x - sh[0]
        if name.startswith(("left_", "right_")):  # a leg panel of pants or shorts
            side = 1.0 if name.startswith("left") else -1.0
            origin = hip_l * np.array([side, 1.0, 1.0])
            axis = leg_axis * np.array([side, 1.0, 1.0])
            d = pts - origin
            d = d - (d @ axis)[:, None] * axis
            back = -1.0 if name.endswith("back") else 1.0
            return np.arctan2(back * side * d[:, 0], back * d[:, 2]), y
        back = -1.0 if name == "back" else 1.0
        return np.arctan2(back * x, back * (z - hzc)), y

    def regions(v):
        x, y, z = v[:, 0], v[:, 1], v[:, 2]
        if spec.panels == "top":
            names = ["front", "back", "left_sleeve", "right_sleeve"]
            reg = np.where(z > hzc, 0, 1)
            arm = (np.abs(x) > sh[0] + 0.03) & (y > sh[1] - 0.12)
            if sleeve:
                reg = np.where(arm & (x > 0), 2, np.where(arm & (x < 0), 3, reg))
        elif spec.panels == "skirt":
            names = ["front", "back"]
            reg = np.where(z > hzc, 0, 1)
        else:
            names = ["left_front", "left_back", "right_front", "right_back"]
            reg = np.where(x >= 0, 0, 2) + np.where(z > hzc, 0, 1)
        return tuple(names), reg.astype(np.int32), chart

    return field, keep, lo, hi, regions, (None if top else float(waist_y - p["waist"]))
