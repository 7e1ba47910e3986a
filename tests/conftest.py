"""Shared fixtures: the default body is built (or loaded from drape's cache) once per session."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="session")
def default_body():
    from datagen.body.cache import default_body as _default_body

    return _default_body()


@pytest.fixture(scope="session")
def subdivided_body(default_body):
    return default_body.subdivided()


@pytest.fixture(scope="session")
def small_model():
    """A random SMPL-format model of 300 vertices with non-zero pose blend shapes (fast)."""
    from datagen.body.model import BodyModel
    from datagen.body.skeleton import SMPL_PARENTS

    rng = np.random.default_rng(7)
    V, J = 300, 24
    weights = rng.random((V, J)) ** 4
    weights /= weights.sum(1, keepdims=True)
    reg = rng.random((J, V)) * (rng.random((J, V)) < 0.05)
    reg[:, 0] += 1e-3
    reg /= reg.sum(1, keepdims=True)
    faces = rng.integers(0, V, size=(500, 3))
    return BodyModel(
        v_template=rng.normal(size=(V, 3)) * 0.3,
        shapedirs=rng.normal(size=(V, 3, 10)) * 0.01,
        posedirs=rng.normal(size=(207, V * 3)) * 0.001,
        J_regressor=reg,
        weights=weights,
        parents=np.array(SMPL_PARENTS),
        faces=faces,
        meta={"source": "test"},
    )
