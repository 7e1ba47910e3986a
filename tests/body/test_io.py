"""Body files: drape's files load in smplx and pose identically; real SMPL files load in drape."""

import pickle
import sys
import types

import numpy as np
import pytest
import scipy.sparse
import torch

from datagen.body.io import load_body_file, save_body_file
from datagen.errors import InputError


def smplx_pose(path, betas, pose, dtype=torch.float64):
    import smplx
    from smplx.vertex_ids import vertex_ids

    # smplx's extra keypoints index SMPL's own vertices; point them at vertex 0 for small meshes.
    ids = {k: 0 for k in vertex_ids["smplh"]} if load_body_file(path).vertex_count < 6890 else None
    model = smplx.SMPL(model_path=str(path), dtype=dtype, vertex_ids=ids)
    out = model(betas=torch.tensor(betas, dtype=dtype), global_orient=torch.tensor(pose[:, :3], dtype=dtype),
                body_pose=torch.tensor(pose[:, 3:], dtype=dtype))
    return out.vertices.detach().numpy()


@pytest.mark.parametrize("suffix", [".pkl", ".npz"])
def test_default_body_round_trips_and_matches_smplx(default_body, tmp_path, suffix):
    path = save_body_file(default_body, tmp_path / f"body{suffix}")
    loaded = load_body_file(path)
    for key in ("v_template", "shapedirs", "J_regressor", "weights", "faces", "parents"):
        np.testing.assert_array_equal(getattr(loaded, key), getattr(default_body, key))
    assert loaded.posedirs is None and loaded.meta["rest_pose"] == "t-pose"
    rng = np.random.default_rng(11)
    betas, pose = rng.normal(size=(6, 10)), rng.normal(scale=0.5, size=(6, 72))
    ours, _ = default_body.pose(betas, pose)
    if suffix == ".pkl":  # smplx.SMPL reads pickles
        assert np.abs(smplx_pose(path, betas, pose) - ours).max() < 1e-5
        assert np.abs(smplx_pose(path, betas, pose, torch.float32) - ours).max() < 1e-5


def test_pkl_is_small_with_zero_posedirs(default_body, tmp_path):
    path = save_body_file(default_body, tmp_path / "body.pkl")
    with open(path, "rb") as fh:
        raw = pickle.load(fh, encoding="latin1")
    assert raw["posedirs"].shape == (default_body.vertex_count, 3, 207) and not raw["posedirs"].any()
    assert path.stat().st_size < 20e6


def _write_real_smpl_style(path, model):
    """Write ``model`` as SMPL's own files are: a protocol-2 pickle whose arrays are chumpy
    objects, a scipy.sparse J_regressor, 300 shape components and SMPL's extra keys."""
    chumpy = types.ModuleType("chumpy")
    ch_mod = types.ModuleType("chumpy.ch")

    class Ch:  # what chumpy's Ch pickles as: its state dict holds the value under 'x'
        def __init__(self, x):
            self.x = x

    Ch.__module__, Ch.__qualname__ = "chumpy.ch", "Ch"
    ch_mod.Ch = Ch
    sys.modules["chumpy"], sys.modules["chumpy.ch"] = chumpy, ch_mod
    try:
        V = model.vertex_count
        shapedirs = np.concatenate([model.shapedirs, np.zeros((V, 3, 290))], axis=2)
        rng = np.random.default_rng(5)
        posedirs = rng.normal(scale=1e-3, size=(V, 3, 207))
        data = {
            "v_template": Ch(model.v_template), "shapedirs": Ch(shapedirs), "posedirs": posedirs,
            "J_regressor": scipy.sparse.csc_matrix(model.J_regressor), "weights": Ch(model.weights),
            "kintree_table": np.stack([np.array([4294967295] + list(model.parents[1:])), np.arange(24)]),
            "f": model.faces.astype(np.uint32), "J": Ch(model.rest_joints()[0]), "bs_style": "lbs", "bs_type": "lrotmin",
            "weights_prior": Ch(model.weights), "vert_sym_idxs": np.arange(V),
        }
        with open(path, "wb") as fh:
            pickle.dump(data, fh, protocol=2)
    finally:
        del sys.modules["chumpy"], sys.modules["chumpy.ch"]
    return posedirs


