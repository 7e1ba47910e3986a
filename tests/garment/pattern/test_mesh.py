"""Flat meshing: seams resampled to equal counts, panels triangulated with their outline kept."""

from pathlib import Path

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.garment.mesh import boundary_loops
from datagen.garment.pattern.mesh import mesh_pattern, mesh_quality, triangulate_polygon
from datagen.garment.pattern.model import Edge, Panel, Pattern, SeamSide, Stitch
from datagen.garment.pattern.spec import read_spec
from tests.garment.pattern.test_spec import own_pattern

HOODY = Path(__file__).parent / "fixtures" / "garmentcode_hoody_mean_specification.json"
DRESS = Path(__file__).parent / "fixtures" / "garmentcode_dress_pencil_specification.json"


def side_fraction(mesh, pattern, side, vid):
    """Arc-length fraction of vertex vid along a seam side (by its edge and position on it)."""
    pi = pattern.panel_index(side.panel)
    p = pattern.panels[pi]
    lengths = [p.edge_length(e) for e in side.edges]
    before = 0.0
    for e, ln in zip(side.edges, lengths):
        ids = mesh.edge_vertices[(pi, e)]
        hit = np.flatnonzero(ids == vid)
        if len(hit):
            pts = mesh.rest_uv[ids]
            run = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
            return (before + ln * run[hit[0]] / run[-1]) / sum(lengths)
        before += ln
    raise AssertionError(f"vertex {vid} is not on {side}")


@pytest.fixture(scope="module")
def hoody():
    return mesh_pattern(read_spec(HOODY), 0.02)


def test_seams_have_equal_counts_and_sew_matching_points(hoody):
    pat = hoody.pattern
    h = hoody.edge_length
    for k, st in enumerate(pat.stitches):
        pairs = hoody.stitch_pairs[hoody.stitch_of_pair == k]
        la, lb = st.a.length(pat), st.b.length(pat)
        assert len(pairs) >= max(la, lb) / h * 0.6
        for va, vb in pairs:
            fa = side_fraction(hoody, pat, st.a, va)
            fb = side_fraction(hoody, pat, st.b, vb)
            if st.reversed:
                fb = 1 - fb
            # the same fraction of the seam, up to the merge of nearby corners (half an edge)
            assert abs(fa - fb) * max(la, lb) <= 0.5 * h + 1e-9
    assert (hoody.panel_id[hoody.stitch_pairs[:, 0]] >= 0).all()


def test_every_panel_is_a_disc_with_its_outline_kept(hoody):
    pat = hoody.pattern
    for pi, panel in enumerate(pat.panels):
        f = hoody.faces[hoody.face_panel == pi]
        uv = hoody.rest_uv
        loops = boundary_loops(f)
        assert len(loops) == 1, f"{panel.name}: {len(loops)} boundary loops"
        v = np.unique(f)
        e = np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1), axis=0)
        assert len(v) - len(e) + len(f) == 1  # Euler characteristic of a disc
        tri = uv[f]
        area = 0.5 * ((tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1])
                      - (tri[:, 1, 1] - tri[:, 0, 1]) * (tri[:, 2, 0] - tri[:, 0, 0]))
        assert (area > 0).all(), f"{panel.name}: a face is clockwise or degenerate"
        assert area.sum() == pytest.approx(panel.area(), rel=0.01)
        # every pattern corner is a mesh vertex, at its exact place
        for e, edge in enumerate(panel.edges):
            ids = hoody.edge_vertices[(pi, e)]
            if panel.edge_length(e) > 0.3 * hoody.edge_length:
                assert uv[ids[0]] == pytest.approx(panel.vertices[edge.start], abs=1e-12)
                assert uv[ids[-1]] == pytest.approx(panel.vertices[edge.end], abs=1e-12)
            # boundary vertices lie on the edge's curve
            ref = edge.sample(panel, 2000)
            d = np.linalg.norm(uv[ids][:, None] - ref[None], axis=2).min(axis=1)
            assert d.max() < 0.3 * hoody.edge_length


def test_quality_on_garmentcode_patterns(hoody):
    for mesh in (hoody, mesh_pattern(read_spec(DRESS), 0.02)):
        q = mesh_quality(mesh.rest_uv, mesh.faces)
        assert q.min_angle > 15, q
        assert q.angle_p1 > 30, q
        assert q.edge_median == pytest.approx(0.02, rel=0.15)
        assert q.edge_max_ratio < 1.8 and q.edge_min_ratio > 0.3, q


def test_dart_apex_and_multi_edge_seams():
    # a panel with a dart (edges 1 and 2 sewn to each other) and a two-edge side sewn to one edge
    dart = Panel(name="skirt", vertices=[(0, 0), (0.5, 0), (0.5, 0.4), (0.27, 0.4), (0.25, 0.3), (0.23, 0.4),
                                         (0, 0.4)],
                 edges=[Edge(start=i, end=(i + 1) % 7) for i in range(7)])
    band = Panel(name="band", vertices=[(0, 0), (0.63, 0), (0.63, 0.05), (0, 0.05)],
                 edges=[Edge(start=i, end=(i + 1) % 4) for i in range(4)])
    pat = Pattern(name="dart", panels=(dart, band), stitches=(
        Stitch(a=SeamSide(panel="skirt", edges=(3,)), b=SeamSide(panel="skirt", edges=(4,))),
        Stitch(a=SeamSide(panel="skirt", edges=(5, 6)), b=SeamSide(panel="band", edges=(2,))),
    ))
    m = mesh_pattern(pat, 0.01)
    a = m.edge_vertices[(0, 3)]
    b = m.edge_vertices[(0, 4)]
    assert len(a) == len(b)
    # the dart's apex is not sewn to itself; its legs are sewn point to point, mirrored
    pairs = m.stitch_pairs[m.stitch_of_pair == 0]
    assert len(pairs) == len(a) - 1
    np.testing.assert_allclose(m.rest_uv[pairs[:, 0], 1], m.rest_uv[pairs[:, 1], 1], atol=1e-9)
    # the skirt's corner (0, 0.4), 0.23 m along its side, meets the band 0.23 m from the end of its edge 2: (0.23, 0.05)
    pairs = m.stitch_pairs[m.stitch_of_pair == 1]
    corner = int(np.flatnonzero(np.all(np.isclose(m.rest_uv, [0, 0.4]) & (m.panel_id == 0)[:, None], axis=1))[0])
    partner = pairs[pairs[:, 0] == corner, 1]
    assert m.rest_uv[partner[0]] == pytest.approx([0.23, 0.05], abs=1e-9)
    assert len(pairs) == len(m.edge_vertices[(1, 2)])
    q = mesh_quality(m.rest_uv, m.faces)
    assert q.min_angle > 10


def test_triangulate_polygon_keeps_a_concave_outline():
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    r = 0.3 + 0.12 * np.cos(5 * t)  # a five-lobed star, strongly concave
    poly = np.stack([r * np.cos(t), r * np.sin(t)], axis=1)
    pts, faces = triangulate_polygon(poly, 0.02)
    np.testing.assert_array_equal(pts[:80], poly)
    loops = boundary_loops(faces)
    assert len(loops) == 1 and sorted(loops[0].tolist()) == list(range(80))
    q = mesh_quality(pts, faces)
    assert q.min_angle > 15


def test_edge_length_out_of_range_is_refused():
    with pytest.raises(InputError, match="edge length between"):
        mesh_pattern(own_pattern(), 0.0005)
