"""The pattern model: edge geometry, and the errors a malformed panel or stitch raises."""

import math

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.garment.pattern.model import (Arc, Cubic, Edge, Panel, Pattern, Quadratic, SeamSide, Stitch,
                                           euler_xyz_matrix)


def rect(name, w=0.5, h=0.6, **kw):
    return Panel(name=name, vertices=[(0, 0), (w, 0), (w, h), (0, h)],
                 edges=[Edge(start=i, end=(i + 1) % 4) for i in range(4)], **kw)


def disc(name, r=0.5):
    arc = Arc(radius=r, large_arc=False, right=True)
    return Panel(name=name, vertices=[(0, 0), (2 * r, 0)],
                 edges=[Edge(start=0, end=1, curve=arc), Edge(start=1, end=0, curve=arc)])


def test_straight_and_arc_lengths_and_areas():
    p = rect("front")
    assert [p.edge_length(i) for i in range(4)] == pytest.approx([0.5, 0.6, 0.5, 0.6])
    assert p.area() == pytest.approx(0.3)
    d = disc("d", 0.5)
    assert d.edge_length(0) == pytest.approx(math.pi * 0.5)
    assert d.area() == pytest.approx(math.pi * 0.25, rel=1e-4)
    # "right": the first half circle runs below the chord from (0, 0) to (1, 0)
    mid = d.edges[0].sample(d, 3)[1]
    assert mid == pytest.approx([0.5, -0.5])


def test_large_arc_spans_more_than_half_a_circle():
    # a panel closed by a 270-degree arc bulging to the right of (0, 0) -> (1, 0): below the chord
    r = 1 / math.sqrt(2)
    p = Panel(name="p", vertices=[(0, 0), (1, 0)],
              edges=[Edge(start=0, end=1, curve=Arc(radius=r, large_arc=True, right=True)), Edge(start=1, end=0)])
    assert p.edge_length(0) == pytest.approx(1.5 * math.pi * r)
    pts = p.edges[0].sample(p, 101)
    assert pts[:, 1].min() == pytest.approx(-0.5 - r, abs=1e-4)
    assert np.linalg.norm(pts - [0.5, -0.5], axis=1) == pytest.approx(np.full(101, r), abs=1e-9)


def test_bezier_samples_are_equally_spaced_and_on_the_curve():
    p = Panel(name="q", vertices=[(0, 0), (1, 0), (1, 1), (0, 1)],
              edges=[Edge(start=0, end=1, curve=Quadratic(control=(0.5, -0.4))), Edge(start=1, end=2),
                     Edge(start=2, end=3, curve=Cubic(control1=(0.7, 1.3), control2=(0.3, 0.7))), Edge(start=3, end=0)])
    pts = p.edges[0].sample(p, 201)
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert steps.std() / steps.mean() < 1e-3
    assert steps.sum() == pytest.approx(p.edge_length(0), rel=1e-5)  # 200 chords of the curve
    # the quadratic's apex is at t = 1/2: y = -0.4 / 2
    assert pts[:, 1].min() == pytest.approx(-0.2, abs=1e-4)
    assert pts[0] == pytest.approx([0, 0]) and pts[-1] == pytest.approx([1, 0])


def test_self_intersecting_outline_names_panel_and_edges():
    with pytest.raises(InputError, match=r"panel 'bow'.*crosses itself.*edges 0 and 2"):
        Panel(name="bow", vertices=[(0, 0), (1, 1), (1, 0), (0, 1)],
              edges=[Edge(start=i, end=(i + 1) % 4) for i in range(4)])


def test_curve_that_crosses_the_outline_is_refused():
    # the quadratic bottom edge dips up through the top edge
    with pytest.raises(InputError, match=r"panel 'loop'.*crosses itself.*edges 0 and 2"):
        Panel(name="loop", vertices=[(0, 0), (1, 0), (1, 0.2), (0, 0.2)],
              edges=[Edge(start=0, end=1, curve=Quadratic(control=(0.5, 0.8))), Edge(start=1, end=2),
                     Edge(start=2, end=3), Edge(start=3, end=0)])


