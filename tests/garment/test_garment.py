"""Procedural garments: every type builds and passes every check; parameters, files, CLI."""

from __future__ import annotations

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.garment.checks import check_garment
from datagen.garment.levelset import cut_mesh
from datagen.materials import MATERIALS, material
from datagen.garment.mesh import boundary_loops, load_garment
from datagen.garment.types import GARMENT_TYPES, garment_params, make_garment

LOOP_NAMES = {
    "tshirt": "neck hem left_cuff right_cuff", "long_sleeve_shirt": "neck hem left_cuff right_cuff",
    "tank_top": "neck hem left_armhole right_armhole", "dress": "neck hem left_armhole right_armhole",
    "jacket": "neck hem left_cuff right_cuff", "coat": "neck hem left_cuff right_cuff",
    "skirt": "waist hem", "flared_skirt": "waist hem", "pants": "waist left_hem right_hem", "shorts": "waist left_hem right_hem",
}


@pytest.fixture(scope="module")
def garments(default_body):
    return {kind: make_garment(kind, default_body, seed=3) for kind in GARMENT_TYPES}


def test_every_type_builds_and_passes_every_check(garments, default_body):
    assert len(GARMENT_TYPES) >= 10
    for kind, g in garments.items():
        c = check_garment(g, default_body.v_template, default_body.faces)
        assert c["ok"], (kind, c["failures"])
        assert 2000 <= g.vertex_count <= 8000, kind
        assert c["min_clearance"] >= 0.005, kind
        assert c["outward_area_fraction"] > 0.95, kind
        assert c["edge_spread"] < 0.25 and c["angle_p1_deg"] > 25.0, kind
        assert len(g.loops) == GARMENT_TYPES[kind].boundary_loops == g.metadata.boundary_loops
        assert set(g.loops) == set(LOOP_NAMES[kind].split()), (kind, sorted(g.loops))
        assert g.vertex_region.shape == (g.vertex_count,) and g.uv.shape == (g.vertex_count, 2)
        assert g.seam_vertex.any() and not g.seam_vertex.all()
        assert g.metadata.type == kind and g.metadata.rest_area_m2 > 0.2
        assert (g.metadata.waistband is None) == (GARMENT_TYPES[kind].hangs_from == "shoulders")
        # material frames: per-corner UVs in metres, not mirrored; weft horizontal on the trunk and
        # legs and around the arm on sleeves; warp perpendicular to it in the face
        fu = g.face_uv
        uv_area = 0.5 * ((fu[:, 1, 0] - fu[:, 0, 0]) * (fu[:, 2, 1] - fu[:, 0, 1])
                         - (fu[:, 2, 0] - fu[:, 0, 0]) * (fu[:, 1, 1] - fu[:, 0, 1]))
        tri = g.vertices[g.faces]
        area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        assert np.mean(uv_area > 0) > 0.98 and 0.9 < np.median(uv_area / area) < 1.1, kind
        weft, warp = g.material_frames().transpose(1, 0, 2)
        sleeve = np.isin(g.face_region, [i for i, n in enumerate(g.region_names) if n.endswith("sleeve")])
        assert np.mean(np.abs(weft[~sleeve, 1]) < 0.05) > 0.97, kind
        assert np.mean(np.abs(weft[sleeve, 0]) < 0.05) > 0.97 if sleeve.any() else True, kind
        np.testing.assert_allclose(np.einsum("ij,ij->i", weft, warp), 0.0, atol=1e-9)


@pytest.mark.parametrize("body,kinds", [("fat", ("pants", "dress", "jacket")), ("thin", ("tshirt", "skirt", "coat"))])
def test_other_bodies(default_body, body, kinds):
    from datagen.body.shapes import resolve_betas

    betas = resolve_betas(default_body, body=body)[0]
    verts = np.asarray(default_body.shaped(betas))[0]
    for kind in kinds:
        g = make_garment(kind, default_body, betas, seed=11)
        c = check_garment(g, verts, default_body.faces)
        assert c["ok"], (body, kind, c["failures"])


