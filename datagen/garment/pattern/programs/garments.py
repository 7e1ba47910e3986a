"""Whole garments from the parts: skirts, tops, dresses and open-front jackets.

Each ``build_*`` takes a resolved design (see :mod:`.space`) and the body's measurements and
returns a validated :class:`~datagen.garment.pattern.model.Pattern`; each ``*_SPACE`` is the
design space its program draws from.
"""

from __future__ import annotations

from datagen.body.measurements import BodyMeasurements
from datagen.garment.pattern.model import Pattern
from datagen.garment.pattern.programs import bodice as bd
from datagen.garment.pattern.programs.collars import hood, ring_collar, strip_collar
from datagen.garment.pattern.programs.fit import frame
from datagen.garment.pattern.programs.outline import Piece, seam
from datagen.garment.pattern.programs.skirts import (SKIRT_LENGTH, SKIRT_SPACES, WAIST_SPACE, SkirtFit,
                                                     skirt_fit, skirt_parts, waistband)
from datagen.garment.pattern.programs.space import Choice, DesignSpace, Range

__all__ = ["DRESS_SPACE", "JACKET_SPACE", "SKIRT_PROGRAM_SPACES", "TOP_SPACE", "build_dress", "build_jacket",
           "build_skirt", "build_top"]

SKIRT_PROGRAM_SPACES = {kind: WAIST_SPACE + space for kind, space in SKIRT_SPACES.items()}


def build_skirt(kind: str):
    """The builder of a skirt of ``kind`` (a key of :data:`SKIRT_SPACES`)."""
    def build(design, m: BodyMeasurements) -> Pattern:
        fit = skirt_fit(m, design)
        parts = skirt_parts(kind, design, fit)
        pieces, stitches = list(parts.pieces), list(parts.stitches)
        if design["waistband"]:
            p, s = waistband(parts, fit, float(design["band_width"]))
            pieces += p
            stitches += s
        return _pattern(f"skirt_{kind}", pieces, stitches, design)
    return build


def _pattern(name: str, pieces: list[Piece], stitches, design) -> Pattern:
    return Pattern(name=name, panels=tuple(p.panel for p in pieces), stitches=tuple(stitches), design=dict(design))


_BODY = DesignSpace((
    Range(name="ease", low=0.04, high=0.2, step=0.08, unit="m", doc="girth added at the chest (fitted to loose)"),
    Range(name="fit", low=0.0, high=1.0, step=0.5, unit="", doc="below the chest: 0 hangs straight, 1 follows the body"),
))
_DARTS = Choice(name="darts", options=(False, True), doc="bust darts in the front's side seams")
_TOP_LENGTH = Range(name="length", low=-0.2, high=1.4, step=0.2, unit="of crotch depth",
                    doc="hem below the natural waist as a share of the waist-to-crotch height (0.2 is about 5 cm; "
                        "negative: cropped)")

TOP_SPACE = bd.neckline_space() + _BODY + DesignSpace((_TOP_LENGTH, _DARTS)) + bd.sleeve_space() + DesignSpace((
    Choice(name="collar", options=("none", "stand", "hood"), doc="a stand collar or a hood on the neckline"),
    Range(name="collar_height", low=0.03, high=0.07, step=0.02, unit="m", doc="height of the stand collar",
          when={"collar": ("stand",)}),
    Range(name="hood_depth", low=0.26, high=0.34, step=0.04, unit="m", doc="front-to-back depth of the hood",
          when={"collar": ("hood",)}),
))

DRESS_SPACE = bd.neckline_space() + _BODY + DesignSpace((
    _DARTS,
    Range(name="waist_seam", low=-0.06, high=0.12, step=0.06, unit="m",
          doc="bodice-skirt seam below the natural waist (negative: empire line)"),
)) + bd.sleeve_space() + DesignSpace((
    Choice(name="skirt", options=("a_line", "circle"), doc="the skirt's cut"),
    SKIRT_LENGTH,
    Range(name="flare", low=1.0, high=2.0, step=0.1, unit="of hip girth", doc="hem girth over the hip girth",
          when={"skirt": ("a_line",)}),
    Range(name="fullness", low=0.5, high=1.0, step=0.125, unit="of a circle", doc="half to full circle",
          when={"skirt": ("circle",)}),
    Choice(name="collar", options=("none", "stand"), doc="a stand collar on the neckline"),
    Range(name="collar_height", low=0.03, high=0.07, step=0.02, unit="m", doc="height of the stand collar",
          when={"collar": ("stand",)}),
))

JACKET_SPACE = bd.neckline_space(("round", "v", "scoop")) + DesignSpace((
    Range(name="ease", low=0.1, high=0.22, step=0.08, unit="m", doc="girth added at the chest"),
    Range(name="fit", low=0.0, high=1.0, step=0.5, unit="", doc="below the chest: 0 hangs straight, 1 follows the body"),
    Range(name="length", low=0.6, high=1.8, step=0.2, unit="of crotch depth",
          doc="hem below the natural waist as a share of the waist-to-crotch height"),
    Range(name="opening", low=0.0, high=0.1, step=0.05, unit="m", doc="gap between the two front edges"),
)) + bd.sleeve_space((0.7, 1.0), allow_none=False) + DesignSpace((
    Choice(name="collar", options=("none", "stand", "shirt", "flat", "hood"), doc="collar or hood"),
    Range(name="collar_height", low=0.04, high=0.1, step=0.03, unit="m", doc="height of the collar",
          when={"collar": ("stand", "shirt", "flat")}),
    Range(name="hood_depth", low=0.26, high=0.34, step=0.04, unit="m", doc="front-to-back depth of the hood",
          when={"collar": ("hood",)}),
))


