"""Skirts: straight (with a back vent), A-line, circle to half-circle, gored with or without godets.

Every skirt hangs from a waist line at height ``top_y`` whose girth is ``waist`` (the body's girth
there plus ease) and clears the hips (hip girth plus ease) on the way down. Panels are in panel
space with y = height above the floor; front panels face +Z, back panels are turned 180 degrees
about Y, gores and circle panels are turned about Y to their place around the body.

The parts are shared with the dress (:mod:`.garments`), which hangs a skirt from its bodice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from datagen.body.measurements import BodyMeasurements
from datagen.garment.pattern.model import Arc, Quadratic, Stitch
from datagen.garment.pattern.programs.fit import frame, ring_radius, torso_girth
from datagen.garment.pattern.programs.bands import Target, band
from datagen.garment.pattern.programs.outline import Piece, Seg, mirror, piece, seam
from datagen.garment.pattern.programs.space import Choice, DesignSpace, Range

__all__ = ["SKIRT_LENGTH", "SKIRT_SPACES", "SkirtFit", "SkirtParts", "WAIST_SPACE", "skirt_fit", "skirt_parts",
           "waistband"]

@dataclass(frozen=True, kw_only=True)
class SkirtFit:
    """Where a skirt hangs on one body [m]: its waist edge's height and girth, hips, hem."""

    top_y: float
    waist: float
    hip_y: float
    hip: float
    hem_y: float
    floor_y: float
    centre_z: float


@dataclass
class SkirtParts:
    """A skirt's panels and seams, and its waist edges in the order a band (or a bodice) meets them:
    ``front_top`` from the body's right to its left across the front, ``back_top`` from the body's
    left to its right across the back (each (piece, edge names in the piece's loop order))."""

    pieces: list[Piece]
    stitches: list[Stitch]
    front_top: list[Target] = field(default_factory=list)
    back_top: list[Target] = field(default_factory=list)


SKIRT_LENGTH = Range(name="length", low=0.3, high=1.0, step=0.05, unit="of waist-to-ankle",
                     doc="hem below the waist line as a share of the waist-to-ankle height (0.05 is about 5 cm)")
WAIST_SPACE = DesignSpace((
    Range(name="rise", low=0.0, high=0.06, step=0.05, unit="m", doc="waist line below the natural waist"),
    Range(name="ease", low=0.02, high=0.08, step=0.08, unit="m", doc="girth added at the waist and hips"),
    Choice(name="waistband", options=(True, False), doc="a separate band sewn to the waist"),
    Range(name="band_width", low=0.03, high=0.07, step=0.02, unit="m", doc="height of the waistband",
          when={"waistband": (True,)}),
))

SKIRT_SPACES: dict[str, DesignSpace] = {
    "straight": DesignSpace((
        Range(name="length", low=0.35, high=0.95, step=0.05, unit="of waist-to-ankle", doc=SKIRT_LENGTH.doc),
        Range(name="hem_ratio", low=0.85, high=1.15, step=0.05, unit="of hip girth",
              doc="hem girth over the hip girth: pencil (<1) to straight (1) to slightly flared"),
        Choice(name="darts", options=(True, False), doc="waist darts (else the side seams take the waist in)"),
        Range(name="vent", low=0.1, high=0.3, step=0.05, unit="m", doc="height of the back vent above the hem"),
    )),
    "a_line": DesignSpace((
        SKIRT_LENGTH,
        Range(name="flare", low=1.15, high=2.0, step=0.1, unit="of hip girth", doc="hem girth over the hip girth"),
        Choice(name="darts", options=(True, False), doc="waist darts (else the side seams take the waist in)"),
    )),
    "circle": DesignSpace((
        SKIRT_LENGTH,
        Range(name="fullness", low=0.5, high=1.0, step=0.125, unit="of a circle",
              doc="the flat skirt's angle: a half circle (0.5) to a full circle (1)"),
        Choice(name="panels", options=(2, 4), doc="panels the circle is cut into"),
    )),
    "gored": DesignSpace((
        SKIRT_LENGTH,
        Choice(name="gores", options=(4, 6, 8, 10, 12), doc="number of gores (panels)"),
        Range(name="flare", low=1.0, high=2.0, step=0.1, unit="of hip girth", doc="hem girth over the hip girth"),
        Choice(name="godets", options=(False, True), doc="triangular godets set into the gore seams at the hem"),
        Range(name="godet_height", low=0.15, high=0.4, step=0.05, unit="m", doc="height of a godet",
              when={"godets": (True,)}),
        Range(name="godet_width", low=0.1, high=0.3, step=0.05, unit="m", doc="width of a godet at the hem",
              when={"godets": (True,)}),
    )),
}