def test_tshirt_sleeve_ends_above_the_elbow_and_skirt_has_a_back_slit(garments, default_body):
    """Builder 9: a T-shirt sleeve drawn long is built (and recorded) 9 cm short of the elbow; the
    straight skirt's hem runs up a slit at the back, and only there."""
    from datagen.body.skeleton import SMPL_JOINT_NAMES

    joints = np.asarray(default_body.rest_joints(np.zeros(default_body.shape_dim)))[0]
    reach = joints[SMPL_JOINT_NAMES.index("left_elbow"), 0] - joints[SMPL_JOINT_NAMES.index("left_shoulder"), 0]
    long_ = make_garment("tshirt", default_body, seed=3, params={"sleeve_length": 0.25})
    assert long_.metadata.params["sleeve_length"] == pytest.approx(reach - 0.09)
    assert np.abs(long_.vertices[:, 0]).max() < joints[SMPL_JOINT_NAMES.index("left_elbow"), 0] - 0.09 + 0.01
    short = make_garment("tshirt", default_body, seed=3, params={"sleeve_length": 0.12})
    assert short.metadata.params["sleeve_length"] == pytest.approx(0.12)  # short ones are left alone

    skirt = garments["skirt"]
    hem = skirt.vertices[skirt.loops["hem"]]
    low = hem[:, 1].min()
    back_mid = hem[(np.abs(hem[:, 0]) < 0.03) & (hem[:, 2] < 0)]
    front_mid = hem[(np.abs(hem[:, 0]) < 0.03) & (hem[:, 2] > 0)]
    assert back_mid[:, 1].max() - low > 0.15  # the slit: 20-30 cm drawn, its top kept 10 cm below the hips
    assert front_mid[:, 1].max() - low < 0.03  # the front hem stays level


def test_open_front_cut_that_pinches_the_boundary_is_split(default_body):
    """Coat seed 19 on the thin body: the cut of the open front leaves the boundary touching itself
    at one vertex; the vertex is split, so the coat has its three openings and passes every check."""
    from datagen.body.shapes import resolve_betas

    betas = resolve_betas(default_body, body="thin")[0]
    g = make_garment("coat", default_body, betas, seed=19)
    assert set(g.loops) == set(LOOP_NAMES["coat"].split())
    c = check_garment(g, np.asarray(default_body.shaped(betas))[0], default_body.faces)
    assert c["ok"], c["failures"]


def test_long_top_on_thin_body_keeps_one_hem(default_body):
    from datagen.body.shapes import resolve_betas

    # on the thin body a hem 12 cm below the hip joints is below the crotch: the hem is kept above it
    g = make_garment("tank_top", default_body, resolve_betas(default_body, body="thin")[0], seed=9, params={"hem": 0.12})
    assert set(g.loops) == set(LOOP_NAMES["tank_top"].split())


def test_deterministic_and_seeded(garments, default_body):
    again = make_garment("skirt", default_body, seed=3)
    np.testing.assert_array_equal(again.vertices, garments["skirt"].vertices)
    other = make_garment("skirt", default_body, seed=4)
    assert other.metadata.params != again.metadata.params


def test_bad_input_says_what_is_allowed(default_body):
    with pytest.raises(InputError, match="types: tshirt"):
        make_garment("kimono", default_body)
    with pytest.raises(InputError, match=r"allowed range is \[0.1, 0.25\]"):
        make_garment("tshirt", default_body, params={"sleeve_length": 0.9})
    for edge in (0.001, 0.5, 5.0):  # too many vertices to simulate; too coarse for necklines, cuffs and hems
        with pytest.raises(InputError, match="must be between 0.004 and 0.1 m"):
            make_garment("coat", default_body, target_edge_length=edge)
    with pytest.raises(InputError, match="presets: cotton"):
        material("leather")
    for k, v in GARMENT_TYPES.items():
        p = garment_params(k, 0)
        assert all(v.params[n].low <= p[n] <= v.params[n].high for n in p)


def test_materials_are_si_and_ordered():
    for m in MATERIALS.values():
        assert 0.03 < m.density < 0.6 and 0 < m.poisson < 0.5 and 1e-7 < m.bending < 1e-3
    assert MATERIALS["denim"].stretch_warp > MATERIALS["cotton"].stretch_warp > MATERIALS["jersey"].stretch_warp
    assert MATERIALS["denim"].bending > MATERIALS["silk"].bending


def test_cut_mesh_is_watertight_along_the_cut():
    import trimesh

    sphere = trimesh.creation.icosphere(3)
    v, f = cut_mesh(np.asarray(sphere.vertices), np.asarray(sphere.faces), sphere.vertices[:, 1] - 0.3)
    loops = boundary_loops(f)
    assert len(loops) == 1
    np.testing.assert_allclose(v[loops[0], 1], 0.3, atol=1e-9)
    assert (v[:, 1] >= 0.3 - 1e-9).all()


