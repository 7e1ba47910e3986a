"""The Croissant description of a store (``croissant.json``, JSON-LD, Croissant 1.0:
https://docs.mlcommons.org/croissant/docs/croissant-spec.html): the dataset's name, description,
licence and version, its files (the store's root ``zarr.json``, with its sha256, and the per-sample
table's Parquet files) and one record set, ``samples``, whose fields are the per-sample table's
scalar columns. Dataset tools that read Croissant (``mlcroissant``, the Hugging Face Hub, Kaggle)
find the data through it; ``tests/store/test_card.py`` checks it with mlcroissant's validator.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pyarrow as pa

CONTEXT: dict[str, Any] = {
    "@language": "en", "@vocab": "https://schema.org/", "citeAs": "cr:citeAs", "column": "cr:column",
    "conformsTo": "dct:conformsTo", "cr": "http://mlcommons.org/croissant/", "rai": "http://mlcommons.org/croissant/RAI/",
    "data": {"@id": "cr:data", "@type": "@json"}, "dataType": {"@id": "cr:dataType", "@type": "@vocab"},
    "dct": "http://purl.org/dc/terms/", "equivalentProperty": "cr:equivalentProperty",
    "examples": {"@id": "cr:examples", "@type": "@json"}, "extract": "cr:extract", "field": "cr:field",
    "fileProperty": "cr:fileProperty", "fileObject": "cr:fileObject", "fileSet": "cr:fileSet", "format": "cr:format",
    "includes": "cr:includes", "isLiveDataset": "cr:isLiveDataset", "jsonPath": "cr:jsonPath", "key": "cr:key",
    "md5": "cr:md5", "parentField": "cr:parentField", "path": "cr:path", "recordSet": "cr:recordSet",
    "references": "cr:references", "regex": "cr:regex", "repeated": "cr:repeated", "replace": "cr:replace",
    "samplingRate": "cr:samplingRate", "sc": "https://schema.org/", "separator": "cr:separator", "source": "cr:source",
    "subField": "cr:subField", "transform": "cr:transform",
}
"""The JSON-LD context of Croissant 1.0 (as mlcroissant writes it)."""

LICENSE_URL = "https://www.apache.org/licenses/LICENSE-2.0"


def _data_type(t) -> str | None:
    import pyarrow as pa

    if pa.types.is_boolean(t):
        return "sc:Boolean"
    if pa.types.is_integer(t):
        return "sc:Integer"
    if pa.types.is_floating(t):
        return "sc:Float"
    if pa.types.is_string(t) or pa.types.is_large_string(t):
        return "sc:Text"
    return None  # lists (β) are left to the Parquet file


def croissant(facts: dict[str, Any], table: pa.Table, licences: tuple[tuple[str, str], ...]) -> dict[str, Any]:
    """The Croissant JSON-LD of a store from its card's ``facts`` (:func:`datagen.store.card.card_facts`),
    its per-sample ``table`` and the (part, licence) pairs of the card (FileObject digests are added
    when the files are written)."""
    from datagen.store.samples_table import COLUMNS, TABLE_DIR

    name = facts["name"]
    fields = []
    for f in table.schema:
        dtype = _data_type(f.type)
        if dtype is None:
            continue
        unit, doc = COLUMNS[f.name]
        fields.append({"@type": "cr:Field", "@id": f"samples/{f.name}", "name": f.name,
                       "description": f"{doc} ({unit})", "dataType": dtype,
                       "source": {"fileSet": {"@id": "sample-table"}, "extract": {"column": f.name}}})
    return {
        "@context": CONTEXT, "@type": "sc:Dataset", "name": name,
        "description": (f"drape garment animation dataset: {facts['samples']} simulated scenes (a garment on a body "
                        f"doing a motion; {facts['passed']} passed the simulator's gates), {facts['totals']['frames']} "
                        "garment-frames, stored as a zarr v3 store (schema version "
                        f"{facts['schema_version']}; README.md lists every array). Licences: "
                        + "; ".join(f"{part}: {text}" for part, text in licences)),
        "conformsTo": "http://mlcommons.org/croissant/1.0",
        "citeAs": f"drape {facts['drape_version']}, dataset {name} (seed {facts['seed']})",
        "license": LICENSE_URL, "version": "1.0.0",
        **({"datePublished": facts["provenance"]["packed_at"][:10]} if facts["provenance"].get("packed_at") else {}),
        "distribution": [
            {"@type": "cr:FileObject", "@id": "zarr-root", "name": "zarr.json",
             "description": "the zarr v3 store's root metadata: root attributes (config, code names, provenance) and "
                            "the consolidated metadata of every array",
             "contentUrl": "zarr.json", "encodingFormat": "application/json"},
            {"@type": "cr:FileSet", "@id": "sample-table", "name": "sample-table",
             "description": "the per-sample table, one Parquet file per split", "encodingFormat": "application/x-parquet",
             "includes": f"{TABLE_DIR}/*.parquet"},
        ],
        "recordSet": [{"@type": "cr:RecordSet", "@id": "samples", "name": "samples",
                       "description": "one record per sample (simulated scene)", "key": {"@id": "samples/sample"},
                       "field": fields}],
    }
