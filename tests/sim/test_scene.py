"""``simulate`` (the batched scene runner) records every frame's own positions."""

from __future__ import annotations

import numpy as np

from datagen.sim.scene import RunConfig, SceneArrays, simulate


def test_recorded_frames_are_copies_not_views_of_the_state_buffers():
    """On the CPU warp's ``.numpy()`` is a view of the array: recording it would make every
    frame alias one of the two ping-pong states. A falling cloth must have a lower mean height
    in each recorded frame than in the one before."""
    n = 6
    u = np.linspace(0.0, 0.2, n)
    gx, gz = np.meshgrid(u, u, indexing="ij")
    verts = np.stack([gx.ravel(), np.ones(n * n), gz.ravel()], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, c, b], 1), np.stack([a, d, c], 1)])
    frames = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), (len(faces), 1, 1))
    body = np.array([[0.0, -10.0, 0.0], [0.1, -10.0, 0.0], [0.0, -10.0, 0.1], [0.0, -9.9, 0.0]])  # far below
    body_faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    T = 8
    scene = SceneArrays(garment_vertices=verts, garment_faces=faces, material="cotton", material_frames=frames,
                        weft_scale=np.ones(len(faces)),
                        body_frames=np.repeat(body[None], T, 0), body_faces=body_faces, fps=30.0, lead_frames=0)
    config = RunConfig(settle_rest=1, lead_in=0.0, settle_pose=0, ramp=0.0)
    (result,) = simulate([scene], config, device="cpu")
    heights = result.positions[..., 1].mean(axis=1)
    assert len(heights) >= 5
    assert np.all(np.diff(heights) < -1e-4), heights
