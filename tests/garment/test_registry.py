"""The garment-type registry: codes frozen in the schema, records checked at import, and a new type
changes no other type's garments; the typed garment metadata and its JSON form."""

from __future__ import annotations

import dataclasses
import json
from types import MappingProxyType

import numpy as np
import pytest

import schemas.garment_types as schema
from datagen.errors import InputError
from datagen.garment.metadata import GarmentMetadata, Waistband
from datagen.garment.registry import (
    GARMENT_TYPES,
    GarmentRegistryError,
    GarmentType,
    check_registry,
    garment_type,
    garment_type_names,
)
from datagen.garment.types import garment_params, make_garment


def test_codes_are_the_schemas_and_unique():
    codes = [t.code for t in GARMENT_TYPES.values()]
    assert len(set(codes)) == len(codes)
    assert {n: t.code for n, t in GARMENT_TYPES.items()} == dict(schema.GARMENT_TYPE_CODES)
    # today's codes, which existing stores hold
    assert dict(schema.GARMENT_TYPE_CODES) == {
        "tshirt": 0, "long_sleeve_shirt": 1, "tank_top": 2, "jacket": 3, "coat": 4, "dress": 5, "skirt": 6,
        "flared_skirt": 7, "pants": 8, "shorts": 9}
    names = garment_type_names()
    assert all(names[t.code] == n for n, t in GARMENT_TYPES.items()) and len(names) == len(schema.GARMENT_TYPE_CODES)
    check_registry()
    with pytest.raises(TypeError):
        schema.GARMENT_TYPE_CODES["kimono"] = 10  # read-only
    with pytest.raises(dataclasses.FrozenInstanceError):
        GARMENT_TYPES["tshirt"].code = 3
    with pytest.raises(TypeError):
        GARMENT_TYPES["tshirt"].params["hem"] = None


def test_a_record_without_a_schema_code_or_with_a_taken_one_is_refused():
    kimono = dataclasses.replace(GARMENT_TYPES["tank_top"], name="kimono", code=10)
    with pytest.raises(GarmentRegistryError, match=r"'kimono' \(code 10\) has no code in schemas/garment_types.py "
                                                   r"GARMENT_TYPE_CODES; add 'kimono': 10 there"):
        check_registry({**GARMENT_TYPES, "kimono": kimono})
    taken = dataclasses.replace(kimono, code=2)
    with pytest.raises(GarmentRegistryError, match="garment types 'tank_top' and 'kimono' have the same code 2"):
        check_registry({**GARMENT_TYPES, "kimono": taken}, {**schema.GARMENT_TYPE_CODES, "kimono": 2})
    with pytest.raises(GarmentRegistryError, match="'kimono' has code 2 but .* gives it 10; a type's code never changes"):
        check_registry({"kimono": taken}, {**schema.GARMENT_TYPE_CODES, "kimono": 10})
    with pytest.raises(GarmentRegistryError, match=r"must be 0..10, each once"):
        check_registry(GARMENT_TYPES, {**schema.GARMENT_TYPE_CODES, "kimono": 11})
    with pytest.raises(GarmentRegistryError, match="registered under the name 'cape'"):
        check_registry({"cape": kimono}, {**schema.GARMENT_TYPE_CODES, "kimono": 10})


def test_a_record_whose_pieces_do_not_fit_is_refused():
    tank = GARMENT_TYPES["tank_top"]
    with pytest.raises(GarmentRegistryError, match="need the style parameters sleeve_length, cuff_ease"):
        dataclasses.replace(tank, sleeves=True, side_opening="cuff")
    with pytest.raises(GarmentRegistryError, match="side_opening is 'armhole' but its pieces .* make it 'cuff'"):
        dataclasses.replace(GARMENT_TYPES["tshirt"], side_opening="armhole")
    with pytest.raises(GarmentRegistryError, match="top_opening is 'neck'"):
        dataclasses.replace(GARMENT_TYPES["skirt"], top_opening="neck")
    with pytest.raises(GarmentRegistryError, match="hangs_from is 'hips'; one of shoulders, waist"):
        dataclasses.replace(tank, hangs_from="hips")
    with pytest.raises(GarmentRegistryError, match="material 'leather' is not a preset"):
        dataclasses.replace(tank, material="leather")
    with pytest.raises(GarmentRegistryError, match="sleeve_above_elbow needs sleeves"):
        dataclasses.replace(tank, sleeve_above_elbow=0.09)
    with pytest.raises(GarmentRegistryError, match="a back slit needs a skirt that hangs from the waist"):
        dataclasses.replace(GARMENT_TYPES["pants"], back_slit=True)
    with pytest.raises(GarmentRegistryError, match="need the style parameters slit"):
        dataclasses.replace(GARMENT_TYPES["flared_skirt"], back_slit=True)
    with pytest.raises(InputError, match="unknown garment type 'kimono'; types: tshirt"):
        garment_type("kimono")