MIN_HIP_DROP = 0.06
"""The hem of a skirt is at least this far [m] below the hip line (a skirt covers the hips)."""


def skirt_fit(m: BodyMeasurements, design) -> SkirtFit:
    """A standalone skirt's waist, hips and hem on ``m`` from the design's rise, ease and length."""
    f = frame(m)
    top = m.waist_height - float(design["rise"])
    ease = float(design["ease"])
    hem = m.waist_height - float(design["length"]) * (m.waist_height - m.ankle_height)
    hip_y = min(m.hip_height, top - 0.06)
    return SkirtFit(top_y=top, waist=float(torso_girth(m, top)) + ease, hip_y=hip_y, hip=m.hip + ease,
                    hem_y=min(hem, hip_y - MIN_HIP_DROP), floor_y=f.floor_y, centre_z=f.centre_z)


def _fitted_half(fit: SkirtFit, quarter_waist: float, quarter_hip: float, quarter_hem: float, darts: bool,
                 dart_length: float) -> tuple[list[Seg], tuple]:
    """Right half of a front/back skirt panel, bottom centre to top centre; (segments, end point)."""
    q = max(quarter_hip - quarter_waist, 0.0)
    intake = 0.5 * q if darts and q >= 0.02 else 0.0
    xw = quarter_waist + intake
    ye, yh, yw = fit.hem_y, fit.hip_y, fit.top_y
    xh = max(quarter_hip, xw)
    segs = [Seg((0.0, ye), None, "hem+", "hem"), Seg((quarter_hem, ye), None, "side_lo+"),
            Seg((xh, yh), Quadratic(control=(xh, yh + 0.6 * (yw - yh))), "side_hi+")]
    if intake:
        dx = 0.5 * quarter_waist
        segs += [Seg((xw, yw), None, "waist_out+", "waist"), Seg((dx + intake / 2, yw), None, "dart_a+"),
                 Seg((dx, yw - dart_length), None, "dart_b+"), Seg((dx - intake / 2, yw), None, "waist_in+", "waist")]
    else:
        segs += [Seg((xw, yw), None, "waist+", "waist")]
    return segs, (0.0, yw)


def _darted(p: Piece) -> bool:
    return any(n.startswith("dart_") for n in p.index)


def _top_names(p: Piece) -> list[list[str]]:
    """A symmetric skirt panel's waist runs from its -x end to its +x end (each in loop order)."""
    if _darted(p):
        return [["waist_out-"], ["waist_in+", "waist_in-"], ["waist_out+"]]
    return [["waist+", "waist-"]]


def _dart_stitches(p: Piece) -> list[Stitch]:
    if not _darted(p):
        return []
    return [seam(p, ["dart_a+"], p, ["dart_b+"]), seam(p, ["dart_b-"], p, ["dart_a-"])]


