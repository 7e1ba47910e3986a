"""Every body command on the default body; user errors print one line and exit 2."""

import json

import numpy as np
import pytest

from datagen.body.export import named_pose
from datagen.body.shapes import preset_betas
from datagen.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.usefixtures("default_body")
def test_help_has_examples(capsys):
    for argv in (["--help"], ["body", "--help"], ["body", "build", "--help"], ["body", "export", "--help"], ["body", "info", "--help"]):
        with pytest.raises(SystemExit) as e:
            main(argv)
        assert e.value.code == 0
        assert "example" in capsys.readouterr().out


def test_build_writes_an_smpl_file(capsys, tmp_path, default_body):
    code, out, _ = run(capsys, "body", "build", "--out", str(tmp_path / "b.pkl"))
    assert code == 0 and "cache hit" in out and (tmp_path / "b.pkl").stat().st_size > 1e6


def test_info_json(capsys, default_body):
    code, out, _ = run(capsys, "body", "info", "--json")
    info = json.loads(out)
    assert code == 0 and info["vertices"] == 13348 and info["joints"] == 24 and set(info["presets"]) == {"thin", "regular", "fat"}


@pytest.mark.parametrize("fmt", ["npz", "obj", "ply", "usd"])
def test_export_formats(capsys, tmp_path, fmt, default_body):
    out_path = tmp_path / f"body.{'usda' if fmt == 'usd' else fmt}"
    code, _, err = run(capsys, "body", "export", "--body", "fat", "--pose", "a-pose", "--format", fmt, "--out", str(out_path))
    assert code == 0, err
    if fmt == "npz":
        with np.load(out_path) as npz:
            assert npz["vertices"].shape == (13348, 3) and npz["joints"].shape == (24, 3)
    elif fmt == "usd":
        from pxr import Usd, UsdGeom

        stage = Usd.Stage.Open(str(out_path))
        assert UsdGeom.GetStageUpAxis(stage) == "Y" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
        pts = np.array(UsdGeom.Mesh(stage.GetPrimAtPath("/Body/Skin")).GetPointsAttr().Get())
        ref, _ = default_body.pose(preset_betas(default_body, "fat")[None], named_pose("a-pose")[None])
        np.testing.assert_allclose(pts, ref[0], atol=1e-6)
    else:
        import trimesh

        assert len(trimesh.load(out_path, process=False).vertices) == 13348


def test_export_pose_file(capsys, tmp_path, default_body):
    rng = np.random.default_rng(0)
    np.savez(tmp_path / "motion.npz", poses=rng.normal(scale=0.2, size=(5, 156)), trans=np.zeros((5, 3)))
    code, _, err = run(capsys, "body", "export", "--pose", str(tmp_path / "motion.npz"), "--frame", "4", "--out", str(tmp_path / "p.npz"))
    assert code == 0, err


@pytest.mark.parametrize(
    "argv, message",
    [
        (["body", "export", "--pose", "x-pose", "--out", "OUT/a.obj"], "neither a named pose"),
        (["body", "export", "--body", "huge", "--out", "OUT/a.obj"], "unknown body preset 'huge'"),
        (["body", "export", "--betas"] + ["0.1"] * 11 + ["--out", "OUT/a.obj"], "11 β values given; this body has 10"),
        (["body", "export", "--out", "OUT/missing/a.obj"], "does not exist; create it first"),
        (["body", "export", "--out", "OUT/a.xyz", "--pose", "t-pose"], "a.xyz must end in .npz or .obj"),
        (["body", "info", "--model", "OUT/none.pkl"], "does not exist"),
        (["body", "export", "--pose", "OUT/bad.npy", "--out", "OUT/a.obj"], "θ needs 72"),
    ],
)
def test_user_errors_are_one_line(capsys, tmp_path, argv, message, default_body):
    np.save(tmp_path / "bad.npy", np.zeros(10))
    argv = [a.replace("OUT", str(tmp_path)) for a in argv]
    code, _, err = run(capsys, *argv)
    assert code == 2 and message in err and "Traceback" not in err


def test_missing_optional_dependency_says_how_to_install(capsys, tmp_path, monkeypatch, default_body):
    import sys

    monkeypatch.setitem(sys.modules, "pxr", None)  # makes `import pxr` fail as if usd-core were absent
    code, _, err = run(capsys, "body", "export", "--out", str(tmp_path / "a.usda"))
    assert code == 2 and "needs the Python package 'pxr'" in err and "pip install 'drape[usd]'" in err


def test_generate_batch_size_replaces_the_configs_and_is_checked(capsys, tmp_path):
    """``--batch-size`` sets simulation.batch_size (an execution setting) over a preset; out of its
    limits it is refused in one line."""
    assert main(["generate", "--preset", "paper-motion", "--batch-size", "252", "--print-config",
                 "--out", str(tmp_path / "s")]) == 0
    assert json.loads(capsys.readouterr().out)["simulation"]["batch_size"] == 252
    assert main(["generate", "--preset", "paper-motion", "--batch-size", "0", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "error: --batch-size must be in 1..4096, got 0"