@pytest.fixture
def add_type_first(monkeypatch):
    """Inserts a copy of the shorts under a new name and the next unused code FIRST in the registry
    (and its code in the schema's), as a developer adding a type at the top would; undone after."""
    saved = dict(GARMENT_TYPES)

    def insert() -> GarmentType:
        new = dataclasses.replace(GARMENT_TYPES["shorts"], name="culottes", code=len(schema.GARMENT_TYPE_CODES))
        monkeypatch.setattr(schema, "GARMENT_TYPE_CODES", MappingProxyType({**schema.GARMENT_TYPE_CODES,
                                                                           "culottes": new.code}))
        GARMENT_TYPES.clear()
        GARMENT_TYPES.update({"culottes": new, **saved})
        return new

    yield insert
    GARMENT_TYPES.clear()
    GARMENT_TYPES.update(saved)


def test_adding_a_type_changes_no_other_types_garments(default_body, add_type_first):
    others = list(GARMENT_TYPES)
    before = {(k, s): garment_params(k, s) for k in others for s in range(6)}
    shorts = make_garment("shorts", default_body, seed=3)  # the cheapest type to build

    new = add_type_first()
    check_registry()  # the new record and its schema code are accepted
    assert next(iter(GARMENT_TYPES)) == "culottes"
    assert all(list(GARMENT_TYPES).index(k) != GARMENT_TYPES[k].code for k in others)  # every position moved
    assert {(k, s): garment_params(k, s) for k in others for s in range(6)} == before
    again = make_garment("shorts", default_body, seed=3)
    for name in ("vertices", "faces", "uv", "face_uv", "vertex_region", "seam_vertex"):
        assert np.array_equal(getattr(again, name), getattr(shorts, name)), name
    assert again.loops.keys() == shorts.loops.keys() and again.region_names == shorts.region_names
    assert all(np.array_equal(again.loops[n], shorts.loops[n]) for n in shorts.loops)
    assert again.metadata.params == shorts.metadata.params
    # the new type draws its own parameters (its code salts the seed) and names its store code
    assert garment_params("culottes", 3) != garment_params("shorts", 3)
    names = garment_type_names()
    assert names[new.code] == "culottes" and all(names[GARMENT_TYPES[k].code] == k for k in others)


def test_metadata_is_typed_and_round_trips_through_json(default_body):
    g = make_garment("skirt", default_body, seed=2)
    m = g.metadata
    assert isinstance(m, GarmentMetadata) and isinstance(m.waistband, Waistband)
    assert m.type == "skirt" and m.seed == 2 and m.expected_boundary_loops == 2 == m.boundary_loops
    assert m.vertex_count == g.vertex_count and m.material == g.material and len(m.betas) == default_body.shape_dim
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.seed = 3
    d = json.loads(json.dumps(m.to_dict()))
    assert GarmentMetadata.from_dict(d) == m
    with pytest.raises(InputError, match=r"unknown key\(s\) 'colour'; its keys are type, params"):
        GarmentMetadata.from_dict({**d, "colour": "red"})
    with pytest.raises(InputError, match=r"'waistband' has unknown key\(s\) 'elastic'"):
        GarmentMetadata.from_dict({**d, "waistband": {**d["waistband"], "elastic": True}})
    with pytest.raises(InputError, match="seed must be int"):
        GarmentMetadata.from_dict({**d, "seed": "three"})
    # a garment of another origin: nothing but what it has
    bare = GarmentMetadata.from_dict({})
    assert bare.type is None and bare.params == {} and bare.waistband is None and bare.to_dict() == {}
    # the plain dict of older garment files keeps a file garment's origin at the top level
    legacy = GarmentMetadata.from_dict({"type": "file", "source": "a.obj", "units": "cm", "units_guessed": True,
                                        "up_axis": "z", "up_axis_guessed": False, "remesh_edge_length": None})
    assert legacy.origin.units == "cm" and not legacy.origin.up_axis_guessed


def test_npz_without_drape_metadata_still_loads(default_body, tmp_path):
    from datagen.garment.mesh import load_garment

    g = make_garment("shorts", default_body, seed=1)
    path = g.save(tmp_path / "g.npz")
    with np.load(path, allow_pickle=False) as d:
        arrays = {k: d[k] for k in d.files if k != "metadata"}
    with open(tmp_path / "bare.npz", "wb") as fh:
        np.savez(fh, **arrays)
    back = load_garment(tmp_path / "bare.npz")
    assert back.metadata == GarmentMetadata() and np.array_equal(back.vertices, g.vertices)
    np.testing.assert_array_equal(back.weft_rest_scale(), 1.0)
    arrays["metadata"] = np.array(json.dumps({**g.metadata.to_dict(), "colour": "red"}))
    with open(tmp_path / "odd.npz", "wb") as fh:
        np.savez(fh, **arrays)
    with pytest.raises(InputError, match=r"odd.npz: garment metadata has unknown key\(s\) 'colour'"):
        load_garment(tmp_path / "odd.npz")


def test_garments_and_types_pickle(default_body):
    """Scenes travel pickled (the benchmarks' prepared runs, Ray): a garment and a type record come
    back equal, their read-only parameter mappings read-only again."""
    import pickle

    from datagen.garment.types import make_garment

    g = make_garment("shorts", default_body, seed=1)
    back = pickle.loads(pickle.dumps(g))
    assert back.metadata == g.metadata and np.array_equal(back.vertices, g.vertices)
    with pytest.raises(TypeError):
        back.metadata.params["hem"] = 0.0
    t = pickle.loads(pickle.dumps(GARMENT_TYPES["shorts"]))
    assert t == GARMENT_TYPES["shorts"]
    with pytest.raises(TypeError):
        t.params["hem"] = None
