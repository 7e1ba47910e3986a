"""Host-side measures of the simulator (``datagen.sim.metrics``) against their definitions."""

from __future__ import annotations

import numpy as np

from datagen.sim.metrics import principal_strain


def test_principal_strain_is_the_largest_stretch_minus_one():
    """A triangle stretched by 1.1 along one in-plane direction and 0.95 across it, then rotated
    and moved: its largest principal strain is 0.1, whatever its orientation; a mesh at rest has 0."""
    rng = np.random.default_rng(0)
    rest = np.array([[0.0, 0.0, 0.0], [0.02, 0.0, 0.0], [0.007, 0.015, 0.0]])
    faces = np.array([[0, 1, 2]])
    a = np.radians(30.0)
    d = np.array([np.cos(a), np.sin(a), 0.0])
    e = np.array([-np.sin(a), np.cos(a), 0.0])
    stretch = 1.1 * np.outer(d, d) + 0.95 * np.outer(e, e) + np.outer([0, 0, 1.0], [0, 0, 1.0])
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moved = rest @ stretch.T @ q.T + np.array([0.3, -1.0, 2.0])
    assert np.allclose(principal_strain(rest, faces, moved), [0.1], atol=1e-12)
    assert np.allclose(principal_strain(rest, faces, np.stack([rest, moved])), [[0.0], [0.1]], atol=1e-12)
