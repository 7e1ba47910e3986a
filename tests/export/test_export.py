"""Export and look: animated USD files (points, normals, time codes, primvars, UsdSkel rig) read back
with pxr and checked by usd-core's validators; previews (PNG, GIF, MP4); the ``drape simulate`` and
plain-array sources; and the errors a user can make.

Tests on a real store share one micro store made by ``drape generate`` (5 scenes simulated on the
CPU, some of which fail), marked slow; the others use small synthetic arrays.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from datagen.cli import main
from datagen.errors import InputError, MissingDependencyError

MICRO = {
    "seed": 0, "frames": 6, "segment_length": 3, "garment_edge_length": 0.07,
    "simulation": {"settle_rest": 2, "lead_in": 0.1, "settle_pose": 1, "ramp": 0.1,
                   "solver": {"substeps": 3, "iterations": 3, "detection_interval": 2}},
    # the fit model needs more than three training (garment, body) pairs
    "train": {"garments": ["tshirt:0", "pants:0"], "bodies": ["regular", "seed:1"], "motions": ["walk:0"]},
    "test": {"garments": ["skirt:1"], "bodies": ["thin"], "motions": ["wave:1"]},
}

GARMENT_RGB = np.array([0.25, 0.45, 0.75])


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def store_path(tmp_path_factory) -> Path:
    from datagen.config import load_config
    from datagen.generate.config import DatasetConfig
    from datagen.generate.run import generate

    out = tmp_path_factory.mktemp("export") / "micro.zarr"
    generate(load_config(DatasetConfig, MICRO), out)
    return out


@pytest.fixture(scope="module")
def store(store_path):
    from datagen.store import open_store

    return open_store(store_path)


@pytest.fixture(scope="module")
def ok_sample(store) -> int:
    ok = [i for i in range(len(store)) if store.scalars(i)["failure"] == 0]
    assert ok, "the micro store has no sample that did not fail"
    return ok[0]


def synthetic(T: int = 4):
    """A moving icosphere 'body' and a moving grid 'garment' with two regions."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.3)
    bv0, bf = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    n = 6
    u, v = np.meshgrid(np.linspace(-0.3, 0.3, n), np.linspace(-0.3, 0.3, n))
    gv0 = np.stack([u.ravel(), v.ravel(), np.full(n * n, 0.4)], axis=1)
    quads = np.array([[r * n + c, r * n + c + 1, (r + 1) * n + c + 1, (r + 1) * n + c]
                      for r in range(n - 1) for c in range(n - 1)])
    gf = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    shift = np.stack([np.linspace(0, 0.1, T), np.zeros(T), np.zeros(T)], axis=1)[:, None]
    rng = np.random.default_rng(0)
    body = (bv0[None] + shift).astype(np.float32)
    garment = (gv0[None] + shift + rng.normal(scale=0.005, size=(T, n * n, 3))).astype(np.float32)
    region = (gv0[:, 0] > 0).astype(np.int32)
    return body, bf, garment, gf, region, gv0


def stage_of(path):
    from pxr import Usd

    return Usd.Stage.Open(str(path))


# ------------------------------------------------------------------------------ synthetic arrays (fast)


