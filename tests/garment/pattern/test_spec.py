"""GarmentCode's specification JSON: read, written and read again equal; placed where GarmentCode puts it."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.garment.pattern.model import Arc, Cubic, Edge, Panel, Pattern, Quadratic, SeamSide, Stitch, euler_xyz_matrix
from datagen.garment.pattern.spec import abs_to_rel, read_spec, rel_to_abs, spec_dict, write_spec

FIXTURES = Path(__file__).parent / "fixtures"
GARMENTCODE = sorted(FIXTURES.glob("garmentcode_*_specification.json"))  # MIT, see GARMENTCODE_LICENSE.txt


def assert_same(p: Pattern, q: Pattern, tol=1e-9):
    assert p.name == q.name and dict(p.design) == dict(q.design)
    assert [x.name for x in p.panels] == [x.name for x in q.panels]
    for a, b in zip(p.panels, q.panels):
        np.testing.assert_allclose(a.vertices, b.vertices, atol=tol)
        np.testing.assert_allclose(a.translation, b.translation, atol=tol)
        np.testing.assert_allclose(a.rotation, b.rotation, atol=1e-9)
        np.testing.assert_allclose(a.grain, b.grain, atol=1e-12)
        assert dict(a.edge_groups) == dict(b.edge_groups)
        assert len(a.edges) == len(b.edges)
        for e, f in zip(a.edges, b.edges):
            assert (e.start, e.end, type(e.curve)) == (f.start, f.end, type(f.curve))
            if isinstance(e.curve, Arc):
                assert e.curve.radius == pytest.approx(f.curve.radius, abs=tol)
                assert (e.curve.large_arc, e.curve.right) == (f.curve.large_arc, f.curve.right)
            elif e.curve is not None:
                np.testing.assert_allclose(np.ravel(list(vars(e.curve).values())),
                                           np.ravel(list(vars(f.curve).values())), atol=tol)
    assert p.stitches == q.stitches


def polyline_distance(line: np.ndarray, x: np.ndarray) -> float:
    """Distance from point x to the polyline [N, 3]."""
    a, b = line[:-1], line[1:]
    t = np.clip(np.einsum("ij,ij->i", x - a, b - a) / np.maximum(np.einsum("ij,ij->i", b - a, b - a), 1e-30), 0, 1)
    return float(np.linalg.norm(a + t[:, None] * (b - a) - x, axis=1).min())


def own_pattern() -> Pattern:
    """Every edge kind, a two-edge stitch side, a start-to-start stitch, grain, groups and a design."""
    front = Panel(name="front", vertices=[(-0.2, 0), (0.2, 0), (0.25, 0.5), (0, 0.55), (-0.25, 0.5)],
                  edges=[Edge(start=0, end=1, curve=Quadratic(control=(0.0, -0.05))),
                         Edge(start=1, end=2),
                         Edge(start=2, end=3, curve=Cubic(control1=(0.2, 0.58), control2=(0.1, 0.5))),
                         Edge(start=3, end=4, curve=Arc(radius=0.3, large_arc=False, right=False)),
                         Edge(start=4, end=0)],
                  translation=(0.0, 0.9, 0.15), rotation=(0.0, 0.0, 0.0), grain=(0.6, 0.8),
                  edge_groups={"hem": (0,), "neck": (2, 3)})
    back = Panel(name="back", vertices=[(-0.2, 0), (0.2, 0), (0.25, 0.5), (-0.25, 0.5)],
                 edges=[Edge(start=0, end=1), Edge(start=1, end=2), Edge(start=2, end=3), Edge(start=3, end=0)],
                 translation=(0.0, 0.9, -0.15), rotation=(0.0, 180.0, 0.0))
    lf = front.edge_length(2) + front.edge_length(3)
    band = Panel(name="band", vertices=[(0, 0), (lf / 2, 0), (lf, 0), (lf, 0.05), (0, 0.05)],
                 edges=[Edge(start=i, end=(i + 1) % 5) for i in range(5)], translation=(0.3, 1.5, 0.0),
                 rotation=(10.0, -30.0, 5.0))
    return Pattern(name="own", panels=(front, back, band), stitches=(
        Stitch(a=SeamSide(panel="front", edges=(1,)), b=SeamSide(panel="back", edges=(3,))),
        Stitch(a=SeamSide(panel="front", edges=(4,)), b=SeamSide(panel="back", edges=(1,))),
        Stitch(a=SeamSide(panel="front", edges=(2, 3)), b=SeamSide(panel="band", edges=(0, 1)), reversed=False,
               ease=0.02),
    ), design={"length": 0.55, "neckline": "round", "darts": 2})


def test_relative_coordinates_are_garmentcodes_frame():
    # u along start -> end, v to its left (perp(x, y) = (-y, x))
    assert rel_to_abs((1, 1), (3, 1), (0.5, 0.25)) == pytest.approx([2.0, 1.5])
    assert rel_to_abs((0, 0), (0, 2), (0.5, 0.5)) == pytest.approx([-1.0, 1.0])
    rng = np.random.default_rng(0)
    for _ in range(20):
        s, e, p = rng.normal(size=(3, 2))
        assert rel_to_abs(s, e, abs_to_rel(s, e, p)) == pytest.approx(p)


def test_own_pattern_round_trips(tmp_path):
    p = own_pattern()
    q = read_spec(write_spec(p, tmp_path / "own_specification.json"))
    assert_same(p, q)
    data = json.loads((tmp_path / "own_specification.json").read_text())
    assert data["properties"]["units_in_meter"] == 100
    st = data["pattern"]["stitches"]
    # the two-edge side is written as GarmentCode's one-edge pairs, start meeting start
    assert [(s[0]["edge"], s[1]["edge"], s[2:]) for s in st[2:]] == [(2, 0, ["right_wrong"]), (3, 1, ["right_wrong"])]
    assert data["pattern"]["panels"]["front"]["edges"][3]["curvature"] == {
        "type": "circle", "params": [pytest.approx(30.0), 0, 0]}
    # metres in, centimetres in the file, metres out; another unit reads the same
    q2 = read_spec(spec_dict(p, units_in_meter=1000) | {"name": "own"})
    assert_same(p, q2)


@pytest.mark.parametrize("path", GARMENTCODE, ids=lambda p: p.stem)
def test_garmentcode_file_reads_where_garmentcode_places_it(path):
    data = json.loads(path.read_text())
    pat = read_spec(path)
    assert pat.name == path.stem.removesuffix("_specification")  # the name is the file's, as GarmentCode
    scale = 1 / data["properties"]["units_in_meter"]
    for panel in pat.panels:
        spec = data["pattern"]["panels"][panel.name]
        rot, tr = euler_xyz_matrix(spec["rotation"]), np.asarray(spec["translation"]) * scale
        verts = np.asarray(spec["vertices"]) * scale

        def place(p2):
            return rot @ np.append(p2, 0.0) + tr
        for k, (e, es) in enumerate(zip(panel.edges, spec["edges"])):
            s, t = verts[es["endpoints"][0]], verts[es["endpoints"][1]]
            ours = panel.to_3d(e.sample(panel, 400))
            assert ours[0] == pytest.approx(place(s), abs=1e-12) and ours[-1] == pytest.approx(place(t), abs=1e-12)
            c = es.get("curvature")
            if c is None:
                continue
            if c["type"] in ("quadratic", "cubic"):  # the Bezier's point at t = 1/2, by its own formula
                cp = [rel_to_abs(s, t, q) for q in c["params"]]
                mid = (s + 2 * cp[0] + t) / 4 if len(cp) == 1 else (s + 3 * cp[0] + 3 * cp[1] + t) / 8
            else:  # the arc's middle: the sagitta from the chord's midpoint, on its 'right' side
                r, large, right = c["params"]
                r *= scale
                d = np.linalg.norm(t - s)
                h = math.sqrt(r * r - d * d / 4)
                sag = r + h if large else r - h
                left = np.array([-(t - s)[1], (t - s)[0]]) / d
                mid = (s + t) / 2 + (-1 if right else 1) * sag * left
            gap = polyline_distance(ours, place(mid))
            assert gap < 2e-5, f"{panel.name} edge {k}: curve midpoint {gap * 1000:.2f} mm off our edge"
    # every GarmentCode stitch became one of ours, same panels and edges
    ours = [(s.a.panel, s.a.edges, s.b.panel, s.b.edges) for s in pat.stitches]
    assert ours == [(a["panel"], (a["edge"],), b["panel"], (b["edge"],)) for a, b, *_ in data["pattern"]["stitches"]]


@pytest.mark.parametrize("path", GARMENTCODE, ids=lambda p: p.stem)
def test_garmentcode_file_round_trips(path, tmp_path):
    p = read_spec(path)
    q = read_spec(write_spec(p, tmp_path / path.name))
    assert_same(p, q)


def test_clockwise_panel_is_mirrored_and_lands_in_the_same_place():
    # a back panel as GarmentCode writes it: clockwise in the body's frame, no rotation
    spec = {"pattern": {"panels": {"back": {
        "vertices": [[0, 0], [0, 50], [40, 50], [40, 0]],
        "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]},
                  {"endpoints": [2, 3], "curvature": {"type": "circle", "params": [30, 0, 1]}},
                  {"endpoints": [3, 0], "curvature": {"type": "quadratic", "params": [[0.5, 0.2]]}}],
        "translation": [-20, 100, -15], "rotation": [0, 0, 0]}}, "stitches": []},
        "properties": {"units_in_meter": 100}}
    p = read_spec(spec).panel("back")
    assert p.rotation == (0.0, 180.0, 0.0)
    assert p.to_3d(np.array(p.vertices)) == pytest.approx(
        np.array([[0, 0, 0], [0, 0.5, 0], [0.4, 0.5, 0], [0.4, 0, 0]]) + [-0.2, 1.0, -0.15])
    # the arc from (40, 50) down to (40, 0) bulges to its right (-x in the body frame): into the panel
    mid = p.to_3d(p.edges[2].sample(p, 3))[1]
    assert mid == pytest.approx([-0.2 + 0.4 - (0.3 - math.sqrt(0.3**2 - 0.25**2)), 1.25, -0.15])


def test_bad_files_say_what_is_wrong(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InputError, match="not JSON"):
        read_spec(bad)
    with pytest.raises(InputError, match="needs 'pattern'"):
        read_spec({"panels": {}})
    with pytest.raises(InputError, match=r"panel 'p': edge 0: bad curvature"):
        read_spec({"pattern": {"panels": {"p": {"vertices": [[0, 0], [1, 0], [0, 1]], "edges": [
            {"endpoints": [0, 1], "curvature": {"type": "spline", "params": []}},
            {"endpoints": [1, 2]}, {"endpoints": [2, 0]}]}}, "stitches": []}, "properties": {"units_in_meter": 1}})


def uneven_pattern() -> Pattern:
    """Two edges (a quadratic and an arc) of one panel sewn to one straight edge of another."""
    p = own_pattern()
    front = p.panel("front")
    total = front.edge_length(2) + front.edge_length(3)
    strip = Panel(name="strip", vertices=[(0, 0), (total, 0), (total, 0.04), (0, 0.04)],
                  edges=[Edge(start=i, end=(i + 1) % 4) for i in range(4)], edge_groups={"top": (2,)})
    return Pattern(name="uneven", panels=(front, p.panel("back"), strip), stitches=(
        p.stitches[0], p.stitches[1],
        Stitch(a=SeamSide(panel="front", edges=(2, 3)), b=SeamSide(panel="strip", edges=(0,))),
    ))


def test_uneven_stitch_is_written_as_split_pairs_and_read_back_whole(tmp_path):
    p = uneven_pattern()
    data = spec_dict(p)
    st = data["pattern"]["stitches"][2:]
    # the strip's edge 0 is split in two (its new edges 0 and 1), sewn in reverse order
    assert [(s[0]["edge"], s[1]["edge"]) for s in st] == [(2, 1), (3, 0)]
    strip = data["pattern"]["panels"]["strip"]
    assert [e.get("drape_piece", [None])[0] for e in strip["edges"]] == [0, 0, None, None, None]
    assert strip["edge_groups"] == {"top": [3]}
    q = read_spec(write_spec(p, tmp_path / "uneven_specification.json"))
    assert_same(p, q)
    # what GarmentCode reads (drape's marks ignored): every one-edge pair of the same length
    for panel in data["pattern"]["panels"].values():
        for e in panel["edges"]:
            e.pop("drape_piece", None)
    for s in data["pattern"]["stitches"]:
        s[0].pop("seam", None)
        s[0].pop("ease", None)
    plain = read_spec(data)
    assert len(plain.panel("strip").edges) == 5
    assert all(s.ease == 0 for s in plain.stitches)


def test_split_curves_join_back_exactly():
    from datagen.garment.pattern.split import join_curve, split_curve
    p = own_pattern().panel("front")
    for k in (0, 2, 3):
        e = p.edges[k]
        parts = split_curve(p, e, [0.3, 0.7])
        start = np.asarray(p.vertices[e.start])
        joined = join_curve(start, p.vertices[e.end], [(parts[0][1], 0.0, 0.3)], start, parts[0][0])
        ref = e.sample(p, 50)
        back = Edge(start=e.start, end=e.end, curve=joined).sample(p, 50)
        np.testing.assert_allclose(back, ref, atol=1e-9)
