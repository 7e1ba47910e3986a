"""Bodices: front and back torso panels with necklines, armholes, shoulders, optional bust darts,
and the set-in sleeves that fit their armholes.

Drafted flat in the T-pose's frontal plane (panel x = the body's X on a front panel, y = height
above the floor): the neck side point at the neck's radius plus the neckline's width, the shoulder
point over the body's, the underarm point at a quarter of the chest girth plus
ease, the side seam down through the waist and hip at a quarter of the girth there plus ease (as
tight as the design's ``fit`` asks, never tighter than the body), the hem at the design's length.
The shoulder and bust points are the body's measured landmarks (``shoulder_x``, ``bust_x``).

Sleeves: the arm is horizontal in the rest pose, so a sleeve's front and back halves lie in the
bodice's planes and their cap is the armhole's own curve (the same length by construction); the
sleeve runs along the arm to its length, its girth at the end the arm's girth there times the
design's width, never less than the hand needs.

A bust dart is a V in the front's side seam pointing at the bust point: the front below it is
longer by the dart's intake, so the side seams of front and back match above and below the dart
exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from datagen.body.measurements import BodyMeasurements
from datagen.garment.pattern.model import Cubic, Quadratic, Stitch, euler_xyz_matrix
from datagen.garment.pattern.programs.bands import band
from datagen.garment.pattern.programs.fit import Frame, arm_girth, ring_radius, torso_girth
from datagen.garment.pattern.programs.outline import Piece, Seg, mirror, piece, seam, shift, turn
from datagen.garment.pattern.programs.space import Choice, DesignSpace, Range

__all__ = ["BodiceFit", "NECKLINES", "bodice", "bodice_fit", "neckline_space", "sleeve_space", "sleeves"]

NECKLINES = {
    # depth below the front neck point [m] and extra width of the opening [m], each (low, high)
    "round": ((0.0, 0.05), (0.0, 0.03)),
    "v": ((0.07, 0.2), (0.0, 0.03)),
    "boat": ((-0.005, 0.02), (0.05, 0.09)),
    "scoop": ((0.05, 0.14), (0.02, 0.06)),
}
"""Necklines and their ranges; a design picks a point in each range (``neck_depth``, ``neck_width``
from 0 to 1)."""

BACK_NECK_DROP = 0.02
"""Depth [m] of the back neckline below the neck side points."""
HAND_GIRTH_FACTOR = 1.45
"""A sleeve's end (without a cuff opening) is at least this many wrist girths around (a hand passes)."""
DART_SHORT = 0.02
"""A bust dart's point stops this far [m] short of the bust point."""


def neckline_space(options=tuple(NECKLINES)) -> DesignSpace:
    return DesignSpace((
        Choice(name="neckline", options=options, doc="shape of the front neckline"),
        Range(name="neck_depth", low=0.0, high=1.0, step=1.0, unit="of the neckline's range",
              doc="how deep the front neckline is within its shape's range (round 0-5 cm, V 7-20 cm, "
                  "boat 0-2 cm, scoop 5-14 cm below the front neck point)"),
        Range(name="neck_width", low=0.0, high=1.0, step=1.0, unit="of the neckline's range",
              doc="how wide the neckline is within its shape's range (round and V 0-3 cm, boat 5-9 cm, "
                  "scoop 2-6 cm wider than the neck)"),
    ))


def sleeve_space(lengths=(0.2, 1.0), allow_none: bool = True) -> DesignSpace:
    params = []
    if allow_none:
        params += [Choice(name="sleeve", options=("set_in", "none"), doc="set-in sleeves or sleeveless"),
                   Range(name="armhole_drop", low=0.02, high=0.08, step=0.03, unit="m",
                         doc="sleeveless armhole below the armpit", when={"sleeve": ("none",)}),
                   Range(name="strap", low=0.0, high=0.06, step=0.03, unit="m",
                         doc="sleeveless shoulder narrowed by", when={"sleeve": ("none",)})]
    when = {"sleeve": ("set_in",)} if allow_none else {}
    params += [
        Range(name="sleeve_length", low=lengths[0], high=lengths[1], step=0.1, unit="of arm length",
              doc="sleeve along the top of the arm from the shoulder point (0.1 is about 5 cm)", when=when),
        Range(name="sleeve_width", low=1.1, high=1.7, step=0.1, unit="of arm girth",
              doc="girth at the sleeve's end over the arm's girth there", when=when),
        Choice(name="cuffs", options=(False, True), doc="a band sewn to each sleeve's end", when=when),
        Range(name="cuff_height", low=0.03, high=0.07, step=0.02, unit="m", doc="height of a cuff",
              when={**when, "cuffs": (True,)}),
    ]
    return DesignSpace(tuple(params))