def test_writer_on_plain_arrays_round_trips_and_validates(tmp_path):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from pxr import UsdGeom

    from datagen.export.usd import usd_validation_errors, write_animation_usd

    body, bf, garment, gf, region, _ = synthetic()
    path = write_animation_usd(tmp_path / "a.usda", body, bf, garment, gf, 24.0, region=region,
                               region_names=["left", "right"], metadata={"sample": 7, "alpha": [0.5, -1.0, 2.0]})
    assert usd_validation_errors(path) == []
    stage = stage_of(path)
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == 24.0 and stage.GetFramesPerSecond() == 24.0
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, 3.0)
    root = stage.GetDefaultPrim()
    assert root.GetPath() == "/Drape" and root.GetCustomDataByKey("drape:sample") == 7
    np.testing.assert_array_equal(list(root.GetCustomDataByKey("drape:alpha")), [0.5, -1.0, 2.0])
    g = UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Garment"))
    b = UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Body"))
    assert g.GetPointsAttr().GetTimeSamples() == [0.0, 1.0, 2.0, 3.0]
    for t in range(4):
        np.testing.assert_array_equal(np.asarray(g.GetPointsAttr().Get(t)), garment[t])
        np.testing.assert_array_equal(np.asarray(b.GetPointsAttr().Get(t)), body[t])
        n = np.asarray(g.GetNormalsAttr().Get(t))
        assert n.shape == garment[t].shape and np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-5)
    assert g.GetNormalsInterpolation() == UsdGeom.Tokens.vertex
    np.testing.assert_array_equal(np.asarray(g.GetFaceVertexIndicesAttr().Get()), gf.reshape(-1))
    pv = UsdGeom.PrimvarsAPI(g).GetPrimvar("drape:region")
    assert pv.GetInterpolation() == UsdGeom.Tokens.vertex
    np.testing.assert_array_equal(np.asarray(pv.Get()), region)
    assert list(pv.GetAttr().GetCustomDataByKey("drape:region_names")) == ["left", "right"]
    assert len(g.GetDisplayColorAttr().Get()) == len(region)


def test_pattern_uvs_and_panels_are_st_and_panel_primvars_usd_accepts(tmp_path):
    """A pattern garment's flat panel coordinates per triangle corner become the faceVarying ``st``
    primvar (texCoord2f[], in faceVertexIndices order), its panels a uniform int primvar; a shell's
    per-vertex uv a vertex ``st``; usd-core's validators accept both."""
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from pxr import Sdf, UsdGeom

    from datagen.export.usd import usd_validation_errors, write_animation_usd

    body, bf, garment, gf, region, _ = synthetic()
    F, V = len(gf), garment.shape[1]
    corner = np.random.default_rng(3).random((F, 3, 2)).astype(np.float32)
    panel = (np.arange(F) % 2).astype(np.int32)
    path = write_animation_usd(tmp_path / "p.usda", body, bf, garment, gf, 24.0, garment_st=corner,
                               garment_panel=panel, panel_names=["front", "back"])
    assert usd_validation_errors(path) == []
    stage = stage_of(path)
    g = UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Garment"))
    st = UsdGeom.PrimvarsAPI(g).GetPrimvar("st")
    assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying and st.GetTypeName() == Sdf.ValueTypeNames.TexCoord2fArray
    np.testing.assert_array_equal(np.asarray(st.Get()), corner.reshape(-1, 2))
    pv = UsdGeom.PrimvarsAPI(g).GetPrimvar("drape:panel")
    assert pv.GetInterpolation() == UsdGeom.Tokens.uniform
    np.testing.assert_array_equal(np.asarray(pv.Get()), panel)
    assert list(pv.GetAttr().GetCustomDataByKey("drape:panel_names")) == ["front", "back"]
    uv = np.random.default_rng(4).random((V, 2)).astype(np.float32)
    path = write_animation_usd(tmp_path / "s.usd", body, bf, garment, gf, 24.0, garment_st=uv)
    assert usd_validation_errors(path) == []
    stage = stage_of(path)
    st = UsdGeom.PrimvarsAPI(UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Garment"))).GetPrimvar("st")
    assert st.GetInterpolation() == UsdGeom.Tokens.vertex
    np.testing.assert_array_equal(np.asarray(st.Get()), uv)
    with pytest.raises(InputError, match="per triangle corner"):
        write_animation_usd(tmp_path / "x.usda", body, bf, garment, gf, 24.0, garment_st=uv[:-1])
    with pytest.raises(InputError, match="non-finite"):
        write_animation_usd(tmp_path / "x.usda", body, bf, garment, gf, 24.0, garment_st=np.full((F, 3, 2), np.nan))
    with pytest.raises(InputError, match="integer panel per garment triangle"):
        write_animation_usd(tmp_path / "x.usda", body, bf, garment, gf, 24.0, garment_panel=panel[:-1])


def test_writer_refuses_bad_arrays_and_paths(tmp_path):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from datagen.export.usd import write_animation_usd

    body, bf, garment, gf, region, _ = synthetic()
    with pytest.raises(InputError, match="4 frames; the garment has 3"):
        write_animation_usd(tmp_path / "a.usd", body, bf, garment[:3], gf, 30)
    bad = garment.copy()
    bad[2, 0, 0] = np.nan
    with pytest.raises(InputError, match=r"non-finite .* frame\(s\) \[2\]"):
        write_animation_usd(tmp_path / "a.usd", body, bf, bad, gf, 30)
    with pytest.raises(InputError, match="region code 1 has no name"):
        write_animation_usd(tmp_path / "a.usd", body, bf, garment, gf, 30, region=region, region_names=["one"])
    with pytest.raises(InputError, match=r"\.usda"):
        write_animation_usd(tmp_path / "a.obj", body, bf, garment, gf, 30)
    with pytest.raises(InputError, match="does not exist"):
        write_animation_usd(tmp_path / "no" / "a.usd", body, bf, garment, gf, 30)
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="does not exist"):
        write_animation_usd(tmp_path / "file" / "a.usd", body, bf, garment, gf, 30)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]  # nothing written