def test_clockwise_outline_open_loop_and_bad_grain_are_refused():
    with pytest.raises(InputError, match=r"panel 'cw'.*clockwise"):
        Panel(name="cw", vertices=[(0, 0), (0, 1), (1, 1), (1, 0)],
              edges=[Edge(start=i, end=(i + 1) % 4) for i in range(4)])
    with pytest.raises(InputError, match=r"panel 'open'.*not closed.*edge 1 ends at vertex 2"):
        Panel(name="open", vertices=[(0, 0), (1, 0), (1, 1), (0, 1)],
              edges=[Edge(start=0, end=1), Edge(start=1, end=2), Edge(start=3, end=0)])
    with pytest.raises(InputError, match=r"panel 'g'.*grain.*unit"):
        rect("g", grain=(0.0, 2.0))
    with pytest.raises(InputError, match=r"panel 'arc'.*edge 0.*half the chord"):
        Panel(name="arc", vertices=[(0, 0), (1, 0)],
              edges=[Edge(start=0, end=1, curve=Arc(radius=0.2, large_arc=False, right=True)), Edge(start=1, end=0)])


def test_stitch_with_unequal_sides_names_both_panels_and_edges():
    with pytest.raises(InputError, match=r"stitch 0 joins panel 'f' edges \[1\] \(60.00 cm\) to panel 'b' "
                                         r"edges \[0\] \(50.00 cm\)"):
        Pattern(name="t", panels=(rect("f"), rect("b")),
                stitches=(Stitch(a=SeamSide(panel="f", edges=(1,)), b=SeamSide(panel="b", edges=(0,))),))
    # ease admits a gathered seam
    Pattern(name="t", panels=(rect("f"), rect("b", h=0.66)),
            stitches=(Stitch(a=SeamSide(panel="f", edges=(1,)), b=SeamSide(panel="b", edges=(3,)), ease=0.1),))


def test_edge_stitched_twice_is_refused():
    with pytest.raises(InputError, match=r"edge 1 of panel 'f' is stitched twice \(stitches 0 and 1\)"):
        Pattern(name="t", panels=(rect("f"), rect("b")),
                stitches=(Stitch(a=SeamSide(panel="f", edges=(1,)), b=SeamSide(panel="b", edges=(3,))),
                          Stitch(a=SeamSide(panel="f", edges=(1,)), b=SeamSide(panel="b", edges=(1,)))))


def test_stitch_sides_must_exist_and_be_consecutive():
    with pytest.raises(InputError, match=r"no.* panel 'x'|names panel 'x'"):
        Pattern(name="t", panels=(rect("f"),),
                stitches=(Stitch(a=SeamSide(panel="f", edges=(1,)), b=SeamSide(panel="x", edges=(3,))),))
    with pytest.raises(InputError, match=r"edges \[0, 2\] of panel 'f' are not consecutive"):
        Pattern(name="t", panels=(rect("f"), rect("b", w=1.1)),
                stitches=(Stitch(a=SeamSide(panel="f", edges=(0, 2)), b=SeamSide(panel="b", edges=(0,))),))
    with pytest.raises(InputError, match=r"two panels are named 'f'"):
        Pattern(name="t", panels=(rect("f"), rect("f")), stitches=())


def test_multi_edge_side_wraps_the_loop_and_free_edges_are_the_rest():
    p = Pattern(name="t", panels=(rect("f", w=0.6), rect("b", w=0.6, h=0.6)),
                stitches=(Stitch(a=SeamSide(panel="f", edges=(3, 0)), b=SeamSide(panel="b", edges=(1, 2))),))
    assert p.stitches[0].a.length(p) == pytest.approx(1.2)
    assert p.free_edges() == [("f", 1), ("f", 2), ("b", 0), ("b", 3)]


def test_euler_matches_garmentcode_convention():
    # Rz @ Ry @ Rx: a 90 degree turn about Y takes the panel's x axis to -Z
    assert euler_xyz_matrix((0, 90, 0)) @ [1, 0, 0] == pytest.approx([0, 0, -1], abs=1e-12)
    r = euler_xyz_matrix((30, 40, 50))
    from scipy.spatial.transform import Rotation
    assert r == pytest.approx(Rotation.from_euler("xyz", [30, 40, 50], degrees=True).as_matrix())
    p = rect("f", translation=(0.1, 1.0, 0.2), rotation=(0, 180, 0))
    assert p.to_3d(np.array([[0.5, 0.0]]))[0] == pytest.approx([-0.4, 1.0, 0.2])