@dataclass(frozen=True, kw_only=True)
class BodiceFit:
    """The landmarks of one bodice on one body [m], panel space (x from the middle, y height)."""

    neck_x: float         # half width of the neck opening at the neck side points
    neck_y: float         # height of the neck side points
    front_neck_y: float   # height of the front neckline at the centre
    back_neck_y: float
    shoulder: tuple[float, float]
    underarm: tuple[float, float]
    side: tuple[tuple[float, float], ...]  # side seam below the underarm, top to bottom (the hem last)
    dart_intake: float    # 0 without a bust dart
    bust_x: float
    chest: float          # the bodice's girth at the underarm [m]
    frame: Frame


def _neck(design, m: BodyMeasurements) -> tuple[float, float]:
    (d0, d1), (w0, w1) = NECKLINES[design["neckline"]]
    depth = d0 + float(design["neck_depth"]) * (d1 - d0)
    width = w0 + float(design["neck_width"]) * (w1 - w0)
    return depth, width


def bodice_fit(design, m: BodyMeasurements, frame: Frame, *, hem_y: float, ease: float, fit: float,
               darts: bool, sleeves: bool) -> BodiceFit:
    """Landmarks of a bodice on ``m``: girth ``ease`` [m] added, ``fit`` from 0 (boxy below the
    chest) to 1 (following the body), hem at ``hem_y`` [m above the floor]."""
    y_ns = m.shoulder_height + 0.5 * (m.neck_height - m.shoulder_height)
    x_s = m.shoulder_x
    y_s = m.shoulder_height - 0.01
    if sleeves:
        depth = max(0.4 * m.armhole, (m.upper_arm + 0.06) / 2)
        y_u = y_s - depth
    else:
        x_s -= float(design.get("strap", 0.0))
        y_u = min(m.armpit_height - float(design.get("armhole_drop", 0.04)), y_s - 0.08)
    x_u = max((m.chest + ease) / 4, x_s + 0.03)  # (broad shoulders over a narrow chest: the armhole still slopes out)
    depth, width = _neck(design, m)
    x_n = min(m.neck / (2 * math.pi) + 0.01 + width, x_s - 0.03)
    hem_y = min(hem_y, y_u - 0.12)

    def half_width(y: float) -> float:
        need = (float(torso_girth(m, y)) + ease) / 4
        return max(need, (1 - fit) * x_u + fit * need)

    levels = [y for y in (m.waist_height, min(m.hip_height, m.waist_height - 0.1)) if y > hem_y + 0.03 and y < y_u - 0.1]
    side = [(half_width(y), y) for y in levels] + [(half_width(hem_y), hem_y)]
    intake = float(np.clip(0.4 * (m.chest - m.underbust), 0.015, 0.04)) if darts else 0.0
    y_d = y_u - 0.04  # where the dart meets the side seam
    y_cf = max(m.front_neck_height - depth, y_d + 0.03, y_u + 0.04)
    y_cf = min(y_cf, y_ns - 0.005)
    return BodiceFit(neck_x=x_n, neck_y=y_ns, front_neck_y=y_cf, back_neck_y=y_ns - BACK_NECK_DROP,
                     shoulder=(x_s, y_s), underarm=(x_u, y_u), side=tuple(side), dart_intake=intake,
                     bust_x=m.bust_x + DART_SHORT, chest=4 * x_u, frame=frame)


def armhole_curve(b: BodiceFit) -> Cubic:
    """The armhole from the underarm point up to the shoulder point (a bodice's ``+`` side)."""
    (x_s, y_s), (x_u, y_u) = b.shoulder, b.underarm
    depth = y_s - y_u
    return Cubic(control1=(x_u - 0.55 * (x_u - x_s), y_u), control2=(x_s - 0.01, y_u + 0.45 * depth))