def test_unwritable_directory_is_refused_before_any_work(tmp_path, monkeypatch):
    """(Permission bits do not stop root, so the check itself is exercised through os.access.)"""
    from datagen import files
    from datagen.files import check_output_dir, check_output_path

    monkeypatch.setattr(files.os, "access", lambda *a, **k: False)
    with pytest.raises(InputError, match="is not writable"):
        check_output_path(tmp_path / "a.usd", (".usd",), "USD file")
    with pytest.raises(InputError, match="not writable"):
        check_output_dir(tmp_path / "d", "output directory")


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from datagen.export import usd
    from datagen.files import atomic_output

    body, bf, garment, gf, _, _ = synthetic()
    target = tmp_path / "a.usd"
    target.write_text("old")

    calls = []
    normals = usd._normals_vt

    def boom(*a, **k):  # the second mesh's normals fail, after the garment's were set
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("out of memory")
        return normals(*a, **k)

    monkeypatch.setattr(usd, "_normals_vt", boom)
    with pytest.raises(RuntimeError):
        usd.write_animation_usd(target, body, bf, garment, gf, 30)
    with pytest.raises(RuntimeError), atomic_output(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("interrupted")
    assert target.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["a.usd"]


def test_vertex_normals_point_out_of_a_sphere_and_stretch_measures_scaling():
    import trimesh

    from datagen.export.preview import vertex_stretch
    from datagen.export.usd import vertex_normals

    s = trimesh.creation.icosphere(subdivisions=2)
    v = np.asarray(s.vertices)
    n = vertex_normals(np.stack([v, 2 * v]), s.faces)
    assert n.shape == (2, len(v), 3) and (np.sum(n * v, axis=-1) > 0.98).all()
    st = vertex_stretch(np.stack([v, 1.1 * v]), s.faces, v)
    np.testing.assert_allclose(st[0], 0, atol=1e-12)
    np.testing.assert_allclose(st[1], 0.1, atol=1e-9)


def test_missing_optional_dependencies_say_how_to_install(tmp_path, monkeypatch):
    from datagen.export.animation import Animation
    from datagen.export.preview import render_clip
    from datagen.export.usd import write_animation_usd

    body, bf, garment, gf, _, _ = synthetic()
    anim = Animation(body_vertices=body, body_faces=bf, garment_vertices=garment, garment_faces=gf, fps=30)
    monkeypatch.setitem(sys.modules, "pxr", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'drape\[usd\]'"):
        write_animation_usd(tmp_path / "a.usd", body, bf, garment, gf, 30)
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    with pytest.raises(MissingDependencyError, match="pip install imageio-ffmpeg"):
        render_clip(anim, tmp_path / "c.mp4")
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'drape\[render\]'"):
        render_clip(anim, tmp_path / "c.gif")
    assert list(tmp_path.iterdir()) == []


def test_clips_of_plain_arrays_gif_and_mp4(tmp_path):
    from PIL import Image

    from datagen.export.animation import Animation
    from datagen.export.preview import render_clip

    body, bf, garment, gf, region, rest = synthetic(T=5)
    anim = Animation(body_vertices=body, body_faces=bf, garment_vertices=garment, garment_faces=gf, fps=30,
                     region=region, region_names=("left", "right"), garment_rest=rest, title="synthetic")
    gif = render_clip(anim, tmp_path / "c.gif", size=(160, 128), color_by="stretch")
    with Image.open(gif) as im:
        assert im.n_frames == 5 and im.size == (160, 128)
    try:
        import imageio_ffmpeg
    except ImportError:
        with pytest.raises(MissingDependencyError, match="pip install imageio-ffmpeg"):
            render_clip(anim, tmp_path / "c.mp4")
        return
    mp4 = render_clip(anim, tmp_path / "c.mp4", size=(160, 128), color_by="region", view="side")
    reader = imageio_ffmpeg.read_frames(str(mp4))
    meta = next(reader)
    assert tuple(meta["size"]) == (160, 128) and sum(1 for _ in reader) == 5


def test_plain_array_npz_and_frame_specs(tmp_path):
    from datagen.export.animation import from_npz, load_animation, parse_frames

    body, bf, garment, gf, region, _ = synthetic()
    np.savez(tmp_path / "pred.npz", garment_vertices=garment, garment_faces=gf, body_vertices=body, body_faces=bf,
             fps=25.0, region=region, region_names=np.array(["left", "right"]))
    a = from_npz(tmp_path / "pred.npz")
    assert a.fps == 25.0 and a.region_names == ("left", "right") and a.skeleton is None
    np.testing.assert_array_equal(a.garment_vertices, garment)
    sub = load_animation(tmp_path / "pred.npz", frames=np.array([1, 3]))
    np.testing.assert_array_equal(sub.garment_vertices, garment[[1, 3]])
    assert sub.source_frames.tolist() == [1, 3]
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(InputError, match="neither plain arrays"):
        from_npz(tmp_path / "other.npz")
    assert parse_frames("2:8:3", 10).tolist() == [2, 5] and parse_frames(None, 3).tolist() == [0, 1, 2]
    for bad, msg in (("12", "valid frames are 0 .. 9"), ("-1", "negative numbers are not read as from the end"),
                     ("-3:", "out of range"), ("5:2", "select no frame"), ("0:4:0", "step"),
                     ("a:b", "A:B")):
        with pytest.raises(InputError, match=msg):
            parse_frames(bad, 10)


def test_an_old_simulate_result_is_refused_with_what_to_do(tmp_path):
    """Files of ``drape simulate`` from before it recorded the body (positions, faces, names) are
    not rebuilt from their names: the loader says to simulate again."""
    from datagen.export.animation import from_npz

    np.savez_compressed(tmp_path / "run.npz", positions=np.zeros((2, 3, 3), np.float32), faces=np.array([[0, 1, 2]]),
                        garment="skirt", motion="wave", body="thin")
    with pytest.raises(InputError, match="older drape.*run drape simulate again"):
        from_npz(tmp_path / "run.npz")


# ------------------------------------------------------------------------------ a real store (slow)


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".usd", ".usda"])
def test_store_sample_to_usd_round_trips(store_path, store, ok_sample, tmp_path, capsys, suffix):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from pxr import UsdGeom

    from datagen.export.usd import usd_validation_errors

    i = ok_sample
    out = tmp_path / f"anim{suffix}"
    code, text, _ = run(capsys, "export", "usd", store_path, "--sample", i, "--out", out, "--validate")
    assert code == 0 and f"wrote {out}" in text and "usd-core validators: no problems" in text
    assert usd_validation_errors(out) == []
    x = store.sample(i, names=["detail", "body_vertices"])
    T = len(x["detail"])
    g = store.garment(int(store.scalars(i)["garment"]))
    stage = stage_of(out)
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    fps = store.config["fps"]
    assert stage.GetTimeCodesPerSecond() == fps and stage.GetFramesPerSecond() == fps
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, T - 1.0)
    garment = UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Garment"))
    body = UsdGeom.Mesh(stage.GetPrimAtPath("/Drape/Body"))
    assert garment.GetPointsAttr().GetTimeSamples() == [float(t) for t in range(T)]
    for t in range(T):
        np.testing.assert_array_equal(np.asarray(garment.GetPointsAttr().Get(t)), x["detail"][t])
        np.testing.assert_array_equal(np.asarray(body.GetPointsAttr().Get(t)), x["body_vertices"][t])
        assert len(garment.GetNormalsAttr().Get(t)) == len(g["rest_vertices"])
        assert len(body.GetNormalsAttr().Get(t)) == x["body_vertices"].shape[1]
    np.testing.assert_array_equal(np.asarray(garment.GetFaceVertexIndicesAttr().Get()), g["faces"].reshape(-1))
    np.testing.assert_array_equal(np.asarray(body.GetFaceVertexIndicesAttr().Get()),
                                  store.read("body/faces").reshape(-1))
    pv = UsdGeom.PrimvarsAPI(garment).GetPrimvar("drape:region")
    np.testing.assert_array_equal(np.asarray(pv.Get()), g["region"])
    assert tuple(pv.GetAttr().GetCustomDataByKey("drape:region_names")) == store.names["region_names"]
    assert len(garment.GetDisplayColorAttr().Get()) == len(g["region"])
    st = UsdGeom.PrimvarsAPI(garment).GetPrimvar("st")  # a shell garment: its material uv per vertex
    assert st.GetInterpolation() == UsdGeom.Tokens.vertex
    np.testing.assert_array_equal(np.asarray(st.Get()), g["uv"])
    root = stage.GetDefaultPrim()
    assert root.GetCustomDataByKey("drape:sample") == i
    assert root.GetCustomDataByKey("drape:split") == store.names["split_names"][store.scalars(i)["split"]]