def test_real_smpl_format_file_loads_without_chumpy(small_model, tmp_path):
    path = tmp_path / "SMPL_NEUTRAL.pkl"
    posedirs = _write_real_smpl_style(path, small_model)
    loaded = load_body_file(path)
    assert loaded.shape_dim == 300 and loaded.has_pose_blendshapes
    np.testing.assert_allclose(loaded.posedirs, posedirs.reshape(-1, 207).T)
    rng = np.random.default_rng(9)
    betas, pose = rng.normal(size=(3, 10)), rng.normal(scale=0.5, size=(3, 72))
    expected, _ = small_model.replace(posedirs=posedirs.reshape(-1, 207).T.copy()).pose(betas, pose)
    got, _ = loaded.pose(betas, pose)
    np.testing.assert_allclose(got, expected, atol=1e-12)


def test_real_smpl_format_without_chumpy_objects_matches_smplx(small_model, tmp_path):
    path = tmp_path / "smpl_plain.pkl"
    model = small_model
    data = {"v_template": model.v_template, "shapedirs": model.shapedirs, "posedirs": model.posedirs.T.reshape(-1, 3, 207),
            "J_regressor": scipy.sparse.csc_matrix(model.J_regressor), "weights": model.weights,
            "kintree_table": np.stack([np.array([4294967295] + list(model.parents[1:])), np.arange(24)]),
            "f": model.faces.astype(np.uint32)}
    with open(path, "wb") as fh:
        pickle.dump(data, fh, protocol=2)
    rng = np.random.default_rng(10)
    betas, pose = rng.normal(size=(2, 10)), rng.normal(scale=0.5, size=(2, 72))
    ours, _ = load_body_file(path).pose(betas, pose)
    assert np.abs(smplx_pose(path, betas, pose) - ours).max() < 1e-5


def test_bad_body_files(tmp_path, small_model):
    with pytest.raises(InputError, match="does not exist"):
        load_body_file(tmp_path / "nope.pkl")
    (tmp_path / "garbage.pkl").write_bytes(b"hello world")
    with pytest.raises(InputError, match="neither an npz archive nor a pickle"):
        load_body_file(tmp_path / "garbage.pkl")
    (tmp_path / "trunc.pkl").write_bytes(pickle.dumps({"a": np.zeros(1000)}, protocol=2)[:50])
    with pytest.raises(InputError, match="could not be read"):
        load_body_file(tmp_path / "trunc.pkl")
    np.savez(tmp_path / "partial.npz", v_template=np.zeros((3, 3)))
    with pytest.raises(InputError, match="lacks shapedirs, posedirs"):
        load_body_file(tmp_path / "partial.npz")

    class Evil:
        def __reduce__(self):
            import os

            return (os.system, ("echo pwned",))

    (tmp_path / "evil.pkl").write_bytes(pickle.dumps({"v_template": Evil()}, protocol=2))
    with pytest.raises(InputError, match="not part of an SMPL file"):
        load_body_file(tmp_path / "evil.pkl")
    good = save_body_file(small_model, tmp_path / "ok.npz")
    with np.load(good) as npz:
        arrays = dict(npz)
    arrays["weights"] = arrays["weights"][:-1]
    np.savez(tmp_path / "badshape.npz", **arrays)
    with pytest.raises(InputError, match=r"weights must be \[V=300, J=24\]"):
        load_body_file(tmp_path / "badshape.npz")
    with pytest.raises(InputError, match="must end in .npz or .pkl"):
        save_body_file(small_model, tmp_path / "x.obj")


def test_concurrent_writers_of_one_body_file(small_model, tmp_path):
    """Processes that build the same cached body at once each write a file of their own and rename
    it into place (the workers of benchmarks/garment_cache.py once collided on one temporary name: the
    second rename found nothing and its garment was never built); nothing temporary is left."""
    from concurrent.futures import ThreadPoolExecutor

    path = tmp_path / "body.npz"
    with ThreadPoolExecutor(4) as pool:
        written = list(pool.map(lambda _: save_body_file(small_model, path), range(8)))
    assert written == [path] * 8
    assert load_body_file(path).vertex_count == small_model.vertex_count
    assert sorted(p.name for p in tmp_path.iterdir()) == ["body.npz"]