def test_npz_round_trip_and_obj(garments, tmp_path):
    g = garments["pants"]
    back = load_garment(g.save(tmp_path / "pants.npz"))
    np.testing.assert_array_equal(back.vertices, g.vertices)
    np.testing.assert_array_equal(back.vertex_region, g.vertex_region)
    np.testing.assert_array_equal(back.face_uv, g.face_uv)
    assert back.region_names == g.region_names and back.material == g.material
    assert set(back.loops) == set(g.loops) and back.metadata.type == "pants"
    assert back.metadata == g.metadata  # every field, the waistband and material included
    np.testing.assert_array_equal(back.weft_rest_scale(), g.weft_rest_scale())
    import trimesh

    obj = trimesh.load(g.save(tmp_path / "pants.obj"), process=False)
    assert len(obj.vertices) == g.vertex_count


def test_cli_list_and_make_with_picture(tmp_path, capsys):
    from datagen.cli import main

    assert main(["garment", "list"]) == 0
    assert "shorts" in capsys.readouterr().out
    out, png = tmp_path / "skirt.npz", tmp_path / "skirt.png"
    assert main(["garment", "make", "--type", "skirt", "--seed", "2", "--out", str(out), "--show", str(png)]) == 0
    assert "checks: ok" in capsys.readouterr().out
    assert out.stat().st_size > 0 and png.stat().st_size > 10_000
    assert main(["garment", "make", "--type", "cape", "--out", str(tmp_path / "x.obj")]) == 2
    assert "types:" in capsys.readouterr().err


def test_file_garment_units_and_up_axis_guessed(garments, tmp_path):
    import trimesh

    g = garments["skirt"]
    # written in centimetres with Z up, as some tools export
    v = g.vertices[:, [0, 2, 1]] * np.array([1.0, -1.0, 1.0]) * 100.0
    trimesh.Trimesh(v, g.faces, process=False).export(tmp_path / "skirt_cm.obj")
    from datagen.garment.files import load_garment_file

    back = load_garment_file(tmp_path / "skirt_cm.obj")
    assert back.metadata.origin.units == "cm" and back.metadata.origin.up_axis == "z"
    assert back.metadata.origin.units_guessed and back.metadata.params == {} and back.metadata.seed is None
    assert back.metadata.vertex_count == len(back.vertices) and back.metadata.waistband is None
    np.testing.assert_array_equal(back.weft_rest_scale(), 1.0)
    np.testing.assert_allclose(back.vertices, g.vertices, atol=1e-6)
    assert len(back.loops) == 2


def test_file_garment_from_gltf(garments, tmp_path):
    """A binary glTF (metres, Y up, as the format prescribes) reads back through trimesh unchanged."""
    import trimesh

    from datagen.garment.files import load_garment_file

    g = garments["skirt"]
    trimesh.Trimesh(g.vertices, g.faces, process=False).export(tmp_path / "skirt.glb")
    back = load_garment_file(tmp_path / "skirt.glb")
    assert back.metadata.origin.units == "m" and back.metadata.origin.up_axis == "y"
    np.testing.assert_allclose(back.vertices, g.vertices, atol=1e-6)
    np.testing.assert_array_equal(back.faces, g.faces)
    assert len(back.loops) == 2


def test_file_garment_refuses_what_cannot_be_simulated(tmp_path):
    import trimesh

    from datagen.garment.files import load_garment_file

    a = trimesh.creation.box()
    b = trimesh.creation.box()
    b.apply_translation([3.0, 0, 0])
    trimesh.util.concatenate([a, b]).export(tmp_path / "two.obj")
    with pytest.raises(InputError, match="2 separate pieces"):
        load_garment_file(tmp_path / "two.obj", units="m")
    # three triangles on one edge: non-manifold
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], dtype=float)
    f = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    trimesh.Trimesh(v, f, process=False).export(tmp_path / "fin.ply")
    with pytest.raises(InputError, match="non-manifold edges"):
        load_garment_file(tmp_path / "fin.ply", units="m")
    with pytest.raises(InputError, match="does not exist"):
        load_garment_file(tmp_path / "none.obj")