@pytest.mark.slow
def test_skeleton_animates_and_skins_the_body_like_the_store(store_path, store, ok_sample, tmp_path, capsys):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from pxr import Usd, UsdGeom, UsdSkel

    from datagen.body.skeleton import SMPL_JOINT_NAMES
    from datagen.export.usd import usd_validation_errors
    from datagen.geometry.rotations import axis_angle_to_matrix_np, quaternion_to_axis_angle_np

    i = ok_sample
    out = tmp_path / "rig.usda"
    assert run(capsys, "export", "usd", store_path, "--sample", i, "--out", out, "--skeleton")[0] == 0
    assert usd_validation_errors(out) == []
    x = store.sample(i, names=["body_vertices", "pose", "trans", "joints"])
    stage = stage_of(out)
    assert not stage.GetPrimAtPath("/Drape/Body")  # the skinned mesh replaces the time-sampled body
    skel = UsdSkel.Skeleton(stage.GetPrimAtPath("/Drape/Skel/Skeleton"))
    joints = list(skel.GetJointsAttr().Get())
    assert len(joints) == 24 and joints[4] == "pelvis/left_hip/left_knee"
    assert list(skel.GetJointNamesAttr().Get()) == list(SMPL_JOINT_NAMES)
    anim = UsdSkel.Animation(stage.GetPrimAtPath("/Drape/Skel/Animation"))
    assert len(anim.GetJointsAttr().Get()) == 24
    t = len(x["pose"]) - 1
    q = np.asarray(anim.GetRotationsAttr().Get(t))  # Gf order: x, y, z, w
    assert q.shape == (24, 4)
    back = quaternion_to_axis_angle_np(q[:, [3, 0, 1, 2]].astype(np.float64))
    np.testing.assert_allclose(axis_angle_to_matrix_np(back), axis_angle_to_matrix_np(x["pose"][t]), atol=1e-6)
    tr = np.asarray(anim.GetTranslationsAttr().Get(t))
    rest0 = np.asarray(skel.GetBindTransformsAttr().Get()[0])[3, :3]
    np.testing.assert_allclose(tr[0], rest0 + x["trans"][t], atol=1e-6)
    # UsdSkel's own skinning reproduces the stored posed body and joints
    root = UsdSkel.Root(stage.GetPrimAtPath("/Drape/Skel"))
    cache = UsdSkel.Cache()
    cache.Populate(root, Usd.TraverseInstanceProxies())
    binding = cache.ComputeSkelBindings(root, Usd.TraverseInstanceProxies())[0]
    query = cache.GetSkelQuery(binding.GetSkeleton())
    skinning = binding.GetSkinningTargets()[0]
    rest = UsdGeom.Mesh(skinning.GetPrim()).GetPointsAttr().Get()
    for t in range(len(x["pose"])):
        points = type(rest)(rest)
        assert skinning.ComputeSkinnedPoints(query.ComputeSkinningTransforms(t), points, t)
        np.testing.assert_allclose(np.asarray(points), x["body_vertices"][t], atol=1e-5)
        world = np.asarray(query.ComputeJointWorldTransforms(UsdGeom.XformCache(t)))
        np.testing.assert_allclose(world[:, 3, :3], x["joints"][t], atol=1e-5)