def _neckline(kind: str, n: tuple, y_c: float) -> Quadratic | Cubic | None:
    """The neckline's right half from the neck side point ``n`` to the centre at height ``y_c``."""
    x_n, y_n = n
    if kind == "v":
        return None
    if kind == "boat":
        return Quadratic(control=(0.6 * x_n, y_c))
    if kind == "scoop":
        return Cubic(control1=(x_n, y_n - 0.7 * (y_n - y_c)), control2=(0.5 * x_n, y_c))
    return Quadratic(control=(x_n, y_c))


def _side(b: BodiceFit, front: bool) -> list[Seg]:
    """The side seam from the hem up to the underarm (``+`` side), split where the dart meets it."""
    x_u, y_u = b.underarm
    pts = list(b.side[::-1])  # hem first, going up
    nxt = b.side[0]
    y_d = y_u - 0.04
    t = (y_u - y_d) / (y_u - nxt[1])
    d1 = (x_u + t * (nxt[0] - x_u), y_d)
    low = [Seg(p, None, f"side{len(pts) - 1 - k}+") for k, p in enumerate(pts)]
    if front and b.dart_intake:
        i = b.dart_intake
        low = shift(low, dy=-i)
        apex = (b.bust_x, y_d - i / 2)
        return low + [Seg((d1[0], d1[1] - i), None, "dart_a+"), Seg(apex, None, "dart_b+"),
                      Seg(d1, None, "side_top+")]
    return low + [Seg(d1, None, "side_top+")]


def bodice(b: BodiceFit, neckline: str, *, name: str, front: bool, open_front: float | None = None,
           right: bool = False) -> Piece:
    """A front or back bodice panel. ``open_front``: a front cut in two at the centre with each
    half's centre edge this far [m] from the middle: the body-left half, or with ``right`` its
    mirror, the body-right half."""
    hem_y = b.side[-1][1] - (b.dart_intake if front else 0.0)
    centre_x = open_front or 0.0
    segs = [Seg((centre_x, hem_y), None, "hem+", "hem")] + _side(b, front)  # the side starts at the hem's end
    x_s, y_s = b.shoulder
    n = (b.neck_x, b.neck_y)
    segs += [Seg(b.underarm, armhole_curve(b), "armhole+", "armhole"), Seg((x_s, y_s), None, "shoulder+")]
    if front:
        y_c = b.front_neck_y
        segs.append(Seg(n, _neckline(neckline, n, y_c) if open_front is None else
                        _open_neckline(neckline, n, y_c, centre_x), "neck+", "neckline"))
    else:
        y_c = b.back_neck_y
        segs.append(Seg(n, Quadratic(control=(b.neck_x, y_c)), "neck+", "neckline"))
    d = ring_radius(b.chest)
    f = b.frame
    if front:
        place = {"translation": (0.0, f.floor_y, f.centre_z + d)}
    else:
        place = {"translation": (0.0, f.floor_y, f.centre_z - d), "rotation": (0.0, 180.0, 0.0)}
    if open_front is not None:
        segs.append(Seg((centre_x, y_c), None, "front_edge", "front_edge"))
        if right:
            segs, _ = mirror(segs, segs[0].start)
        return piece(name, segs, **place)
    other, _ = mirror(segs, (0.0, y_c))
    return piece(name, segs + other, **place)


def _open_neckline(kind: str, n: tuple, y_c: float, x_c: float):
    """An open front's neckline from the neck side point to the top of the front edge at ``x_c``."""
    x_n, y_n = n
    if kind == "v":
        return None
    if kind == "scoop":
        return Cubic(control1=(x_n, y_n - 0.7 * (y_n - y_c)), control2=(x_c + 0.5 * (x_n - x_c), y_c))
    return Quadratic(control=(x_n, y_c))


def side_stitches(front: Piece, back: Piece, front_side: str, back_side: str) -> list[Stitch]:
    """The side seam of ``front``'s ``front_side`` ("+" or "-") to ``back``'s ``back_side``,
    above and below the dart point."""
    fs, bs = front_side, back_side
    low = sorted((n for n in front.index if n.startswith("side") and n[4:-1].isdigit() and n.endswith(fs)),
                 key=lambda n: -int(n[4:-1]))
    f_low = low if fs == "+" else low[::-1]
    b_names = [n[:-1] + bs for n in low]
    b_low = b_names if bs == "+" else b_names[::-1]
    return [seam(front, [f"side_top{fs}"], back, [f"side_top{bs}"]), seam(front, f_low, back, b_low)]


