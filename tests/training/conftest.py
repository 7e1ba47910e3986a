"""A micro store shaped like paper-motion for the training tests (the micro store with all three splits,
``train_store``, is in tests/conftest.py)."""

from __future__ import annotations

import pytest

from tests.conftest import MICRO_TRAIN  # noqa: F401 (it and its store, train_store, are in tests/conftest.py: the card tests share them)


MOTION_LIKE = {
    "seed": 0, "frames": 6, "segment_length": 3, "garment_edge_length": 0.07, "fit_attribute": False,
    "split_disjoint": ["motions"],
    "simulation": {"settle_rest": 2, "lead_in": 0.1, "settle_pose": 1, "ramp": 0.1,
                   "solver": {"substeps": 3, "iterations": 3, "detection_interval": 2}},
    "train": {"garments": ["skirt:0"], "bodies": ["regular"], "motions": ["walk:0", "squat:0"]},
    "val": {"garments": ["skirt:0"], "bodies": ["regular"], "motions": ["walk:1"]},
    "test": {"garments": ["skirt:0"], "bodies": ["regular"], "motions": ["walk:2"]},
}
"""A micro store shaped like ``paper-motion``: one skirt on one body in every split, only the motions differ."""


@pytest.fixture(scope="session")
def motion_store(tmp_path_factory):
    from datagen.config import load_config
    from datagen.generate.config import DatasetConfig
    from datagen.generate.run import generate

    out = tmp_path_factory.mktemp("motion-store") / "m.zarr"
    generate(load_config(DatasetConfig, MOTION_LIKE), out)
    return out
