"""Writing a motion on the default body: animated USD mesh and BVH of the body's skeleton."""

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.motion.bvh import read_bvh
from datagen.export.motion import (
    usd_validation_errors,
    write_motion_bvh,
    write_motion_usd,
)
from datagen.motion.motion import Motion
from datagen.geometry.rotations import axis_angle_to_matrix_np


def small_motion(frames=5, fps=24.0):
    rng = np.random.default_rng(2)
    poses = rng.normal(scale=0.3, size=(frames, 24, 3))
    trans = np.cumsum(rng.normal(scale=0.02, size=(frames, 3)), axis=0)
    return Motion(poses=poses, trans=trans, fps=fps, label=0, label_name="walk")


@pytest.mark.parametrize("suffix", [".usda", ".usd"])
def test_usd_points_metadata_and_validation(default_body, tmp_path, suffix):
    pxr = pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from pxr import Usd, UsdGeom

    del pxr
    m = small_motion()
    path = write_motion_usd(m, tmp_path / f"walk{suffix}", default_body, with_skeleton=True)
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == 24.0 and stage.GetFramesPerSecond() == 24.0
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, 4.0)
    assert stage.GetDefaultPrim().GetPath() == "/Body"
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Body/Skin"))
    points = mesh.GetPointsAttr()
    assert points.GetTimeSamples() == [0.0, 1.0, 2.0, 3.0, 4.0]
    expected, joints = default_body.pose(None, m.poses, m.trans)
    for k in range(5):
        got = np.asarray(points.Get(k))
        assert got.dtype == np.float32 and got.shape == (default_body.vertex_count, 3)
        np.testing.assert_array_equal(got, expected[k].astype(np.float32))
        ext = np.asarray(mesh.GetExtentAttr().Get(k))
        np.testing.assert_array_equal(ext, [got.min(0), got.max(0)])
    np.testing.assert_array_equal(np.asarray(mesh.GetFaceVertexIndicesAttr().Get()), default_body.faces.reshape(-1))
    assert set(np.asarray(mesh.GetFaceVertexCountsAttr().Get()).tolist()) == {3}
    bones = UsdGeom.BasisCurves(stage.GetPrimAtPath("/Body/Bones"))
    seg = np.asarray(bones.GetPointsAttr().Get(3)).reshape(23, 2, 3)
    np.testing.assert_allclose(seg[:, 1], joints[3, 1:], atol=1e-6)
    assert usd_validation_errors(path) == []


def test_validation_reports_problems(tmp_path):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    from pxr import Usd, UsdGeom

    bad = tmp_path / "bad.usda"
    stage = Usd.Stage.CreateNew(str(bad))  # no upAxis, metersPerUnit or default prim
    UsdGeom.Xform.Define(stage, "/A")
    stage.GetRootLayer().Save()
    assert usd_validation_errors(bad)


def test_usd_errors(default_body, tmp_path):
    pytest.importorskip("pxr", reason="USD export needs usd-core (pip install 'drape[usd]')")
    with pytest.raises(InputError, match=r"\.usda"):
        write_motion_usd(small_motion(), tmp_path / "walk.obj", default_body)
    with pytest.raises(InputError, match="does not exist"):
        write_motion_usd(small_motion(), tmp_path / "no" / "walk.usd", default_body)


def test_bvh_of_the_body_round_trips(default_body, tmp_path):
    m = small_motion()
    path = write_motion_bvh(m, tmp_path / "walk.bvh", default_body)
    back = read_bvh(path, label_name="walk")
    np.testing.assert_allclose(axis_angle_to_matrix_np(back.poses), axis_angle_to_matrix_np(m.poses), atol=1e-5)
    np.testing.assert_allclose(back.trans, m.trans, atol=1e-6)
    assert back.fps == m.fps
