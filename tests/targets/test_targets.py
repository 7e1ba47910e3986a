"""Training targets of paper 000: coarse smoothing, indicator, anchors, features, fit attribute."""

from __future__ import annotations

import inspect
import time

import numpy as np
import pytest
import trimesh

from datagen.errors import InputError
from datagen.geometry.topology import vertex_normals_np
from datagen.targets import (
    FitAttributeModel,
    FitPair,
    SmoothingConfig,
    coarse_from_detail,
    even_subsample,
    factor_scores,
    fit_attribute,
    fit_attribute_model,
    fit_pair,
    garment_correspondence,
    laplacian_operator,
    skinning_transforms,
    smooth_vertices,
)
from tests.targets.feature_oracle import (
    TARGET_NAMES,
    joint_distances,
    pose_body_rows,
    relative_skinning,
    sample_targets,
)


# ----------------------------------------------------------------------------- fixtures

@pytest.fixture(scope="module")
def betas(default_body):
    from datagen.body.shapes import resolve_betas

    return resolve_betas(default_body, body="regular")[0]


@pytest.fixture(scope="module")
def tshirt(default_body, betas):
    from datagen.garment.types import make_garment

    return make_garment("tshirt", default_body, betas, seed=0)


@pytest.fixture(scope="module")
def correspondence(tshirt, subdivided_body, betas):
    return garment_correspondence(tshirt.vertices, subdivided_body, betas)


def _motion(T, seed=0, scale=0.25):
    rng = np.random.default_rng(seed)
    return rng.normal(scale=scale, size=(T, 24, 3)), rng.normal(scale=0.3, size=(T, 3))


def _detail(tshirt, subdivided_body, betas, indicator, poses, trans, seed=0):
    """A stand-in for simulated frames: the garment skinned with its indicator weights plus 3 mm noise."""
    _, _, rel = skinning_transforms(subdivided_body, betas, poses)
    skinned = relative_skinning(tshirt.vertices, subdivided_body.weights[indicator], rel) + trans[:, None]
    return skinned + np.random.default_rng(seed).normal(scale=0.003, size=skinned.shape)


def _grid(n=21, spacing=0.01):
    """A flat n x n grid in the x-y plane (z = 0), two triangles per cell."""
    x, y = np.meshgrid(np.arange(n) * spacing, np.arange(n) * spacing, indexing="ij")
    v = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    f = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return v, f


# ----------------------------------------------------------------------------- coarse smoothing

@pytest.mark.parametrize("boundary", ["loop", "free"])
def test_smoothing_equals_trimesh_on_one_frame(tshirt, boundary):
    rng = np.random.default_rng(3)
    frames = tshirt.vertices[None] + rng.normal(scale=0.004, size=(3,) + tshirt.vertices.shape)
    config = SmoothingConfig(boundary=boundary)
    L = laplacian_operator(tshirt.faces, len(tshirt.vertices), boundary=boundary)
    ours = coarse_from_detail(frames, tshirt.faces, config, operator=L)
    mesh = trimesh.Trimesh(frames[1].copy(), tshirt.faces, process=False)
    ref = trimesh.smoothing.filter_laplacian(mesh, lamb=0.12, iterations=40, volume_constraint=False,
                                             laplacian_operator=L).vertices
    np.testing.assert_allclose(ours[1], ref, atol=1e-12, rtol=0)
    assert np.abs(ours[1] - frames[1]).max() > 1e-3  # it did smooth


def test_free_operator_is_trimesh_operator_away_from_the_boundary(tshirt):
    """trimesh builds its operator from directed face edges: at a boundary vertex it drops the
    neighbour reached by the incoming boundary edge. Elsewhere the two are the same matrix."""
    mesh = trimesh.Trimesh(tshirt.vertices, tshirt.faces, process=False)
    ours = laplacian_operator(tshirt.faces, len(tshirt.vertices), boundary="free").toarray()
    theirs = trimesh.smoothing.laplacian_calculation(mesh).toarray()
    border = np.zeros(len(tshirt.vertices), dtype=bool)
    for loop in tshirt.loops.values():
        border[loop] = True
    np.testing.assert_allclose(ours[~border], theirs[~border], atol=1e-15)
    assert not np.allclose(ours[border], theirs[border])
    np.testing.assert_allclose(ours.sum(1), 1.0, atol=1e-12)


