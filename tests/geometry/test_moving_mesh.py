"""A posed body refitted frame by frame answers every query as a mesh built afresh for that frame."""

from __future__ import annotations

import numpy as np


def test_a_refitted_body_answers_as_a_fresh_mesh(default_body):
    from datagen.geometry.queries import MovingMesh, mesh_signed_distance, warp_mesh

    rng = np.random.default_rng(0)
    faces = np.asarray(default_body.faces)
    moving = MovingMesh(faces)
    betas = np.zeros((1, 10))
    inside_counts = []
    for k in range(4):  # a few different poses of the same topology
        pose = rng.normal(0.0, 0.3, (1, 24, 3))
        v = np.asarray(default_body.pose(betas, pose)[0])[0].astype(np.float32)
        # points near the surface, on both sides of it
        points = v[rng.choice(len(v), 1500)] + rng.normal(0.0, 0.01, (1500, 3)).astype(np.float32)
        refitted = moving.pose(v).signed_distance(points)
        fresh = mesh_signed_distance(warp_mesh(v, faces), points, 1.0)
        np.testing.assert_allclose(refitted, fresh, atol=1e-6)
        assert moving.inside_count(points) == int((fresh < 0).sum())
        inside_counts.append(moving.inside_count(points))
    # the points straddle the surface: some inside, most not
    assert all(0 < n < 1500 for n in inside_counts), inside_counts
