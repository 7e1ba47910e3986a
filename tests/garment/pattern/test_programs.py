"""Pattern programs: every program builds on the thin/regular/fat bodies, deterministically, fits
the body it was built for, honours overrides, refuses unknown names clearly, and counts its designs."""

from __future__ import annotations

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.garment.pattern.model import Pattern
from datagen.garment.pattern.programs import PROGRAMS, count_designs, design_of, make_pattern
from datagen.garment.pattern.programs.space import Choice, DesignSpace, Range

SEEDS = range(4)
BODIES = ("thin", "regular", "fat")


@pytest.fixture(scope="session")
def measurements(default_body):
    from datagen.body.measurements import measure_body
    from datagen.body.shapes import preset_betas

    return {name: measure_body(default_body, preset_betas(default_body, name)) for name in BODIES}


def _edges(pattern: Pattern, group: str) -> float:
    """Total length [m] of the edges in ``group`` over all panels."""
    return sum(p.edge_length(i) for p in pattern.panels for i in p.edge_groups.get(group, ()))


def _width_at(panel, y: float) -> float:
    """Width [m] of ``panel``'s outline along the horizontal line at height ``y`` (panel space)."""
    o = panel.outline(0.002)
    a, b = o, np.roll(o, -1, axis=0)
    cross = (a[:, 1] - y) * (b[:, 1] - y) <= 0
    t = (y - a[cross, 1]) / np.where(b[cross, 1] == a[cross, 1], 1.0, b[cross, 1] - a[cross, 1])
    xs = a[cross, 0] + t * (b[cross, 0] - a[cross, 0])
    return float(xs.max() - xs.min())


@pytest.mark.parametrize("name", list(PROGRAMS))
def test_every_program_builds_on_every_body(name, measurements):
    """Seeds 0..3 on three bodies: the model validates each outline (closed, counter-clockwise, not
    self-crossing) and each stitch (equal sides, no edge sewn twice) on construction."""
    bad = []
    for body, m in measurements.items():
        for seed in SEEDS:
            p = make_pattern(name, seed, m)
            assert isinstance(p, Pattern) and p.design == design_of(name, seed)
            groups = {g for panel in p.panels for g in panel.edge_groups}
            assert "hem" in groups or "cuff" in groups, (name, body, seed, groups)
            for s in p.stitches:
                # Hoods and collar strips are placed flat beside the head and behind the neck and
                # meet the fronts only once wrapped: a seam of theirs to the bodice joins edges on
                # the same side of the body (left or right)
                neck = [side.panel.startswith(("hood", "collar")) for side in (s.a, s.b)]
                if any(neck):
                    xa, xb = _middle_x(p, s.a), _middle_x(p, s.b)
                    if not all(neck) and min(abs(xa), abs(xb)) > 0.03 and xa * xb < 0:
                        bad.append((body, seed, s.describe(), "left/right"))
                    continue
                # elsewhere the ends a stitch's orientation pairs up are the nearer ones, placed
                # around the body (unrolled about its vertical axis); seams under 10 cm (a dart, a
                # short inside leg) do not decide
                if min(s.a.length(p), s.b.length(p)) < 0.1:
                    continue
                a, b = _unrolled(p, s.a, m), _unrolled(p, s.b, m)
                if s.reversed:
                    b = b[::-1]
                if _gap(a[0], b[0]) + _gap(a[1], b[1]) > _gap(a[0], b[1]) + _gap(a[1], b[0]):
                    bad.append((body, seed, s.describe()))
    assert not bad, bad


def _unrolled(pattern: Pattern, side, m) -> np.ndarray:
    """A seam side's first and last points placed in 3D, as (angle about the body's axis [rad],
    height [m]): [2, 2]."""
    panel = pattern.panel(side.panel)
    first = panel.vertices[panel.edges[side.edges[0]].start]
    last = panel.vertices[panel.edges[side.edges[-1]].end]
    p = panel.to_3d(np.asarray([first, last]))
    return np.stack([np.arctan2(p[:, 0], p[:, 2] - m.centre_z), p[:, 1]], axis=1)


