"""Trousers and shorts: front and back panels per leg with a crotch curve, rise, leg width, length.

Drafted as a pattern maker does, from the waist, hip and crotch lines of the body: the front
panel is a quarter of the hip girth less 1 cm with a crotch extension of about a twentieth of it,
the back a quarter plus 1 cm with an extension of about a tenth (both grown when the thigh needs
more), so the leg's girth at the crotch line clears the thigh. Each leg hangs straight from the
crotch line to a hem on a crease line halfway across it. The side seams of front and back are the
same curve shifted by the 2 cm their widths differ by, so they match exactly; the inside leg seams
are matched by lowering the back's crotch point (as real patterns do) or, on short legs, by
moving the back hem's inner corner.
"""

from __future__ import annotations

import math

from datagen.body.measurements import BodyMeasurements
from datagen.garment.pattern.model import Pattern, Quadratic
from datagen.garment.pattern.programs.bands import band
from datagen.garment.pattern.programs.fit import frame, leg_girth, ring_radius, torso_girth
from datagen.garment.pattern.programs.outline import Seg, mirror, piece, seam
from datagen.garment.pattern.programs.space import Choice, DesignSpace, Range

__all__ = ["SHORTS_SPACE", "TROUSERS_SPACE", "build_trousers"]


def _space(length: Range) -> DesignSpace:
    return DesignSpace((
        length,
        Range(name="rise", low=0.0, high=0.08, step=0.04, unit="m", doc="waist line below the natural waist (low rise)"),
        Range(name="ease", low=0.04, high=0.12, step=0.08, unit="m", doc="girth added at the hips"),
        Range(name="hem_width", low=1.1, high=2.0, step=0.1, unit="of leg girth",
              doc="hem girth over the leg's girth at the hem: narrow to wide legs"),
        Choice(name="waistband", options=(True, False), doc="a separate band sewn to the waist"),
        Range(name="band_width", low=0.03, high=0.07, step=0.02, unit="m", doc="height of the waistband",
              when={"waistband": (True,)}),
        Choice(name="cuffs", options=(False, True), doc="a band sewn to each hem"),
        Range(name="cuff_height", low=0.03, high=0.07, step=0.02, unit="m", doc="height of a cuff",
              when={"cuffs": (True,)}),
    ))


TROUSERS_SPACE = _space(Range(name="length", low=0.75, high=1.0, step=0.05, unit="of waist-to-ankle",
                              doc="outside leg from the waist line as a share of the waist-to-ankle height"))
SHORTS_SPACE = _space(Range(name="length", low=0.35, high=0.65, step=0.05, unit="of waist-to-ankle",
                            doc="outside leg from the waist line as a share of the waist-to-ankle height"))

CROTCH_EASE = 0.025
"""The crotch line sits this far [m] below the body's crotch."""
THIGH_EASE = 0.06
"""Girth [m] a leg clears the thigh by at the crotch line."""
MIN_INSEAM = 0.04
"""Shortest inside leg seam [m]."""
BACK_RAISE = 0.025
"""The centre back waist is this much [m] higher than the front (it covers the seat)."""


