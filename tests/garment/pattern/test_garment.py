"""The pattern kind of GarmentMesh: built from a pattern, checked, saved and loaded; the CLI and the drawing."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from datagen.garment.mesh import load_garment
from datagen.garment.pattern.garment import check_pattern_garment, pattern_garment, stand_on_floor
from datagen.garment.pattern.spec import read_spec
from datagen.garment.pattern.svg import draw_svg

FIXTURES = Path(__file__).parent / "fixtures"
ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def regular_body(default_body):
    from datagen.body.shapes import resolve_betas

    betas = resolve_betas(default_body, body="regular")[0]
    return np.asarray(default_body.shaped(betas))[0], np.asarray(default_body.faces)


@pytest.fixture(scope="module")
def hoody(regular_body):
    pat = stand_on_floor(read_spec(FIXTURES / "garmentcode_hoody_mean_specification.json"), regular_body[0])
    return pattern_garment(pat, *regular_body, edge_length=0.03)


def test_pattern_garment_passes_its_checks_and_names_its_openings(hoody, regular_body):
    assert hoody.kind == "pattern"
    c = check_pattern_garment(hoody, *regular_body)
    assert c["ok"], c["failures"]
    assert c["vertices_inside"] == 0 and c["panels"] == 6
    # a hoody: the hem at the bottom, two armholes at the sides, the hood's face opening on top
    assert len(hoody.loops) == 4
    assert {"left_opening", "right_opening"} <= set(hoody.loops)  # no edge group names GarmentCode's armholes
    lowest = min(hoody.loops, key=lambda k: hoody.vertices[hoody.loops[k], 1].mean())
    assert hoody.vertices[hoody.loops[lowest], 1].mean() < hoody.vertices[:, 1].mean()
    # uv is the rest state in the grain frame: same lengths as rest_uv
    e = hoody.faces[:, :2]
    np.testing.assert_allclose(np.linalg.norm(hoody.uv[e[:, 0]] - hoody.uv[e[:, 1]], axis=1),
                               np.linalg.norm(hoody.rest_uv[e[:, 0]] - hoody.rest_uv[e[:, 1]], axis=1))
    assert hoody.face_grain.shape == (len(hoody.faces), 2)
    assert hoody.seam_vertex[hoody.stitch_pairs.ravel()].all()


def test_pattern_garment_round_trips_through_npz(hoody, tmp_path):
    path = hoody.save(tmp_path / "hoody.npz")
    back = load_garment(path)
    assert back.kind == "pattern"
    for name in ("vertices", "faces", "rest_uv", "stitch_pairs", "face_grain", "uv", "vertex_region"):
        np.testing.assert_array_equal(getattr(back, name), getattr(hoody, name))
    assert back.loops.keys() == hoody.loops.keys()
    assert read_spec(json.loads(back.pattern)).stitches == read_spec(json.loads(hoody.pattern)).stitches
    assert back.metadata.type == "pattern:garmentcode_hoody_mean"


def test_svg_numbers_every_stitch(tmp_path):
    pat = read_spec(FIXTURES / "garmentcode_dress_pencil_specification.json")
    text = draw_svg(pat, tmp_path / "dress.svg").read_text()
    assert text.startswith("<svg") and text.rstrip().endswith("</svg>")
    for k in range(len(pat.stitches)):
        assert text.count(f">{k}</text>") == 2  # on both sides
    for p in pat.panels:
        assert f">{p.name}</text>" in text


@pytest.mark.slow
def test_cli_makes_a_pattern_garment_and_refuses_bad_input(tmp_path):
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}
    import os
    env = {**os.environ, **env}
    spec = FIXTURES / "garmentcode_hoody_mean_specification.json"
    r = subprocess.run([sys.executable, "-m", "datagen.cli", "garment", "make", "--spec", str(spec), "--body", "thin",
                        "--edge-length", "0.03", "--out", str(tmp_path / "h.npz"), "--svg", str(tmp_path / "h.svg"),
                        "--write-spec", str(tmp_path / "h.json")], capture_output=True, text=True, env=env, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    assert "checks: ok" in r.stdout and (tmp_path / "h.svg").is_file()
    again = read_spec(tmp_path / "h.json")
    assert len(again.panels) == 6 and load_garment(tmp_path / "h.npz").kind == "pattern"
    r = subprocess.run([sys.executable, "-m", "datagen.cli", "garment", "make", "--pattern", "no_such", "--out",
                        str(tmp_path / "x.npz")], capture_output=True, text=True, env=env, cwd=ROOT)
    assert r.returncode == 2 and "not a pattern program" in r.stderr and "Traceback" not in r.stderr
    r = subprocess.run([sys.executable, "-m", "datagen.cli", "garment", "make", "--type", "dress", "--svg",
                        str(tmp_path / "x.svg"), "--out", str(tmp_path / "x.npz")], capture_output=True, text=True,
                       env=env, cwd=ROOT)
    assert r.returncode == 2 and "--pattern or --spec" in r.stderr


def test_garment_list_json_has_both_families(capsys):
    from datagen.cli import main
    from datagen.garment.pattern.programs import PROGRAMS
    from datagen.garment.types import GARMENT_TYPES

    assert main(["garment", "list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert set(listed["types"]) == set(GARMENT_TYPES) and set(listed["patterns"]) == set(PROGRAMS)
    circle = listed["patterns"]["skirt_circle"]
    assert circle["family"] == "skirt" and all("options" in p or p["low"] <= p["high"] for p in circle["params"].values())
