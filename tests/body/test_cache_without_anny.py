"""A body cache carried to a host without anny (the GPU host of docs/generate.md) is used there."""

from __future__ import annotations

import numpy as np
import pytest

import datagen.body.cache as body_cache
from datagen.body.anny_builder import AnnyBodyConfig
from datagen.body.io import save_body_file
from datagen.errors import InputError


@pytest.fixture
def no_anny(monkeypatch, tmp_path):
    monkeypatch.setenv("DRAPE_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(body_cache, "anny_version", lambda: "unknown")

    def build(config):
        raise RuntimeError("would build with anny")

    monkeypatch.setattr(body_cache, "build_body_from_anny", build)
    return tmp_path


def _put(model, root, key):
    d = root / "body" / f"anny-{key}"
    d.mkdir(parents=True)
    save_body_file(model, d / "body.npz")


def test_the_body_built_elsewhere_for_this_config_is_used(default_body, no_anny):
    config = AnnyBodyConfig()
    _put(default_body, no_anny, config.cache_key("0.6.2"))  # as a host with anny 0.6.2 keyed it
    got = body_cache.default_body(config)
    assert np.array_equal(got.v_template, default_body.v_template)
    assert np.array_equal(got.shapedirs, default_body.shapedirs)
    # another config has no body here: it is built (which needs anny), never swapped for this one
    with pytest.raises(RuntimeError, match="would build"):
        body_cache.default_body(AnnyBodyConfig(seed=1))


def test_two_bodies_from_different_anny_versions_are_refused(default_body, no_anny):
    config = AnnyBodyConfig()
    for version in ("0.6.1", "0.6.2"):
        _put(default_body, no_anny, config.cache_key(version))
    with pytest.raises(InputError, match="2 bodies built from this config by different Anny versions"):
        body_cache.default_body(config)
