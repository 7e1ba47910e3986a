"""Body measurements of the default body's presets: sensible order, consistent with the joints,
within adult anthropometric ranges, deterministic."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from datagen.body.measurements import BodyMeasurements, MeshTopology, measure_body, plane_loops
from datagen.body.shapes import PRESET_NAMES, preset_betas, sample_betas
from datagen.errors import InputError


@pytest.fixture(scope="session")
def preset_measurements(default_body) -> dict[str, BodyMeasurements]:
    return {name: measure_body(default_body, preset_betas(default_body, name)) for name in PRESET_NAMES}


@pytest.fixture(scope="session")
def rest(default_body):
    """name -> (rest vertices [V, 3], rest joints [24, 3]) of each preset."""
    out = {}
    for name in PRESET_NAMES:
        b = preset_betas(default_body, name)[None]
        out[name] = (default_body.shaped(b)[0], default_body.rest_joints(b)[0])
    return out


def _joint_height(default_body, rest, preset: str, joint: str) -> float:
    v, j = rest[preset]
    return float(j[default_body.joint_names.index(joint), 1] - v[:, 1].min())


COORDINATES = ("floor_y", "centre_z")


def test_every_measurement_positive_and_finite(preset_measurements):
    for name, m in preset_measurements.items():
        values = m.as_dict()
        assert set(values) == {f.name for f in dataclasses.fields(BodyMeasurements)}
        bad = {k: v for k, v in values.items() if not np.isfinite(v) or (k not in COORDINATES and v <= 0)}
        assert not bad, f"{name}: {bad}"


def test_girths_in_a_sensible_order(preset_measurements):
    for name, m in preset_measurements.items():
        assert m.neck_narrowest < m.neck < m.waist, name
        assert m.wrist * 1.8 < m.neck_narrowest < m.wrist * 2.6, name  # a neck is about two wrists round
        assert m.wrist < m.upper_arm < m.thigh < m.hip, name
        assert m.armhole > m.upper_arm, name
        assert m.ankle < m.knee < m.thigh, name
        assert m.underbust < m.chest, name
    regular = preset_measurements["regular"]
    assert regular.hip > regular.waist and regular.chest > regular.waist


def test_fat_regular_thin_ordered(preset_measurements):
    thin, regular, fat = (preset_measurements[n] for n in ("thin", "regular", "fat"))
    for field in ("chest", "underbust", "waist", "hip", "thigh", "upper_arm", "neck", "neck_narrowest", "armhole"):
        assert getattr(fat, field) > getattr(regular, field) > getattr(thin, field), field
    # the presets share a stature (1.70 m): heights and lengths barely move with mass
    for field in ("height", "crotch_height", "knee_height", "ankle_height", "arm_length"):
        values = [getattr(m, field) for m in (thin, regular, fat)]
        assert max(values) - min(values) < 0.03, (field, values)


def test_heights_consistent_with_joints(default_body, rest, preset_measurements):
    for name, m in preset_measurements.items():
        jh = lambda joint: _joint_height(default_body, rest, name, joint)  # noqa: E731
        # the waist and hip are true extremes: found inside their search ranges, not at an end
        waist_top = 0.5 * (jh("spine2") + jh("spine3"))
        assert jh("spine1") + 0.01 < m.waist_height < waist_top - 0.01, name
        assert m.crotch_height + 0.015 < m.hip_height < jh("pelvis") - 0.005, name
        # the crotch (a mesh extreme) lies below the hip joints, the armpit below the shoulder joint
        assert m.crotch_height < min(jh("left_hip"), jh("right_hip")) - 0.05, name
        assert m.armpit_height < jh("left_shoulder") < m.shoulder_height, name
        assert m.front_neck_height < m.neck_height < jh("head"), name
        # half-widths: the bust point inside the shoulder point, the armpit just outside it
        sx = float(rest[name][1][default_body.joint_names.index("left_shoulder"), 0])
        assert 0.03 < m.bust_x < m.shoulder_x < m.armpit_x < sx + 0.08, name
        assert m.shoulder_x == pytest.approx(sx, abs=0.005), name
        # knee and ankle heights are the joints'; the knee sits at 26-32 % of stature (ANSUR II's
        # lateral femoral epicondyle height is about 28 %)
        assert 0.26 < m.knee_height / m.height < 0.32, name
        assert m.ankle_height < m.knee_height < m.crotch_height < m.waist_height < m.underbust_height, name
        assert m.underbust_height < m.chest_height < m.armpit_height < m.shoulder_height < m.neck_height, name
        assert m.neck_height < m.height, name
        assert m.crotch_depth == pytest.approx(m.waist_height - m.crotch_height)
        assert m.inseam == pytest.approx(m.crotch_height - m.ankle_height)


# Adult girth ranges [m]: about the 1st percentile of ANSUR II's women to the 99th of its men
# (ANSUR II: Gordon et al. 2014, "2012 Anthropometric Survey of U.S. Army Personnel: Methods and
# Summary Statistics", NATICK/TR-15/007; 4,082 men, 1,986 women), each mean +- 2.5 SD as quoted
# from memory of its summary tables, rounded outwards: chest circumference, waist circumference,
# buttock circumference (hip), neck circumference (below the larynx, across the neck: our
# neck_narrowest), biceps circumference, wrist circumference, thigh circumference, minimum lower
# leg (ankle) circumference. The presets are 1.70 m tall with BMI 18.5 / 23 / 31: inside that
# population, so each of their girths must fall inside these ranges.
ANSUR_RANGES = {
    "chest": (0.78, 1.30), "waist": (0.60, 1.25), "hip": (0.82, 1.30), "neck_narrowest": (0.29, 0.46),
    "upper_arm": (0.22, 0.43), "wrist": (0.13, 0.20), "thigh": (0.45, 0.76), "ankle": (0.18, 0.28),
}


def test_girths_within_adult_ranges(preset_measurements):
    for name, m in preset_measurements.items():
        for field, (lo, hi) in ANSUR_RANGES.items():
            assert lo <= getattr(m, field) <= hi, (name, field, getattr(m, field))
        assert 1.65 < m.height < 1.75, name


def test_random_shapes_measure_in_order(default_body):
    """Ten shapes drawn as datasets draw them (β ~ N(0, I), |β| <= 2.5): every measurement
    positive, the landmarks stacked from ankle to shoulder, the girths ordered."""
    for betas in sample_betas(11, 10, default_body.shape_dim):
        m = measure_body(default_body, betas)
        assert m.ankle_height < m.knee_height < m.crotch_height < m.hip_height < m.waist_height, betas
        assert m.waist_height < m.underbust_height < m.chest_height < m.armpit_height < m.shoulder_height, betas
        assert m.ankle < m.knee < m.thigh and m.wrist < m.upper_arm, betas
        assert m.neck_narrowest < m.neck < m.waist < m.hip and m.underbust < m.chest, betas


def test_deterministic(default_body, preset_measurements):
    again = measure_body(default_body, preset_betas(default_body, "regular")[None])
    assert again == preset_measurements["regular"]


def test_plane_loops_of_a_box():
    """Two disjoint unit cubes cut halfway: two square loops of perimeter 4."""
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    vertices = np.concatenate([corners, corners + [3, 0, 0]])
    faces = np.concatenate([tris, tris + 8])
    loops = plane_loops(vertices, MeshTopology.of(faces), (0, 0.5, 0), (0, 1, 0))
    assert len(loops) == 2
    for loop in loops:
        assert np.allclose(loop[:, 1], 0.5)
        ring = loop[:, [0, 2]]
        assert np.ptp(ring[:, 0]) == pytest.approx(1.0) and np.ptp(ring[:, 1]) == pytest.approx(1.0)


def test_bad_input_is_a_clear_error(default_body):
    with pytest.raises(InputError, match="β values"):
        measure_body(default_body, np.zeros(default_body.shape_dim + 1))


def test_cli_measure_prints_the_presets_measurements(capsys, preset_measurements):
    import json

    from datagen.cli import main

    assert main(["body", "measure", "--body", "fat", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    expected = preset_measurements["fat"].as_dict()
    assert set(printed) == set(expected)
    assert all(printed[k] == pytest.approx(expected[k], abs=1e-4) for k in expected)
    assert main(["body", "measure", "--body", "thin"]) == 0
    text = capsys.readouterr().out
    assert "waist" in text and "measured in" in text


def test_plane_loops_match_trimesh_sections(default_body, rest):
    """The section points equal trimesh's (its mesh_plane segments' end points), at heights through
    the legs, the torso and the arms, and across the arm."""
    import trimesh

    v, _ = rest["regular"]
    mesh = trimesh.Trimesh(v, default_body.faces, process=False)
    topology = MeshTopology.of(default_body.faces)
    floor = v[:, 1].min()
    for origin, normal in [((0, floor + 0.5, 0), (0, 1, 0)), ((0, floor + 1.1, 0), (0, 1, 0)),
                           ((0, floor + 1.34, 0), (0, 1, 0)), ((0.3, 0, 0), (1, 0, 0))]:
        ours = np.concatenate(plane_loops(v, topology, origin, normal))
        segments = trimesh.intersections.mesh_plane(mesh, normal, origin)
        theirs = np.unique(np.round(segments.reshape(-1, 3), 9), axis=0)
        assert len(np.unique(np.round(ours, 9), axis=0)) == len(ours) == len(theirs), origin
        assert np.allclose(np.sort(ours, axis=0), np.sort(theirs, axis=0), atol=1e-9), origin


def test_plane_loops_of_an_open_sheet():
    """A mesh with a boundary (one square of two triangles) gives one open piece of three points."""
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    pieces = plane_loops(vertices, MeshTopology.of(faces), (0.25, 0, 0), (1, 0, 0))
    assert len(pieces) == 1 and len(pieces[0]) == 3
    assert np.allclose(pieces[0][:, 0], 0.25)


def test_one_shape_at_a_time(default_body):
    with pytest.raises(InputError, match="one shape"):
        measure_body(default_body, np.zeros((2, default_body.shape_dim)))
