"""A damaged store never reads as data: a deleted, truncated, zeroed or bit-flipped shard is refused
by every reader (the reader on both backends, a reader in another process, preview, export usd,
info) with the array, the shard and the command that lists every damaged file; nothing is written."""

from __future__ import annotations

import pickle
import shutil
from pathlib import Path

import numpy as np
import pytest

from datagen.cli import main
from datagen.store import open_store, validate
from datagen.store.integrity import DamagedStoreError

DETAIL = "vertex_frames/detail/c/0/0"
"""The one shard of the positions every reader of a sample decodes."""
FAILURE = "samples/failure/c/0"
"""The one shard of a per-sample table every reader (info too) reads first."""


def _delete(f: Path) -> None:
    f.unlink()


def _truncate(f: Path) -> None:
    f.write_bytes(f.read_bytes()[: f.stat().st_size // 2])


def _zero(f: Path) -> None:
    f.write_bytes(bytes(f.stat().st_size))


def _flip(f: Path) -> None:
    """16 bytes inverted in the middle of the file (inside the compressed chunk data)."""
    b = bytearray(f.read_bytes())
    mid = len(b) // 3
    b[mid:mid + 16] = bytes(x ^ 0xFF for x in b[mid:mid + 16])
    f.write_bytes(bytes(b))


DAMAGE = {"deleted": _delete, "truncated": _truncate, "zeroed": _zero, "flipped": _flip}


def damaged_copy(packed: Path, tmp_path: Path, shard: str, kind: str) -> Path:
    copy = tmp_path / f"{kind}.zarr"
    shutil.copytree(packed, copy)
    DAMAGE[kind](copy / shard)
    return copy


def refusal(copy: Path, shard: str) -> str:
    array, key = shard.split("/c/")
    return f"the store is damaged at {array} (shard c/{key}, rows 0 .. "


@pytest.mark.parametrize("backend", ["zarr", "tensorstore"])
@pytest.mark.parametrize("kind", list(DAMAGE))
def test_the_reader_refuses_every_kind_of_damage(packed, tmp_path, kind, backend):
    if backend == "tensorstore":
        pytest.importorskip("tensorstore")
    copy = damaged_copy(packed, tmp_path, DETAIL, kind)
    assert any("vertex_frames/detail" in p and "shard file c/0/0" in p for p in validate(copy, check_values=False))
    store = open_store(copy, backend=backend)
    intact = open_store(packed, backend=backend).frames(0, names=["pose"])["pose"]
    assert np.array_equal(store.frames(0, names=["pose"])["pose"], intact)  # the other arrays still read
    for read in (lambda: store.sample(0), lambda: store.frames(3, 1, names=["detail"]),
                 lambda: store.read("vertex_frames/detail", 0, 5), lambda: store.read("vertex_frames/detail"),
                 lambda: store.array("vertex_frames/detail"), lambda: store.check_files()):
        with pytest.raises(DamagedStoreError) as err:
            read()
        message = str(err.value)
        assert message.startswith(refusal(copy, DETAIL)), message
        assert f"run `drape validate {copy}`" in message


def test_a_reader_in_another_process_checks_again(packed, tmp_path):
    """The check is per process: a reader handed to a DataLoader worker (pickled) checks the shards it
    reads itself, whatever its parent had checked."""
    copy = tmp_path / "copy.zarr"
    shutil.copytree(packed, copy)
    store = open_store(copy)
    before = store.sample(0)["detail"]
    _flip(copy / DETAIL)
    worker = pickle.loads(pickle.dumps(store))
    with pytest.raises(DamagedStoreError, match="damaged at vertex_frames/detail"):
        worker.sample(0)
    shutil.copy(packed / DETAIL, copy / DETAIL)
    assert np.array_equal(pickle.loads(pickle.dumps(store)).sample(0)["detail"], before)


def _cli(capsys, *argv) -> tuple[int, str]:
    capsys.readouterr()
    rc = main(list(argv))
    return rc, capsys.readouterr().err


@pytest.mark.parametrize("kind", list(DAMAGE))
def test_preview_export_and_info_refuse_and_write_nothing(packed, tmp_path, capsys, kind):
    pytest.importorskip("pxr", reason="export usd needs usd-core (pip install 'drape[usd]')")
    copy = damaged_copy(packed, tmp_path, DETAIL, kind)
    out = tmp_path / "out"
    out.mkdir()
    commands = {"preview": ["preview", str(copy), "--sample", "0", "--out", str(out / "f.png")],
                "export one": ["export", "usd", str(copy), "--sample", "0", "--out", str(out / "a.usda")],
                "export all": ["export", "usd", str(copy), "--all", "--out", str(out / "all")]}
    for what, argv in commands.items():
        rc, err = _cli(capsys, *argv)
        assert rc == 1, (what, err)
        assert err.startswith("error: " + refusal(copy, DETAIL)) and err.count("\n") == 1, (what, err)
        assert "Traceback" not in err and list(out.rglob("*")) == [], (what, list(out.rglob("*")))
    # info reads the per-sample tables: damage there is refused like any read
    info_copy = damaged_copy(packed, tmp_path / "info", FAILURE, kind)
    rc, err = _cli(capsys, "info", str(info_copy))
    assert rc == 1 and err.startswith("error: " + refusal(info_copy, FAILURE)), err


def test_info_says_a_shard_it_does_not_read_is_missing_and_exits_1(packed, tmp_path, capsys):
    """info does not read the vertex data, so it does not hash it (validate does); a missing file
    anywhere is cheap to see and it says so, with status 1."""
    copy = damaged_copy(packed, tmp_path, DETAIL, "deleted")
    capsys.readouterr()
    assert main(["info", str(copy)]) == 1
    assert "DAMAGED: 1 problem(s)" in capsys.readouterr().out
    assert main(["info", str(packed)]) == 0
