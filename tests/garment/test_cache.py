"""The on-disk garment cache returns the very garment a fresh build makes."""

from __future__ import annotations

import dataclasses
import json

import numpy as np


def _same(a, b):
    for name in ("vertices", "faces", "uv", "vertex_region", "face_region", "seam_vertex"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.region_names == b.region_names
    assert a.material == b.material
    assert sorted(a.loops) == sorted(b.loops)
    np.testing.assert_array_equal(a.material_frames(), b.material_frames())
    np.testing.assert_array_equal(a.weft_rest_scale(), b.weft_rest_scale())
    # the typed metadata too, but for the wall time of the build
    assert dataclasses.replace(a.metadata, build_seconds=None) == dataclasses.replace(b.metadata, build_seconds=None)


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


def _rewrite_metadata(path, edit):
    with np.load(path, allow_pickle=False) as d:
        arrays = {k: d[k] for k in d.files}
    meta = json.loads(str(arrays["metadata"]))
    edit(meta)
    arrays["metadata"] = np.array(json.dumps(meta))
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


def test_old_cache_entries_load_or_are_rebuilt(default_body, tmp_path, monkeypatch, caplog):
    """An entry written before the typed metadata (the same builder, a plain dict of the same keys)
    reads back; one whose metadata this drape does not know is rebuilt, not a crash."""
    from datagen.garment.cache import cached_garment

    monkeypatch.setenv("DRAPE_CACHE_DIR", str(tmp_path))
    betas = np.zeros(default_body.shape_dim)
    built = cached_garment("skirt", default_body, betas, seed=5)
    path = next((tmp_path / "garments").glob("*.npz"))
    # garment builder 8's plain dict: the keys in its own order, the waistband as a dict
    old = {"type": "skirt", "params": dict(built.metadata.params), "seed": 5, "betas": [0.0] * default_body.shape_dim,
           "target_edge_length": built.metadata.target_edge_length, "expected_boundary_loops": 2,
           "builder_version": built.metadata.builder_version, "build_seconds": 1.5,
           "waistband": dataclasses.asdict(built.metadata.waistband), "vertex_count": built.vertex_count,
           "face_count": len(built.faces), "rest_area_m2": built.metadata.rest_area_m2, "boundary_loops": 2,
           "material": built.material.as_dict()}
    _rewrite_metadata(path, lambda m: (m.clear(), m.update(old)))
    again = cached_garment("skirt", default_body, betas, seed=5)
    _same(built, again)
    assert again.metadata.build_seconds == 1.5  # it came from the file
    _rewrite_metadata(path, lambda m: m.update(colour="red"))
    with caplog.at_level("WARNING"):
        rebuilt = cached_garment("skirt", default_body, betas, seed=5)
    assert "rebuilding" in caplog.text and "colour" in caplog.text
    _same(built, rebuilt)


def test_a_refitted_material_preset_is_a_new_cache_key(default_body, monkeypatch):
    """A cached garment carries its material: when a preset is re-fitted, the garments of the
    types that use it must be built again, not read back with the old material."""
    import datagen.materials as materials
    from datagen.garment.cache import garment_cache_key

    before = garment_cache_key("skirt", 0, default_body, None, None)
    other = garment_cache_key("tshirt", 0, default_body, None, None)
    refit = dict(materials.MATERIALS)
    refit["cotton"] = dataclasses.replace(refit["cotton"], bending=refit["cotton"].bending / 2)
    monkeypatch.setattr(materials, "MATERIALS", refit)
    assert garment_cache_key("skirt", 0, default_body, None, None) != before  # skirts are cotton
    assert garment_cache_key("tshirt", 0, default_body, None, None) == other  # T-shirts are jersey