def _torso(design, m: BodyMeasurements, hem_y: float, *, darts: bool, sleeves: bool):
    """Front and back panels of a closed bodice, sewn at the shoulders and sides (and darts)."""
    b = bd.bodice_fit(design, m, frame(m), hem_y=hem_y, ease=float(design["ease"]), fit=float(design["fit"]),
                      darts=darts, sleeves=sleeves)
    front = bd.bodice(b, design["neckline"], name="bodice_front", front=True)
    back = bd.bodice(b, design["neckline"], name="bodice_back", front=False)
    stitches = [seam(front, ["shoulder+"], back, ["shoulder-"]), seam(front, ["shoulder-"], back, ["shoulder+"])]
    stitches += bd.side_stitches(front, back, "+", "-") + bd.side_stitches(front, back, "-", "+")
    if b.dart_intake:
        stitches += [seam(front, ["dart_a+"], front, ["dart_b+"]), seam(front, ["dart_b-"], front, ["dart_a-"])]
    pieces = [front, back]
    if sleeves:
        p, s = bd.sleeves(b, design, m, {"left": (front, "+"), "right": (front, "-")},
                          {"left": (back, "-"), "right": (back, "+")})
        pieces += p
        stitches += s
    return b, front, back, pieces, stitches


def _collar(design, b, m, front, back, pieces, stitches) -> None:
    kind = design.get("collar", "none")
    if kind == "stand":
        p, s = ring_collar([(front, ["neck+", "neck-"])], [(back, ["neck+", "neck-"])], float(design["collar_height"]), b)
    elif kind == "hood":
        p, s = hood((front, ["neck+"]), (back, ["neck-"]), (front, ["neck-"]), (back, ["neck+"]),
                    float(design["hood_depth"]), m, b)
    else:
        return
    pieces += p
    stitches += s


def build_top(design, m: BodyMeasurements) -> Pattern:
    """A top: T-shirt, blouse, tank top, hoodie, crop top or tunic, by its design."""
    hem_y = m.waist_height - float(design["length"]) * m.crotch_depth
    b, front, back, pieces, stitches = _torso(design, m, hem_y, darts=bool(design["darts"]),
                                              sleeves=design["sleeve"] == "set_in")
    _collar(design, b, m, front, back, pieces, stitches)
    return _pattern("top", pieces, stitches, design)


def build_dress(design, m: BodyMeasurements) -> Pattern:
    """A dress: a bodice to the waist seam and an A-line or circle skirt sewn to it."""
    seam_y = m.waist_height - float(design["waist_seam"])
    b, front, back, pieces, stitches = _torso(design, m, seam_y, darts=bool(design["darts"]),
                                              sleeves=design["sleeve"] == "set_in")
    _collar(design, b, m, front, back, pieces, stitches)
    x_e, top_y = b.side[-1]
    hip_y = min(m.hip_height, top_y - 0.06)
    hem_y = m.waist_height - float(design["length"]) * (m.waist_height - m.ankle_height)
    fit = SkirtFit(top_y=top_y, waist=4 * x_e, hip_y=hip_y, hip=max(m.hip + float(design["ease"]), 4 * x_e),
                   hem_y=min(hem_y, hip_y - 0.06), floor_y=b.frame.floor_y, centre_z=b.frame.centre_z)
    if design["skirt"] == "a_line":
        parts = skirt_parts("a_line", {"flare": design["flare"], "darts": False}, fit)
    else:
        parts = skirt_parts("circle", {"fullness": design["fullness"], "panels": 2}, fit)
    (sf, sf_names), = parts.front_top
    (sb, sb_names), = parts.back_top
    stitches += list(parts.stitches) + [seam(front, ["hem-", "hem+"], sf, sf_names),
                                        seam(back, ["hem-", "hem+"], sb, sb_names)]
    pieces += parts.pieces
    return _pattern("dress", pieces, stitches, design)


def build_jacket(design, m: BodyMeasurements) -> Pattern:
    """An open-front jacket: two fronts, a back, set-in sleeves, and a collar or hood or neither."""
    hem_y = m.waist_height - float(design["length"]) * m.crotch_depth
    b = bd.bodice_fit(design, m, frame(m), hem_y=hem_y, ease=float(design["ease"]), fit=float(design["fit"]),
                      darts=False, sleeves=True)
    gap = float(design["opening"]) / 2
    fl = bd.bodice(b, design["neckline"], name="front_left", front=True, open_front=gap)
    fr = bd.bodice(b, design["neckline"], name="front_right", front=True, open_front=gap, right=True)
    back = bd.bodice(b, design["neckline"], name="back", front=False)
    stitches = [seam(fl, ["shoulder+"], back, ["shoulder-"]), seam(fr, ["shoulder-"], back, ["shoulder+"])]
    stitches += bd.side_stitches(fl, back, "+", "-") + bd.side_stitches(fr, back, "-", "+")
    pieces = [fl, fr, back]
    p, s = bd.sleeves(b, design, m, {"left": (fl, "+"), "right": (fr, "-")}, {"left": (back, "-"), "right": (back, "+")})
    pieces += p
    stitches += s
    kind = design["collar"]
    if kind in ("stand", "shirt", "flat"):
        strip, s = strip_collar([(fl, ["neck+"]), (back, ["neck-"]), (back, ["neck+"]), (fr, ["neck-"])],
                                float(design["collar_height"]), kind, b)
        pieces.append(strip)
        stitches += s
    elif kind == "hood":
        p, s = hood((fl, ["neck+"]), (back, ["neck-"]), (fr, ["neck-"]), (back, ["neck+"]),
                    float(design["hood_depth"]), m, b)
        pieces += p
        stitches += s
    return _pattern("jacket", pieces, stitches, design)