def _front_back(fit: SkirtFit, hem_girth: float, darts: bool, vent: float | None) -> SkirtParts:
    half, end = _fitted_half(fit, fit.waist / 4, fit.hip / 4, hem_girth / 4, darts, 0.09)
    back_half, back_end = _fitted_half(fit, fit.waist / 4, fit.hip / 4, hem_girth / 4, darts, 0.12)
    other, _ = mirror(half, end)
    d = ring_radius(fit.hip)
    front = piece("skirt_front", half + other, translation=(0.0, fit.floor_y, fit.centre_z + d))
    back_rot = (0.0, 180.0, 0.0)
    back_t = (0.0, fit.floor_y, fit.centre_z - d)
    stitches = _dart_stitches(front)
    side = ["side_lo+", "side_hi+"]
    side_m = ["side_hi-", "side_lo-"]
    if vent is None:
        bother, _ = mirror(back_half, back_end)
        back = piece("skirt_back", back_half + bother, translation=back_t, rotation=back_rot)
        stitches += _dart_stitches(back)
        stitches += [seam(front, side, back, side_m), seam(front, side_m, back, side)]
        back_top = [(back, n) for n in _top_names(back)]
        pieces = [front, back]
    else:  # a centre back seam open at the hem: the vent
        vent = min(vent, fit.hip_y - fit.hem_y - 0.05)
        yv = fit.hem_y + max(vent, 0.02)
        left, lend = mirror(back_half, back_end)  # body-left back: panel x < 0, its centre edge on the right
        left = left + [Seg(lend, None, "vent", "vent"), Seg((0.0, yv), None, "cb")]
        right = back_half + [Seg(back_end, None, "cb"), Seg((0.0, yv), None, "vent", "vent")]
        back_l = piece("skirt_back_left", left, translation=back_t, rotation=back_rot)
        back_r = piece("skirt_back_right", right, translation=back_t, rotation=back_rot)
        for p, sgn in ((back_l, "-"), (back_r, "+")):
            if _darted(p):
                a, b = f"dart_a{sgn}", f"dart_b{sgn}"
                stitches.append(seam(p, [a], p, [b]) if sgn == "+" else seam(p, [b], p, [a]))
        stitches += [seam(back_l, ["cb"], back_r, ["cb"]),
                     seam(front, side, back_l, side_m), seam(front, side_m, back_r, side)]
        back_top = ([(back_l, ["waist_out-"]), (back_l, ["waist_in-"])] if _darted(back_l) else [(back_l, ["waist-"])])
        back_top += ([(back_r, ["waist_in+"]), (back_r, ["waist_out+"])] if _darted(back_r) else [(back_r, ["waist+"])])
        pieces = [front, back_l, back_r]
    return SkirtParts(pieces, stitches, [(front, n) for n in _top_names(front)], back_top)


def _around(n: int) -> list[float]:
    """Angles [degrees] about Y of the centres of ``n`` panels around the body: two panels front and
    back, more with seams at the centre front and back."""
    off = 0.0 if n == 2 else 0.5
    return [360.0 * (k + off) / n for k in range(n)]


def _ring_targets(pieces: list[Piece], angles: list[float]) -> tuple[list[Target], list[Target]]:
    """Waist targets of panels around the body: front ones (centre within 90 degrees of +Z) in order
    of increasing angle, back ones likewise, each panel's waist [waist+, waist-]."""
    def wrap(a):
        return (a + 180.0) % 360.0 - 180.0

    front = sorted((wrap(a), p) for p, a in zip(pieces, angles) if abs(wrap(a)) < 90 - 1e-6)
    back = sorted((a % 360.0, p) for p, a in zip(pieces, angles) if abs(wrap(a)) >= 90 - 1e-6)
    return [(p, ["waist+", "waist-"]) for _, p in front], [(p, ["waist+", "waist-"]) for _, p in back]


def _circle(fit: SkirtFit, fullness: float, n: int) -> SkirtParts:
    r = fit.waist / (2 * math.pi * fullness)
    length = fit.top_y - fit.hem_y
    big = r + length
    half = math.pi * fullness / n  # half the angle of one panel [rad]
    s, c = math.sin(half), math.cos(half)
    segs = [Seg((0.0, -big), Arc(radius=big, large_arc=False, right=True), "hem+", "hem"),
            Seg((big * s, -big * c), None, "side+"),
            Seg((r * s, -r * c), Arc(radius=r, large_arc=False, right=False), "waist+", "waist")]
    other, _ = mirror(segs, (0.0, -r))
    angles = _around(n)
    d = ring_radius(fit.hip)
    pieces = []
    for k, a in enumerate(angles):
        t = math.radians(a)
        pieces.append(piece(f"skirt_panel_{k}", segs + other, rotation=(0.0, a, 0.0),
                            translation=(d * math.sin(t), fit.floor_y + fit.top_y + r, fit.centre_z + d * math.cos(t))))
    stitches = [seam(pieces[k], ["side+"], pieces[(k + 1) % n], ["side-"]) for k in range(n)]
    front, back = _ring_targets(pieces, angles)
    return SkirtParts(pieces, stitches, front, back)