def test_smoothing_removes_a_bump_and_keeps_the_boundary():
    v, f = _grid()
    n = 21
    centre = (n // 2) * n + n // 2
    spike = v.copy()
    spike[centre, 2] = 0.01  # a 1 cm spike on one vertex
    out = coarse_from_detail(spike[None], f)[0]
    assert out[centre, 2] < 0.1 * 0.01 and out[:, 2].min() >= 0
    np.testing.assert_allclose(out[:, 2].sum(), 0.01, rtol=0.05)  # spread out, not removed
    checker = v.copy()
    checker[:, 2] = ((np.arange(n)[:, None] + np.arange(n)[None]) % 2).ravel() * 0.002  # 2 mm checkerboard
    out = coarse_from_detail(checker[None], f)[0]
    interior = (v[:, :2].min(1) > 0.045) & (v[:, :2].max(1) < 0.155)
    assert np.ptp(out[interior, 2]) < 0.1 * 0.002  # the highest frequencies are gone
    np.testing.assert_allclose(out[interior, 2].mean(), 0.001, atol=2e-4)  # around the mean level
    # "loop" boundary: straight open borders stay where they are in the plane (no shrinking);
    # "free" boundary pulls them into the mesh
    flat_loop = coarse_from_detail(v[None], f)[0]
    flat_free = coarse_from_detail(v[None], f, SmoothingConfig(boundary="free"))[0]
    mid_edge = (v[:, 0] == 0) & (np.abs(v[:, 1] - 0.1) < 0.025)  # 5+ vertices from the corners, which round off
    assert np.abs(flat_loop[mid_edge] - v[mid_edge]).max() < 2e-6
    assert flat_free[mid_edge, 0].min() > 0.01  # more than one edge length


def test_smoothing_leaves_its_input_alone(tshirt):
    frames = np.repeat(tshirt.vertices[None], 2, axis=0) + 0.001
    frames_t = np.ascontiguousarray(frames.transpose(1, 0, 2)).transpose(1, 0, 2)  # a view laid out [V, T, 3]
    before = frames_t.copy()
    smooth_vertices(frames_t, laplacian_operator(tshirt.faces, len(tshirt.vertices)))
    np.testing.assert_array_equal(frames_t, before)


# ----------------------------------------------------------------------------- correspondence

def test_indicator_is_the_closest_subdivided_body_vertex(tshirt, subdivided_body, betas, correspondence):
    ind = correspondence["indicator"]
    assert ind.dtype == np.int32 and ind.shape == (len(tshirt.vertices),)
    body = subdivided_body.shaped(betas[None])[0]
    rng = np.random.default_rng(0)
    pick = rng.choice(len(tshirt.vertices), 150, replace=False)
    d2 = ((tshirt.vertices[pick, None, :] - body[None]) ** 2).sum(-1)
    np.testing.assert_array_equal(ind[pick], d2.argmin(1))
    np.testing.assert_allclose(correspondence["body_distance"][pick], np.sqrt(d2.min(1)), atol=1e-6)
    np.testing.assert_array_equal(correspondence["skin_weights"], subdivided_body.weights[ind].astype(np.float32))
    # every garment vertex is built at least MIN_CLEARANCE off the body, and not far
    assert correspondence["body_distance"].min() > 0.005 and correspondence["body_distance"].max() < 0.15


def test_pose_body_rows_equals_full_posing_with_pose_blend_shapes(small_model):
    poses, trans = _motion(3, seed=5)
    betas = np.random.default_rng(2).normal(size=10)
    rows = np.array([5, 0, 17, 299, 5])
    full, _ = small_model.pose(betas[None], poses, trans)
    np.testing.assert_allclose(pose_body_rows(small_model, betas, poses, trans, rows), full[:, rows], atol=1e-12)


# ----------------------------------------------------------------------------- per-frame targets

@pytest.fixture(scope="module")
def short_sample(tshirt, subdivided_body, betas, correspondence):
    poses, trans = _motion(3, seed=1)
    ind = correspondence["indicator"]
    detail = _detail(tshirt, subdivided_body, betas, ind, poses, trans)
    out = sample_targets(tshirt.vertices, tshirt.faces, subdivided_body, betas, poses, trans, detail, indicator=ind)
    return poses, trans, detail, out


def test_targets_have_the_documented_shapes(tshirt, short_sample):
    _, _, detail, out = short_sample
    V = len(tshirt.vertices)
    assert tuple(out) == TARGET_NAMES
    shapes = {"joint_distance": (3, V, 24), "joints": (3, 24, 3)}
    for name, arr in out.items():
        assert arr.dtype == np.float32 and arr.shape == shapes.get(name, (3, V, 3)), name
        assert np.isfinite(arr).all()
    np.testing.assert_allclose(np.linalg.norm(out["coarse_normal"], axis=-1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(out["anchor_normal"], axis=-1), 1.0, atol=1e-5)
    # the decomposition of eq. (5) and (9) is exact in the stored arrays
    delta_coarse = out["coarse"] - out["anchor"]
    delta_detail = detail.astype(np.float32) - out["coarse"]
    np.testing.assert_allclose(out["anchor"] + delta_coarse + delta_detail, detail, atol=1e-6)


def test_anchor_is_the_posed_subdivided_body_at_the_indicator(subdivided_body, betas, correspondence, short_sample):
    poses, trans, _, out = short_sample
    ind = correspondence["indicator"]
    full, joints = subdivided_body.pose(betas[None], poses[1:2], trans[1:2])  # the whole 53k-vertex body, once
    np.testing.assert_allclose(out["anchor"][1], full[0, ind], atol=2e-6)
    np.testing.assert_allclose(out["anchor_normal"][1], vertex_normals_np(full[0], subdivided_body.faces)[ind], atol=2e-6)
    np.testing.assert_allclose(out["joints"][1], joints[0], atol=2e-6)
    # the body normals point out of the body, towards the garment that covers it
    toward = np.einsum("ij,ij->i", out["anchor_normal"][1], out["coarse"][1] - out["anchor"][1])
    assert (toward > 0).mean() > 0.95


def test_relative_skinning_ignores_translation_and_is_the_rest_shape_at_rest(tshirt, subdivided_body, betas,
                                                                            correspondence, short_sample):
    poses, trans, detail, out = short_sample
    ind = correspondence["indicator"]
    shift = np.array([1.5, -0.4, 2.0])
    moved = sample_targets(tshirt.vertices, tshirt.faces, subdivided_body, betas, poses, trans + shift,
                           detail + shift, indicator=ind)
    for name in ("anchor_skin", "skin", "anchor_normal", "coarse_normal", "joint_distance"):
        np.testing.assert_allclose(moved[name], out[name], atol=2e-5, err_msg=name)
    np.testing.assert_allclose(moved["anchor"], out["anchor"] + shift, atol=2e-5)
    # no pose blend shapes on the default body: the feature is the posed body without its translation
    np.testing.assert_allclose(out["anchor_skin"], out["anchor"] - trans[:, None], atol=2e-6)
    # in the rest pose the feature is the rest position
    rest = np.zeros((2, 24, 3))
    at_rest = sample_targets(tshirt.vertices, tshirt.faces, subdivided_body, betas, rest, trans[:2], detail[:2],
                             indicator=ind)
    body_rest = subdivided_body.shaped(betas[None])[0]
    for t in range(2):
        np.testing.assert_allclose(at_rest["skin"][t], tshirt.vertices, atol=1e-6)
        np.testing.assert_allclose(at_rest["anchor_skin"][t], body_rest[ind], atol=1e-6)


def test_joint_distances_equal_a_plain_loop(short_sample):
    _, _, _, out = short_sample
    coarse, joints = out["coarse"].astype(np.float64), out["joints"].astype(np.float64)
    some = np.arange(0, coarse.shape[1], 5)
    ref = np.empty((coarse.shape[0], len(some), 24))
    for t in range(coarse.shape[0]):
        for k, i in enumerate(some):
            for s in range(24):
                ref[t, k, s] = np.sqrt(((coarse[t, i] - joints[t, s]) ** 2).sum())
    np.testing.assert_allclose(out["joint_distance"][:, some], ref, atol=1e-6)
    np.testing.assert_allclose(joint_distances(coarse, joints)[:, some], ref, atol=1e-12)


def test_sample_targets_rejects_mismatched_frames(tshirt, subdivided_body, betas, short_sample):
    poses, trans, detail, _ = short_sample
    with pytest.raises(InputError, match="detail must be"):
        sample_targets(tshirt.vertices, tshirt.faces, subdivided_body, betas, poses, trans, detail[:2])


def test_sample_targets_time_for_sixty_frames(tshirt, subdivided_body, betas, correspondence):
    """Not a timed assertion: prints seconds for a ~3,000-vertex garment over T = 60 frames."""
    poses, trans = _motion(60, seed=2)
    ind = correspondence["indicator"]
    detail = _detail(tshirt, subdivided_body, betas, ind, poses, trans)
    t0 = time.perf_counter()
    out = sample_targets(tshirt.vertices, tshirt.faces, subdivided_body, betas, poses, trans, detail, indicator=ind)
    seconds = time.perf_counter() - t0
    print(f"\nsample_targets: {len(tshirt.vertices)} garment vertices, {subdivided_body.vertex_count} body "
          f"vertices, T = 60: {seconds:.2f} s")
    assert out["coarse"].shape == (60, len(tshirt.vertices), 3)


# ----------------------------------------------------------------------------- fit attribute

def test_even_subsample_is_deterministic_and_even(tshirt):
    V, count = len(tshirt.vertices), 1500
    a = even_subsample(tshirt.vertices, tshirt.faces, count, seed=0)
    b = even_subsample(tshirt.vertices, tshirt.faces, count, seed=0)
    np.testing.assert_array_equal(a, b)
    assert len(np.unique(a)) == count and a.dtype == np.int64
    assert not np.array_equal(np.sort(a), np.sort(even_subsample(tshirt.vertices, tshirt.faces, count, seed=1)))
    assert (np.diff(tshirt.vertices[a, 1]) <= 0).all()  # listed from the top down
    from scipy.spatial import cKDTree

    def spacing(idx):
        d, _ = cKDTree(tshirt.vertices[idx]).query(tshirt.vertices[idx], k=2)
        return d[:, 1].min()

    # count points packed hexagonally on the area A sit sqrt(2 A / (sqrt(3) count)) = 1.07 sqrt(A / count)
    # apart; the greedy pick keeps at least 0.6 of that, a random pick is as close as the mesh's
    # shortest edge (the garment builder keeps that at half the target edge length, so the ratio
    # to a random pick depends on the mesh and is not what is tested)
    ideal = np.sqrt(tshirt.metadata.rest_area_m2 / count)
    random_pick = np.random.default_rng(0).choice(V, count, replace=False)
    assert spacing(a) > 0.6 * ideal and spacing(a) > 1.3 * spacing(random_pick)
    gap, _ = cKDTree(tshirt.vertices[a]).query(tshirt.vertices)  # every vertex has a chosen one nearby
    assert gap.max() < 2.5 * ideal
    np.testing.assert_array_equal(np.sort(even_subsample(tshirt.vertices, tshirt.faces, V)), np.arange(V))
    with pytest.raises(InputError, match="at most"):
        even_subsample(tshirt.vertices, tshirt.faces, V + 1)


def test_fit_pair_distances_are_the_indicator_distances(tshirt, subdivided_body, betas, correspondence):
    pair = fit_pair(tshirt.vertices, tshirt.faces, subdivided_body, betas, correspondence["indicator"])
    np.testing.assert_allclose(pair.distances, correspondence["body_distance"], atol=1e-6)


def _three_factor_pairs(pair_count, seed):
    """Pairs on one 8 x 8 grid garment whose 64 distances follow d = μ + Lᵀ z + ε, with 3 factors."""
    v, f = _grid(8)
    rng = np.random.default_rng(seed)
    L = rng.normal(scale=0.01, size=(3, len(v)))
    mu = 0.03 + 0.005 * rng.random(len(v))
    psi = (0.001 + 0.001 * rng.random(len(v))) ** 2
    z = rng.normal(size=(pair_count, 3))
    d = mu + z @ L + rng.normal(size=(pair_count, len(v))) * np.sqrt(psi)
    return [FitPair(vertices=v, faces=f, distances=row) for row in d], L, mu, psi


def test_factor_analysis_recovers_a_known_three_factor_structure():
    pairs, L, mu, psi = _three_factor_pairs(2000, seed=4)
    model = fit_attribute_model(pairs)
    order = even_subsample(pairs[0].vertices, pairs[0].faces, 64, seed=0)
    L, mu, psi = L[:, order], mu[order], psi[order]
    assert model.components.shape == (3, 64) and model.subsample.tolist() == [1, 64, 0]
    # loadings are identified up to a rotation: compare the spanned subspace and the covariance
    q_true, _ = np.linalg.qr(L.T)
    q_fit, _ = np.linalg.qr(model.components.T)
    cosines = np.linalg.svd(q_true.T @ q_fit, compute_uv=False)
    assert cosines.min() > 0.99
    cov_true = L.T @ L + np.diag(psi)
    cov_fit = model.components.T @ model.components + np.diag(model.noise_variance)
    assert np.linalg.norm(cov_fit - cov_true) / np.linalg.norm(cov_true) < 0.1
    np.testing.assert_allclose(model.mean, mu, atol=0.002)
    assert (model.components.sum(axis=1) >= 0).all()


def test_array_transform_equals_sklearn_and_fit_is_deterministic():
    from sklearn.decomposition import FactorAnalysis
    from threadpoolctl import threadpool_limits

    pairs, *_ = _three_factor_pairs(300, seed=6)
    train, test = pairs[:200], pairs[200:]
    model = fit_attribute_model(train)
    again = fit_attribute_model(train)
    for name, arr in model.as_arrays().items():
        np.testing.assert_array_equal(arr, again.as_arrays()[name])
    # the same fit by scikit-learn directly, up to each factor's sign
    order = even_subsample(train[0].vertices, train[0].faces, 64, seed=0)
    X_train = np.stack([p.distances[order] for p in train])
    X_test = np.stack([p.distances[order] for p in test])
    with threadpool_limits(limits=1, user_api="blas"):  # as fit_attribute_model does (speed only)
        fa = FactorAnalysis(n_components=3, svd_method="lapack", random_state=0).fit(X_train)
    np.testing.assert_allclose(np.abs(model.components), np.abs(fa.components_), atol=1e-12)
    np.testing.assert_allclose(model.noise_variance, fa.noise_variance_, atol=1e-15)
    np.testing.assert_allclose(factor_scores(X_test, fa.components_, fa.mean_, fa.noise_variance_),
                               fa.transform(X_test), atol=1e-10)
    # applied from plain arrays alone (as stored), to pairs it never saw
    arrays = {k: np.array(v) for k, v in model.as_arrays().items()}
    fa.components_ = model.components  # scikit-learn with our sign convention
    alpha = np.stack([fit_attribute(arrays, p) for p in test])
    np.testing.assert_allclose(alpha, fa.transform(X_test), atol=1e-10)
    assert alpha.shape == (100, 3)
    np.testing.assert_array_equal(FitAttributeModel.from_arrays(arrays).as_arrays()["subsample"], [1, 64, 0])


def test_fitting_takes_the_training_pairs_only(tshirt):
    params = inspect.signature(fit_attribute_model).parameters
    positional = [n for n, p in params.items() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    assert positional == ["train_pairs"]
    assert not {"split", "test_pairs", "all_pairs", "mask"} & set(params)
    with pytest.raises(InputError, match="training pairs"):
        fit_attribute_model([])
    # a model fitted with N_g* larger than a held-out garment says how to fix it
    pairs, *_ = _three_factor_pairs(10, seed=1)
    model = fit_attribute_model(pairs)
    small_v, small_f = _grid(5)
    with pytest.raises(InputError, match="smaller subsample count"):
        fit_attribute(model, FitPair(vertices=small_v, faces=small_f, distances=np.zeros(len(small_v))))


# ----------------------------------------------------------------------------- derived on read (schema 4)

@pytest.fixture(scope="module")
def store_body(default_body, subdivided_body):
    """The body group exactly as drape generate stores it (float32, subdivision recipe)."""
    from datagen.body.subdivide import subdivision_edges

    m = default_body
    f32 = np.float32
    edges = subdivision_edges(m.faces)
    return {"v_template": m.v_template.astype(f32), "shapedirs": m.shapedirs.astype(f32),
            "J_regressor": np.asarray(m.J_regressor.todense() if hasattr(m.J_regressor, "todense") else m.J_regressor,
                                      dtype=f32),
            "weights": m.weights.astype(f32), "parents": np.asarray(m.parents, np.int32),
            "faces": m.faces.astype(np.int32), "subdivision_edges": edges,
            "subdivided_faces": subdivided_body.faces.astype(np.int32)}


def test_subdivision_recipe_rebuilds_the_subdivided_body(default_body, subdivided_body, store_body, betas):
    from datagen.features import body_shape, subdivided_rows

    shape = body_shape(store_body, betas)
    assert shape.subdivided_vertex_count == subdivided_body.vertex_count
    rows = np.arange(0, subdivided_body.vertex_count, 7)
    rest, weights = subdivided_rows(shape, rows)
    np.testing.assert_allclose(rest, subdivided_body.shaped(betas[None])[0][rows], atol=2e-6)
    np.testing.assert_allclose(weights, subdivided_body.weights[rows], atol=1e-6)


def test_derived_features_equal_the_paper_definitions(tshirt, subdivided_body, default_body, store_body, betas,
                                                      correspondence, short_sample):
    """Every array the schema-3 store kept and schema 4 derives, against sample_targets (paper 000 §4)."""
    import torch

    from datagen.features import bind_garment, body_shape, derive
    from datagen.targets import stored_targets
    from schemas.dataset import DERIVED

    poses, trans, detail, out = short_sample
    kept = stored_targets(tshirt.faces, subdivided_body, betas, poses, trans, detail)
    for name in ("coarse", "joints"):
        np.testing.assert_array_equal(kept[name], out[name])
    binding = bind_garment(body_shape(store_body, betas), tshirt.vertices, tshirt.faces, correspondence["indicator"])
    names = list(DERIVED)
    got = derive(binding, names, pose=poses, trans=trans, coarse=out["coarse"], joints=out["joints"])
    for name in names:
        if name == "body_vertices":
            ref, _ = default_body.pose(betas[None], poses, trans)
            np.testing.assert_allclose(got[name], ref, atol=2e-5, err_msg=name)
        else:
            assert got[name].shape == out[name].shape and got[name].dtype == np.float32, name
            np.testing.assert_allclose(got[name], out[name], atol=2e-5, err_msg=name)
    # the same function on torch tensors (float32, the trainers' path) agrees
    t = lambda a: torch.as_tensor(np.asarray(a), dtype=torch.float32)  # noqa: E731
    got_t = derive(binding, names, pose=t(poses), trans=t(trans), coarse=t(out["coarse"]), joints=t(out["joints"]))
    for name in names:
        assert isinstance(got_t[name], torch.Tensor) and got_t[name].dtype == torch.float32
        np.testing.assert_allclose(got_t[name].numpy(), got[name], atol=5e-5, err_msg=name)
    with pytest.raises(InputError, match="needs \\['coarse'\\]"):
        derive(binding, ["coarse_normal"], pose=poses)


def test_positions_round_trip_within_the_stated_bound():
    from datagen.geometry.positions import decode_positions, encode_positions
    from schemas.dataset import POSITION_QUANTUM

    rng = np.random.default_rng(0)
    x = rng.normal(scale=0.6, size=(4, 500, 3)).astype(np.float32)
    root = rng.normal(size=(4, 3)).astype(np.float32)
    steps = encode_positions(x, root, POSITION_QUANTUM)
    assert steps.dtype == np.int32
    err = np.abs(decode_positions(steps, root, POSITION_QUANTUM).astype(np.float64) - x).max()
    assert POSITION_QUANTUM / 2 * 0.9 < err <= POSITION_QUANTUM / 2 + 4e-7, err