def build_trousers(design, m: BodyMeasurements, name: str) -> Pattern:
    """A pair of trousers (or shorts) of ``design`` fitted to ``m``."""
    f = frame(m)
    ease = float(design["ease"])
    yw = m.waist_height - float(design["rise"])
    yc = m.crotch_height - CROTCH_EASE
    yh = min(m.hip_height, yw - 0.05)
    hip = m.hip + ease
    waist = float(torso_girth(m, yw)) + 0.02 + ease / 4
    ye = min(m.waist_height - float(design["length"]) * (m.waist_height - m.ankle_height), yc - MIN_INSEAM)
    ye = max(ye, m.ankle_height)
    need = m.thigh + THIGH_EASE - hip / 2
    ef, eb = max(hip / 20, need / 3), max(hip / 10, 2 * need / 3)
    hf, hb = hip / 4 - 0.01, hip / 4 + 0.01
    wf = min(waist / 4 - 0.01, hf)
    delta = hb - hf
    # the hem: wide enough for the leg there (and for the knee above it) times the design's width
    leg = float(leg_girth(m, ye)) * float(design["hem_width"])
    if ye < m.knee_height:  # the straight leg must pass the knee
        t = (yc - m.knee_height) / (yc - ye)
        crotch_width = hf + ef + hb + eb
        leg = max(leg, (m.knee + 0.04 - (1 - t) * crotch_width) / t)
    fhw, bhw = leg / 2 - 0.01, leg / 2 + 0.01
    xk = (hf - ef) / 2
    hi_f, ho_f = (xk - fhw / 2, ye), (xk + fhw / 2, ye)
    ho_b = (ho_f[0] + delta, ye)
    yhc = yc + 0.6 * (yw - yc)  # where the centre seam starts to curve into the crotch
    cf = (-ef, yc)

    def side(dx: float) -> list[Seg]:
        pts = [(ho_f[0] + dx, ye)]
        names = []
        if ye < yc - 0.02:
            pts.append((hf + dx, yc))
            names.append("out_lo")
        names.append("out_mid")
        return ([Seg(p, None, n) for p, n in zip(pts, names)]
                + [Seg((hf + dx, yh), Quadratic(control=(hf + dx, yh + 0.6 * (yw - yh))), "out_hi")])

    front = ([Seg(hi_f, None, "hem", "hem")] + side(0.0)
             + [Seg((wf, yw), None, "waist", "waist"), Seg((0.0, yw), None, "cf_hi", "crotch"),
                Seg((0.0, yhc), Quadratic(control=(0.0, yc)), "cf_lo", "crotch"), Seg(cf, None, "inseam", "inseam")])
    inseam = math.dist(cf, hi_f)
    # back: the inside leg matches the front's by lowering the crotch point, or moving the hem's corner
    hi_b = (ho_b[0] - bhw, ye)
    dx = hi_b[0] + eb
    ycb = ye + math.sqrt(max(inseam**2 - dx**2, 0.0))
    if not (inseam > dx and max(yc - 0.04, ye + 0.01) <= ycb <= yc + 0.005):
        ycb = yc - 0.01
        hi_b = (-eb + math.sqrt(max(inseam**2 - (ycb - ye) ** 2, 0.0)), ye)
    cb = (-eb, ycb)
    back = ([Seg(hi_b, None, "hem", "hem")] + side(delta)
            + [Seg((wf + delta, yw), None, "waist", "waist"), Seg((0.02, yw + BACK_RAISE), None, "cb_hi", "crotch"),
               Seg((0.0, yhc), Quadratic(control=(0.0, ycb)), "cb_lo", "crotch"), Seg(cb, None, "inseam", "inseam")])

    dz = ring_radius(hip)
    tf = (0.0, f.floor_y, f.centre_z + dz)
    tb = (0.0, f.floor_y, f.centre_z - dz)
    back_rot = (0.0, 180.0, 0.0)
    # each leg's panels are bent round their own leg when placed (limb): laid flat in front of both
    # legs, a front panel's crotch extension lies on the other leg's panel and is dragged through it
    fl = piece("front_left", front, translation=tf, limb=True)
    fr = piece("front_right", mirror(front, front[0].start)[0], translation=tf, limb=True)
    bl = piece("back_left", mirror(back, back[0].start)[0], translation=tb, rotation=back_rot, limb=True)
    br = piece("back_right", back, translation=tb, rotation=back_rot, limb=True)
    out = [n for n in ("out_lo", "out_mid", "out_hi") if n in fl.index]
    stitches = [
        seam(fl, ["cf_hi", "cf_lo"], fr, ["cf_lo", "cf_hi"]),
        seam(br, ["cb_hi", "cb_lo"], bl, ["cb_lo", "cb_hi"]),
        seam(fl, ["inseam"], bl, ["inseam"]), seam(fr, ["inseam"], br, ["inseam"]),
        seam(fl, out, bl, out[::-1]), seam(br, out, fr, out[::-1]),
    ]
    pieces = [fl, fr, bl, br]
    if design["waistband"]:
        w = float(design["band_width"])
        ft, s1 = band("waistband_front", [(fr, ["waist"]), (fl, ["waist"])], w, top_group="waist",
                      translation=(-(fl.length("waist") + fr.length("waist")) / 2, f.floor_y + yw, f.centre_z + dz + 0.01),
                      rotation=(0.0, 0.0, 0.0))
        bt, s2 = band("waistband_back", [(bl, ["waist"]), (br, ["waist"])], w, top_group="waist",
                      translation=((bl.length("waist") + br.length("waist")) / 2, f.floor_y + yw, f.centre_z - dz - 0.01),
                      rotation=back_rot)
        pieces += [ft, bt]
        stitches += s1 + s2 + [seam(ft, ["end+"], bt, ["end-"]), seam(bt, ["end+"], ft, ["end-"])]
    if design["cuffs"]:
        h = float(design["cuff_height"])
        for leg_name, fp, bp in (("left", fl, bl), ("right", fr, br)):
            cf_, s1 = band(f"cuff_{leg_name}_front", [(fp, ["hem"])], h, top_group="hem")
            cb_, s2 = band(f"cuff_{leg_name}_back", [(bp, ["hem"])], h, top_group="hem")
            pieces += [cf_, cb_]
            stitches += s1 + s2 + [seam(cf_, ["end+"], cb_, ["end-"]), seam(cb_, ["end+"], cf_, ["end-"])]
    return Pattern(name=name, panels=tuple(p.panel for p in pieces), stitches=tuple(stitches), design=dict(design))
