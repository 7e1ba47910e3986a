"""Collars and hoods sewn to a bodice's neckline.

- A stand collar is a straight band around the neckline (two halves on a closed neckline, one
  strip from one front edge round the back to the other on an open front).
- A shirt or flat collar is that strip bent into an arch: its neck edge is an arc of radius
  ``length / angle``, so its outer edge is longer and it turns down over the shoulders (a quarter
  circle for a shirt collar, three fifths of a circle for a flat, Peter Pan-like one).
- A hood is two side panels in the body's sagittal plane, sewn together along the back and over
  the head, their bottom edges sewn to the neckline from the centre front to the centre back.
"""

from __future__ import annotations

import math

import numpy as np

from datagen.garment.pattern.model import Arc, Cubic, Stitch
from datagen.body.measurements import BodyMeasurements
from datagen.garment.pattern.programs.bodice import BodiceFit
from datagen.garment.pattern.programs.outline import Piece, Seg, mirror, piece, seam
from datagen.garment.pattern.programs.bands import Target, band

__all__ = ["COLLAR_ANGLES", "hood", "ring_collar", "strip_collar"]

COLLAR_ANGLES = {"stand": 0.0, "shirt": 0.5 * math.pi, "flat": 1.2 * math.pi}
"""Angle [rad] a collar strip's neck edge turns through (0: straight)."""

HOOD_EASE = 0.06
"""Height [m] a hood reaches above the head."""


def ring_collar(front: list[Target], back: list[Target], height: float, b: BodiceFit) -> tuple[list[Piece], list[Stitch]]:
    """A stand collar on a closed neckline: front and back halves joined at the sides."""
    f = b.frame
    r = b.neck_x + 0.03
    lf = sum(p.length(*n) for p, n in front)
    lb = sum(p.length(*n) for p, n in back)
    cf, s1 = band("collar_front", front, height, top_group="collar", rotation=(0.0, 0.0, 0.0),
                  translation=(-lf / 2, f.floor_y + b.neck_y, f.centre_z + r))
    cb, s2 = band("collar_back", back, height, top_group="collar", rotation=(0.0, 180.0, 0.0),
                  translation=(lb / 2, f.floor_y + b.neck_y, f.centre_z - r))
    return [cf, cb], s1 + s2 + [seam(cf, ["end+"], cb, ["end-"]), seam(cb, ["end+"], cf, ["end-"])]


def strip_collar(targets: list[Target], height: float, style: str, b: BodiceFit) -> tuple[Piece, list[Stitch]]:
    """One collar strip sewn along ``targets`` (in order round the body, seen from outside: from
    the body-left front edge round the back to the body-right one), straight or arched."""
    angle = COLLAR_ANGLES[style]
    lengths = [p.length(*n) for p, n in targets]
    total = float(sum(lengths))
    f = b.frame
    place = {"rotation": (0.0, 180.0, 0.0),
             "translation": (total / 2, f.floor_y + b.neck_y, f.centre_z - b.neck_x - 0.03)}
    if angle == 0.0:
        strip, stitches = band("collar", targets, height, top_group="collar", **place)
        return strip, stitches
    radius = total / angle
    # neck edge: clockwise over the top of a circle centred below the strip's middle
    s = np.concatenate([[0.0], np.cumsum(lengths)])
    theta = math.pi / 2 + angle / 2 - s / radius
    cx, cy = total / 2, -radius

    def at(r, t):
        return (cx + r * math.cos(t), cy + r * math.sin(t))

    segs = [Seg(at(radius, theta[k]), Arc(radius=radius, large_arc=False, right=False), f"bottom{k}", "seam")
            for k in range(len(targets))]
    outer = radius + height
    segs.append(Seg(at(radius, theta[-1]), None, "end+"))
    # the outer edge counter-clockwise back to the start, in two arcs (each under 180 degrees)
    segs.append(Seg(at(outer, theta[-1]), Arc(radius=outer, large_arc=False, right=True), "top_a", "collar"))
    segs.append(Seg(at(outer, math.pi / 2), Arc(radius=outer, large_arc=False, right=True), "top_b", "collar"))
    segs.append(Seg(at(outer, theta[0]), None, "end-"))
    strip = piece("collar", segs, grain=(1.0, 0.0), **place)
    return strip, [seam(strip, [f"bottom{k}"], p, n) for k, (p, n) in enumerate(targets)]


def hood(front_left: Target, back_left: Target, front_right: Target, back_right: Target, depth: float,
         m: BodyMeasurements, b: BodiceFit) -> tuple[list[Piece], list[Stitch]]:
    """A two-panel hood. Each side's bottom edge runs from the centre front to the centre back and
    is sewn to the neckline there: ``front_*`` is the front neckline from the neck side point to
    the centre, ``back_*`` the back neckline from the centre back to the neck side point."""
    lf = front_left[0].length(*front_left[1])
    lb = back_left[0].length(*back_left[1])
    length = lf + lb
    height = m.height - b.neck_y + HOOD_EASE
    depth = max(depth, length + 0.04)
    top = (0.03, height)
    segs = [Seg((0.0, 0.0), None, "neck_front"), Seg((lf, 0.0), None, "neck_back"),
            Seg((length, 0.0), Cubic(control1=(depth, 0.35 * height), control2=(depth, height)), "back_seam"),
            Seg(top, Cubic(control1=(-0.02, 0.66 * height), control2=(-0.02, 0.33 * height)), "face", "hood_opening")]
    other, _ = mirror(segs, (0.0, 0.0))
    f = b.frame
    x = b.neck_x + 0.04
    z = f.centre_z + b.neck_x + 0.02
    left = piece("hood_left", segs, rotation=(0.0, 90.0, 0.0), translation=(x, f.floor_y + b.neck_y, z))
    right = piece("hood_right", other, rotation=(0.0, -90.0, 0.0), translation=(-x, f.floor_y + b.neck_y, z))
    stitches = [seam(left, ["back_seam"], right, ["back_seam"]),
                seam(left, ["neck_front"], *front_left), seam(left, ["neck_back"], *back_left),
                seam(right, ["neck_back"], *back_right), seam(right, ["neck_front"], *front_right)]
    return [left, right], stitches