def _euler(r: np.ndarray) -> tuple[float, float, float]:
    from scipy.spatial.transform import Rotation

    return tuple(float(a) for a in Rotation.from_matrix(r).as_euler("xyz", degrees=True))


_FRONT_SLEEVE = _euler(euler_xyz_matrix((0.0, 0.0, -90.0)))
_BACK_SLEEVE = _euler(euler_xyz_matrix((0.0, 180.0, 0.0)) @ euler_xyz_matrix((0.0, 0.0, -90.0)))
"""Rotations (XYZ Euler, degrees) of a sleeve's front and back halves, drawn turned a quarter."""


def sleeves(b: BodiceFit, design, m: BodyMeasurements, fronts: dict[str, tuple[Piece, str]],
            backs: dict[str, tuple[Piece, str]]) -> tuple[list[Piece], list[Stitch]]:
    """Set-in sleeves (front and back halves per arm, and cuffs) sewn into the armholes.

    ``fronts``/``backs`` map "left"/"right" to the bodice panel holding that arm's front/back
    armhole and the armhole's side ("+"/"-") on it."""
    (x_s, y_s), (x_u, y_u) = b.shoulder, b.underarm
    top_len = max(float(design["sleeve_length"]) * m.arm_length, (x_u - x_s) + 0.03)
    x_c = x_s + top_len
    t = min(top_len / m.arm_length, 1.0)
    girth = max(float(arm_girth(m, t)) * float(design["sleeve_width"]), HAND_GIRTH_FACTOR * m.wrist,
                float(arm_girth(m, t)) + 0.04)
    y_a = m.shoulder_height - m.upper_arm / (2 * math.pi)  # the arm's axis (horizontal in the rest pose)
    c = armhole_curve(b)
    cap = Cubic(control1=c.control2, control2=c.control1)
    segs = [Seg((x_s, y_s), cap, "cap", "armhole"), Seg((x_u, y_u), None, "under"),
            Seg((x_c, y_a - girth / 4), None, "end", "cuff"), Seg((x_c, y_a + girth / 4), None, "top")]
    mirrored, _ = mirror(segs, (x_s, y_s))
    # turned a quarter so that the arm runs along panel y (the axis a wrapped panel bends round):
    # placed with Rz(-90) first, the halves land where they were drawn
    segs, mirrored = turn(segs), turn(mirrored)
    f = b.frame
    dz = ring_radius(0.5 * (2 * (y_s - y_u) + girth))  # the sleeve's mean girth round the arm
    front_t = (0.0, f.floor_y, f.centre_z + dz)
    back_t = (0.0, f.floor_y, f.centre_z - dz)
    pieces, stitches = [], []
    for arm in ("left", "right"):
        # the body-left arm's front half is drawn as is; its back half, seen from behind, mirrored;
        # the grain runs along the arm
        sf = piece(f"sleeve_{arm}_front", segs if arm == "left" else mirrored, translation=front_t,
                   rotation=_FRONT_SLEEVE, grain=(0.0, 1.0))
        sb = piece(f"sleeve_{arm}_back", mirrored if arm == "left" else segs, translation=back_t,
                   rotation=_BACK_SLEEVE, grain=(0.0, 1.0))
        (fp, fside), (bp, bside) = fronts[arm], backs[arm]
        stitches += [seam(sf, ["top"], sb, ["top"]), seam(sf, ["under"], sb, ["under"]),
                     seam(fp, [f"armhole{fside}"], sf, ["cap"]), seam(bp, [f"armhole{bside}"], sb, ["cap"])]
        pieces += [sf, sb]
        if design.get("cuffs"):
            h = float(design["cuff_height"])
            cf, s1 = band(f"cuff_{arm}_front", [(sf, ["end"])], h, top_group="cuff")
            cb, s2 = band(f"cuff_{arm}_back", [(sb, ["end"])], h, top_group="cuff")
            pieces += [cf, cb]
            stitches += s1 + s2 + [seam(cf, ["end+"], cb, ["end-"]), seam(cb, ["end+"], cf, ["end-"])]
    return pieces, stitches