@pytest.mark.slow
def test_split_and_all_export_every_sample_with_frames(store_path, store, tmp_path, capsys, caplog):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    failure = [int(store.scalars(i)["failure"]) for i in range(len(store))]
    code, text, _ = run(capsys, "export", "usd", store_path, "--split", "train", "--out", tmp_path / "train",
                        "--format", "usda")
    assert code == 0
    train = store.split("train")
    expected = [f"sample{i:05d}.usda" for i in train if failure[i] == 0]
    assert sorted(p.name for p in (tmp_path / "train").iterdir()) == expected
    skipped = [int(i) for i in train if failure[i] != 0]
    if skipped:
        assert f"skipped {len(skipped)} failed samples" in text
        assert any("has no recorded frames: skipped" in r.getMessage() for r in caplog.records)
        code, _, err = run(capsys, "export", "usd", store_path, "--sample", skipped[0], "--out", tmp_path / "f.usd")
        assert code == 2 and "no recorded frames" in err and not (tmp_path / "f.usd").exists()
    assert run(capsys, "export", "usd", store_path, "--all", "--out", tmp_path / "all")[0] == 0
    assert len(list((tmp_path / "all").iterdir())) == failure.count(0)


@pytest.mark.slow
def test_bad_sample_split_and_paths_are_clear_errors(store_path, store, tmp_path, capsys):
    from datagen.export.animation import from_store

    n = len(store)
    with pytest.raises(InputError, match=rf"sample {n} is not in store .*valid sample ids are 0 \.\. {n - 1}"):
        from_store(store, n)
    valid = f"valid sample ids are 0 .. {n - 1}"
    for argv, msg in (
        (["export", "usd", store_path, "--sample", n + 3, "--out", tmp_path / "a.usd"], valid),
        (["export", "usd", store_path, "--sample", -1, "--out", tmp_path / "a.usd"], "-1 is out of range: give 0 or more"),
        (["export", "usd", store_path, "--split", "holdout", "--out", tmp_path / "d"], "unknown split 'holdout'"),
        (["export", "usd", store_path, "--sample", 0, "--out", tmp_path / "missing" / "a.usd"], "does not exist"),
        (["export", "usd", store_path, "--sample", 0, "--out", tmp_path / "a.txt"], "must end in one of"),
        (["export", "usd", store_path, "--out", tmp_path / "a.usd"], "--sample ID, --split NAME or --all"),
        (["preview", store_path, "--sample", n, "--out", tmp_path / "p.png"], valid),
        (["preview", store_path, "--sample", 0, "--out", tmp_path / "missing" / "p.png"], "does not exist"),
        (["preview", store_path, "--sample", 0, "--out", tmp_path / "p.jpg"], "p.jpg must end in .png or .gif or .mp4"),
        (["preview", store_path, "--sample", 0, "--view", "top", "--out", tmp_path / "p.png"], "unknown view"),
    ):
        code, _, err = run(capsys, *argv)
        assert code == 2 and msg in err, (argv, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing (half) written


@pytest.mark.slow
def test_preview_frame_is_the_size_asked_and_shows_body_and_garment(store_path, store, ok_sample, tmp_path, capsys):
    from PIL import Image

    i = ok_sample
    T = store.frame_count(i)
    code, _, err = run(capsys, "preview", store_path, "--sample", i, "--frame", T, "--out", tmp_path / "x.png")
    assert code == 2 and f"valid frames are 0 .. {T - 1}" in err
    out = tmp_path / "f.png"
    code, text, _ = run(capsys, "preview", store_path, "--sample", i, "--frame", T - 1, "--view", "three-quarter",
                        "--size", "320x400", "--out", out)
    assert code == 0 and f"frame {T - 1}" in text
    with Image.open(out) as im:
        assert im.size == (320, 400)
        rgb = np.asarray(im.convert("RGB")).astype(float) / 255
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    garment = (b > r + 0.12) & (b > g + 0.05)  # the garment's blue, shaded
    body = (np.abs(r - g) < 0.06) & (r > 0.25) & (r < 0.95) & (r >= b)  # the body's grey
    assert garment.sum() > 100 and body.sum() > 2000, (garment.sum(), body.sum())
    for color_by in ("stretch", "body-distance"):
        path = tmp_path / f"{color_by}.png"
        assert run(capsys, "preview", store_path, "--sample", i, "--color-by", color_by, "--size", "320x400",
                   "--out", path)[0] == 0
        with Image.open(path) as im:
            bar = np.asarray(im.convert("RGB")).astype(float)[60:340, 262:276] / 255  # the colour bar's column
        assert (bar.max(axis=-1) - bar.min(axis=-1) > 0.3).mean() > 0.5  # saturated colours of the colormap


@pytest.mark.slow
def test_preview_gif_has_the_frames_asked(store_path, store, ok_sample, tmp_path, capsys):
    from PIL import Image

    out = tmp_path / "c.gif"
    code, text, _ = run(capsys, "preview", store_path, "--sample", ok_sample, "--frames", "0:6:2", "--view", "side",
                        "--color-by", "region", "--size", "192x240", "--out", out)
    assert code == 0 and "(3 frames)" in text
    with Image.open(out) as im:
        assert im.n_frames == 3 and im.size == (192, 240)
    code, _, err = run(capsys, "preview", store_path, "--sample", ok_sample, "--frames", "0:6", "--out",
                       tmp_path / "x.png")
    assert code == 2 and "a PNG holds one frame" in err


@pytest.mark.slow
def test_preview_of_a_prediction_colours_the_error(store_path, store, ok_sample, tmp_path, capsys):
    from PIL import Image

    x = store.sample(ok_sample, names=["detail"])["detail"]
    np.savez(tmp_path / "pred.npz", garment_vertices=x + np.float32(0.01))
    code, _, err = run(capsys, "preview", store_path, "--sample", ok_sample, "--color-by", "error",
                       "--out", tmp_path / "e.png")
    assert code == 2 and "needs a prediction" in err
    code, _, _ = run(capsys, "preview", store_path, "--sample", ok_sample, "--prediction", tmp_path / "pred.npz",
                     "--color-by", "error", "--size", "256x320", "--out", tmp_path / "e.png")
    assert code == 0
    with Image.open(tmp_path / "e.png") as im:
        assert im.size == (256, 320)
    np.savez(tmp_path / "short.npz", garment_vertices=x[:1])
    code, _, err = run(capsys, "preview", store_path, "--sample", ok_sample, "--prediction", tmp_path / "short.npz",
                       "--out", tmp_path / "s.png")
    assert code == 2 and "frames" in err
