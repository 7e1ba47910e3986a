"""Shared fixtures: the default body is built (or loaded from drape's cache) once per session; a micro store
with all three splits is generated once per session (``train_store``: the training and the dataset card tests)."""

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


# toy solver settings (3 substeps x 6 sweeps, 7 cm edges) for a store in a minute; a detection
# between the sweeps, as the production default of one every 4 sweeps would leave one a substep
MICRO_TRAIN = {
    "seed": 0, "frames": 6, "segment_length": 3, "garment_edge_length": 0.07,
    "simulation": {"settle_rest": 2, "lead_in": 0.1, "settle_pose": 1, "ramp": 0.1,
                   # a toy solve (3 substeps x 6 sweeps, 7 cm edges): its garments are not the data
                   # here. The untangling is off: with 3 sweeps the membrane cannot relax around
                   # its moves, and the T-shirt on seed:1 tore (143 % at frame 11; docs/simulator.md).
                   # 6 sweeps since garment builder 9: at 3 its shorter T-shirt sleeves tore at 7 cm
                   # edges (123 % at frame 3), and so did tshirt:1's at 3 sweeps and tshirt:0's at 6 cm
                   "solver": {"substeps": 3, "iterations": 6, "detection_interval": 2, "untangle_step": 0.0}},
    "train": {"garments": ["tshirt:0", "pants:0"], "bodies": ["regular", "seed:1"], "motions": ["walk:0"]},
    "val": {"garments": ["skirt:1"], "bodies": ["thin"], "motions": ["wave:1"]},
    "test": {"garments": ["tshirt:2"], "bodies": ["fat"], "motions": ["walk:2"]},
}


@pytest.fixture(scope="session")
def train_store(tmp_path_factory):
    """:data:`MICRO_TRAIN` generated (about a minute on 2 cores): the training tests' store and the dataset
    card's (tests/store/test_card.py copies it before writing into it)."""
    from datagen.config import load_config
    from datagen.generate.config import DatasetConfig
    from datagen.generate.run import generate

    out = tmp_path_factory.mktemp("training") / "micro.zarr"
    generate(load_config(DatasetConfig, MICRO_TRAIN), out)
    return out
