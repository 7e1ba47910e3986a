"""4-to-1 subdivision: V' = V + E, every linear quantity carried, posing close to subdividing."""

import numpy as np

from datagen.body.subdivide import subdivision_posing_error, unique_edge_count


def test_vertex_count_is_v_plus_e(default_body, subdivided_body):
    assert subdivided_body.vertex_count == default_body.vertex_count + unique_edge_count(default_body.faces)
    assert subdivided_body.face_count == 4 * default_body.face_count
    assert subdivided_body.meta["subdivision_level"] == 1


def test_linear_quantities_are_carried(default_body, subdivided_body):
    V = default_body.vertex_count
    np.testing.assert_array_equal(subdivided_body.v_template[:V], default_body.v_template)
    np.testing.assert_allclose(subdivided_body.weights.sum(1), 1.0, atol=1e-12)
    assert subdivided_body.weights.min() >= 0
    # Every new vertex is the midpoint of an edge for template, shape directions and weights alike.
    f = default_body.faces
    e = np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1), axis=0)
    mid = 0.5 * (default_body.v_template[e[:, 0]] + default_body.v_template[e[:, 1]])
    new = subdivided_body.v_template[V:]
    # match each new vertex to its edge through positions (trimesh orders edges its own way)
    from scipy.spatial import cKDTree

    d, idx = cKDTree(mid).query(new)
    assert d.max() < 1e-12
    for name in ("shapedirs", "weights"):
        coarse = getattr(default_body, name).reshape(V, -1)
        fine = getattr(subdivided_body, name).reshape(subdivided_body.vertex_count, -1)
        np.testing.assert_allclose(fine[V:], 0.5 * (coarse[e[idx, 0]] + coarse[e[idx, 1]]), atol=1e-12)


def test_joints_unchanged(default_body, subdivided_body):
    rng = np.random.default_rng(0)
    betas = rng.normal(size=(3, 10))
    np.testing.assert_allclose(subdivided_body.rest_joints(betas), default_body.rest_joints(betas), atol=1e-12)


def test_posing_matches_subdividing_the_posed_mesh(default_body):
    rng = np.random.default_rng(1)
    betas, pose = rng.normal(size=(2, 10)), rng.normal(scale=0.3, size=(2, 72))
    err = subdivision_posing_error(default_body, betas, pose)
    V = default_body.vertex_count
    assert err[:, :V].max() < 1e-12  # original vertices pose identically
    assert err.max() < 0.006 and err.mean() < 1e-4  # stated tolerance: 6 mm max, 0.1 mm mean


def test_rigid_pose_is_exact(default_body):
    pose = np.zeros((1, 24, 3))
    pose[0, 0] = [0.3, -1.0, 0.2]  # root only: every vertex moves rigidly, so LBS is linear
    err = subdivision_posing_error(default_body, None, pose)
    assert err.max() < 1e-12