def _middle_x(pattern: Pattern, side) -> float:
    """Body X [m] of the middle of a seam side's edges, placed."""
    panel = pattern.panel(side.panel)
    pts = np.concatenate([panel.edges[i].sample(panel, 9) for i in side.edges])
    return float(panel.to_3d(pts)[:, 0].mean())


def _gap(p, q, radius: float = 0.15) -> float:
    """Distance [m] between two unrolled points on a cylinder of ``radius`` round the body."""
    turn = (p[0] - q[0] + np.pi) % (2 * np.pi) - np.pi
    return float(np.hypot(radius * turn, p[1] - q[1]))


@pytest.mark.parametrize("name", ["skirt_gored", "top", "jacket", "trousers"])
def test_the_seed_decides_the_design(name, measurements):
    m = measurements["regular"]
    a, b = make_pattern(name, 7, m), make_pattern(name, 7, m)
    assert a.design == b.design
    assert [p.vertices for p in a.panels] == [p.vertices for p in b.panels]
    assert [(s.a, s.b, s.reversed) for s in a.stitches] == [(s.a, s.b, s.reversed) for s in b.stitches]
    assert len({repr(sorted(design_of(name, s).items())) for s in range(10)}) == 10


def test_overriding_one_parameter_keeps_the_others(measurements):
    base = design_of("top", 3)
    other = design_of("top", 3, collar="hood", hood_depth=0.3)
    assert other["collar"] == "hood" and other["hood_depth"] == 0.3
    assert all(other[k] == v for k, v in base.items() if k not in ("collar", "hood_depth", "collar_height"))


def test_skirt_waist_is_the_body_waist_plus_ease(measurements):
    for body, m in measurements.items():
        for name in ("skirt_straight", "skirt_a_line", "skirt_circle", "skirt_gored"):
            p = make_pattern(name, 1, m, rise=0.0, ease=0.05, waistband=False)
            assert _edges(p, "waist") == pytest.approx(m.waist + 0.05, rel=0.01), (name, body)


def test_skirt_clears_the_hips(measurements):
    for body, m in measurements.items():
        for name in ("skirt_straight", "skirt_a_line"):
            p = make_pattern(name, 2, m, ease=0.04, waistband=False)
            y = min(m.hip_height, m.waist_height - p.design["rise"] - 0.06)
            girth = sum(_width_at(panel, y) for panel in p.panels)  # front and back panels round the hips
            assert girth >= m.hip + 0.04 - 0.005, (name, body, girth, m.hip)


def test_trousers_fit_the_legs(measurements):
    for body, m in measurements.items():
        for name in ("trousers", "shorts"):
            for seed in SEEDS:
                p = make_pattern(name, seed, m, cuffs=False)
                front, back = p.panel("front_left"), p.panel("back_left")
                (ins,) = front.edge_groups["inseam"]
                assert front.edge_length(ins) <= m.inseam, (name, body, seed)
                crotch = front.vertices[front.edges[ins].start]
                assert crotch[1] < m.crotch_height  # the crotch line is below the body's
                leg = _width_at(front, crotch[1] + 1e-4) + _width_at(back, crotch[1] + 1e-4)
                assert leg >= m.thigh, (name, body, seed, leg, m.thigh)
                waist = _edges(p, "waist")
                assert waist >= m.waist - 0.02 * m.waist, (name, body, seed)  # low rise sits lower and wider


def test_bodice_girth_is_chest_plus_ease_and_sleeves_reach(measurements):
    for body, m in measurements.items():
        p = make_pattern("top", 0, m, ease=0.12, sleeve="set_in", sleeve_length=0.6, cuffs=False)
        front = p.panel("bodice_front")
        ends = [front.vertices[front.edges[i].start] for i in front.edge_groups["armhole"]]
        ends += [front.vertices[front.edges[i].end] for i in front.edge_groups["armhole"]]
        xs = [x for x, y in ends if y == min(y for _, y in ends)]
        assert 2 * (max(xs) - min(xs)) == pytest.approx(m.chest + 0.12, rel=1e-6), body
        sleeve = p.panel("sleeve_left_front")  # along the arm (body X) from the shoulder point, placed
        x1 = sleeve.to_3d(np.asarray(sleeve.vertices))[:, 0].max()
        assert x1 - front.vertices[front.edges[front.edge_groups["armhole"][0]].end][0] == pytest.approx(
            0.6 * m.arm_length, rel=1e-6)
        assert 2 * _edges(p, "cuff") >= m.wrist  # a sleeve's end goes round the arm there


