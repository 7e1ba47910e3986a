"""The on-disk garment cache returns the very garment a fresh build makes."""

from __future__ import annotations

import numpy as np


def _same(a, b):
    for name in ("vertices", "faces", "uv", "vertex_region", "face_region", "seam_vertex"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.region_names == b.region_names
    assert a.material == b.material
    assert sorted(a.loops) == sorted(b.loops)
    np.testing.assert_array_equal(a.material_frames(), b.material_frames())


def test_cached_garment_is_the_built_garment(default_body, tmp_path, monkeypatch):
    from datagen.garment.cache import cached_garment, garment_cache_key
    from datagen.garment.types import make_garment

    monkeypatch.setenv("DRAPE_CACHE_DIR", str(tmp_path))
    betas = np.zeros(default_body.shape_dim)
    built = make_garment("shorts", default_body, betas, seed=3)
    first = cached_garment("shorts", default_body, betas, seed=3)  # builds and writes
    files = list((tmp_path / "garments").glob("*.npz"))
    assert len(files) == 1 and not list((tmp_path / "garments").glob(".*tmp*"))
    second = cached_garment("shorts", default_body, betas, seed=3)  # reads
    _same(built, first)
    _same(built, second)
    # the key follows what the build reads
    assert garment_cache_key("shorts", 3, default_body, betas, None) != garment_cache_key("shorts", 4, default_body,
                                                                                        betas, None)
    assert garment_cache_key("shorts", 3, default_body, betas, None) != garment_cache_key(
        "shorts", 3, default_body, betas + 0.1, None)
    # a damaged file is rebuilt, not trusted
    files[0].write_bytes(b"not a garment")
    third = cached_garment("shorts", default_body, betas, seed=3)
    _same(built, third)