def _gored(fit: SkirtFit, n: int, flare: float, godets: bool, gh: float, gw: float) -> SkirtParts:
    ye, yh, yw = fit.hem_y, fit.hip_y, fit.top_y
    ge, gh_x, gw_x = fit.hip * flare / (2 * n), fit.hip / (2 * n), fit.waist / (2 * n)
    gh_x = max(gh_x, gw_x)
    segs = [Seg((0.0, ye), None, "hem+", "hem")]
    slit = 0.0
    if godets:
        gh = min(gh, yh - ye - 0.05)
        t = gh / (yh - ye)
        top = (ge + t * (gh_x - ge), ye + gh)
        segs += [Seg((ge, ye), None, "gslit+"), Seg(top, None, "side_lo+")]
        slit = math.hypot(top[0] - ge, gh)
    else:
        segs += [Seg((ge, ye), None, "side_lo+")]
    segs += [Seg((gh_x, yh), Quadratic(control=(gh_x, yh + 0.6 * (yw - yh))), "side_hi+"),
             Seg((gw_x, yw), None, "waist+", "waist")]
    other, _ = mirror(segs, (0.0, yw))
    angles = _around(n)
    d = ring_radius(fit.hip)
    pieces = []
    for k, a in enumerate(angles):
        t = math.radians(a)
        pieces.append(piece(f"skirt_gore_{k}", segs + other, rotation=(0.0, a, 0.0),
                            translation=(d * math.sin(t), fit.floor_y, fit.centre_z + d * math.cos(t))))
    stitches = [seam(pieces[k], ["side_lo+", "side_hi+"], pieces[(k + 1) % n], ["side_hi-", "side_lo-"])
                for k in range(n)]
    if godets:
        w = min(gw, 1.6 * slit)
        h = math.sqrt(slit**2 - (w / 2) ** 2)
        tri = [Seg((-w / 2, -h), None, "hem", "hem"), Seg((w / 2, -h), None, "side+"), Seg((0.0, 0.0), None, "side-")]
        for k, a in enumerate(angles):
            mid = a + 180.0 / n
            t = math.radians(mid)
            g = piece(f"skirt_godet_{k}", tri, rotation=(0.0, mid, 0.0),
                      translation=((d + 0.02) * math.sin(t), fit.floor_y + ye + gh, fit.centre_z + (d + 0.02) * math.cos(t)))
            pieces.append(g)
            stitches += [seam(pieces[k], ["gslit+"], g, ["side-"]), seam(pieces[(k + 1) % n], ["gslit-"], g, ["side+"])]
    front, back = _ring_targets(pieces[:n], angles)
    return SkirtParts(pieces, stitches, front, back)


def skirt_parts(kind: str, design, fit: SkirtFit) -> SkirtParts:
    """The panels of a skirt of ``kind`` (a key of :data:`SKIRT_SPACES`) hanging as ``fit`` says."""
    if kind == "straight":
        return _front_back(fit, fit.hip * float(design["hem_ratio"]), bool(design["darts"]), float(design["vent"]))
    if kind == "a_line":
        return _front_back(fit, fit.hip * float(design["flare"]), bool(design.get("darts", False)), None)
    if kind == "circle":
        return _circle(fit, float(design["fullness"]), int(design["panels"]))
    if kind == "gored":
        godets = bool(design["godets"])
        return _gored(fit, int(design["gores"]), float(design["flare"]), godets,
                      float(design.get("godet_height", 0.0)), float(design.get("godet_width", 0.0)))
    raise ValueError(kind)


def waistband(parts: SkirtParts, fit: SkirtFit, width: float) -> tuple[list[Piece], list[Stitch]]:
    """Front and back halves of a waistband on a skirt's waist, joined at the sides."""
    d = ring_radius(fit.waist)
    lf = sum(p.length(*n) for p, n in parts.front_top)
    lb = sum(p.length(*n) for p, n in parts.back_top)
    front, s1 = band("waistband_front", parts.front_top, width, top_group="waist", rotation=(0.0, 0.0, 0.0),
                     translation=(-lf / 2, fit.floor_y + fit.top_y, fit.centre_z + d))
    back, s2 = band("waistband_back", parts.back_top, width, top_group="waist", rotation=(0.0, 180.0, 0.0),
                    translation=(lb / 2, fit.floor_y + fit.top_y, fit.centre_z - d))
    return [front, back], s1 + s2 + [seam(front, ["end+"], back, ["end-"]), seam(back, ["end+"], front, ["end-"])]