def test_overrides_are_honoured(measurements):
    m = measurements["fat"]
    p = make_pattern("skirt_circle", 0, m, fullness=0.75, panels=4, waistband=False)
    assert p.design["fullness"] == 0.75 and p.design["panels"] == 4
    assert sum(panel.name.startswith("skirt_panel") for panel in p.panels) == 4
    p = make_pattern("skirt_gored", 0, m, gores="8", godets="true", godet_height=0.2, godet_width=0.15)
    assert sum(panel.name.startswith("skirt_godet") for panel in p.panels) == 8
    p = make_pattern("jacket", 5, m, collar="none")
    assert not any("collar" in panel.name or "hood" in panel.name for panel in p.panels)
    p = make_pattern("top", 5, m, sleeve="none")
    assert not any(panel.name.startswith("sleeve") for panel in p.panels)
    p = make_pattern("dress", 5, m, skirt="circle", fullness=1.0)
    assert sum(panel.name.startswith("skirt_panel") for panel in p.panels) == 2


def test_unknown_names_and_values_are_clear_errors(measurements):
    m = measurements["regular"]
    with pytest.raises(InputError, match="unknown pattern program 'cape'.*skirt_circle"):
        make_pattern("cape", 0, m)
    with pytest.raises(InputError, match="no design parameter 'sleeves'.*sleeve_length"):
        make_pattern("top", 0, m, sleeves=True)
    with pytest.raises(InputError, match=r"'fullness'.*allowed range is \[0.5, 1\]"):
        make_pattern("skirt_circle", 0, m, fullness=2.0)
    with pytest.raises(InputError, match="'neckline'.*round, v, boat, scoop"):
        make_pattern("top", 0, m, neckline="sweetheart")
    with pytest.raises(InputError, match="'cuff_height'.*applies only when"):
        make_pattern("top", 0, m, sleeve="none", cuff_height=0.05)
    with pytest.raises(InputError, match="seed"):
        make_pattern("top", -1, m)
    with pytest.raises(InputError, match="BodyMeasurements"):
        make_pattern("top", 0, {"chest": 1.0})


def test_design_count_follows_the_declared_spaces():
    space = DesignSpace((
        Choice(name="a", options=("x", "y"), doc=""),
        Range(name="r", low=0.0, high=0.2, step=0.05, unit="m", doc="", when={"a": ("x",)}),
        Choice(name="b", options=(False, True), doc="", when={"a": ("y",)}),
        Range(name="s", low=1.0, high=1.5, step=0.1, unit="", doc="", when={"b": (True,)}),
    ))
    # a=x: 5 bins of r (b does not apply); a=y: b=False 1, b=True 6 bins of s
    assert space.count() == 5 + 1 + 6
    counts = count_designs()
    # skirt_circle by hand: rise 2 x ease 1 x (no band 1 + band 3 widths) x length 15 x fullness 5 x panels 2
    assert counts["skirt_circle"] == 2 * 1 * 4 * 15 * 5 * 2
    assert sum(counts.values()) >= 1000
    coarse = count_designs(coarse=True)
    assert all(coarse[k] <= counts[k] for k in counts)


def test_counting_some_ranges_only():
    lengths = count_designs(ranges=("length",))
    # skirt_circle's choices (band or not x 2 or 4 panels) times its 15 lengths
    assert lengths["skirt_circle"] == 2 * 2 * 15
    assert count_designs(coarse=True)["skirt_circle"] == 4 <= lengths["skirt_circle"] <= count_designs()["skirt_circle"]
