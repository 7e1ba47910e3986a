"""The dataset store: writer -> pack -> reader round trip, validation, tensorstore, refusals,
crash safety (SIGKILL mid-staging) and disk errors, on tiny synthetic samples (no simulator)."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.geometry.positions import encode_positions
from datagen.store import StorageError, format_store_info, open_store, store_info, validate
from datagen.store.layout import MARKER, STAGING, TMP_PREFIX
from schemas.dataset import ARRAYS, POSITION_QUANTUM, ROOT_ATTRIBUTES, TABLES, Chunking
from tests.store import stage_loop as sl
from tests.store.conftest import N, build

HELPER = Path(__file__).with_name("stage_loop.py")
REPO = Path(__file__).resolve().parents[2]


def snapshot(path: Path) -> dict[str, str]:
    """Relative path -> content hash of every file under ``path``."""
    out = {}
    for p in sorted(path.rglob("*")):
        if p.is_file():
            out[str(p.relative_to(path))] = hashlib.sha256(p.read_bytes()).hexdigest()
        elif p.is_dir():
            out[str(p.relative_to(path)) + "/"] = ""
    return out


def read_everything(path: Path) -> dict[str, np.ndarray]:
    import zarr

    root = zarr.open_group(str(path), mode="r")
    return {p: root[p][...] for p in ARRAYS}


# --------------------------------------------------------------------------------------- round trip


def same(name: str, got: np.ndarray, value: np.ndarray) -> bool:
    """Equal, or for quantised positions within the stated bound: half a step plus float32 rounding."""
    if got.dtype != value.dtype or got.shape != value.shape:
        return False
    if name in ("detail", "coarse"):
        bound = POSITION_QUANTUM / 2 + 2 * np.spacing(np.float32(np.abs(value).max(initial=0) + 10))
        return bool(np.all(np.abs(got.astype(np.float64) - value) <= bound))
    return np.array_equal(got, value)


@pytest.mark.parametrize("backend", ["zarr", "tensorstore"])
def test_round_trip_equals_inputs(packed, backend):
    store = open_store(packed, backend=backend)
    assert store.backend == backend and store.sample_count == N and store.config == sl.CONFIG
    for i in range(N):
        arrays, scalars = sl.sample(i)
        got = store.sample(i)
        for name, value in arrays.items():
            assert same(name, got[name], value), (i, name)
        for name, value in scalars.items():
            assert got[name] == np.asarray(value, dtype=ARRAYS[f"samples/{name}"].dtype), (i, name)
        if i in sl.FAILED:
            assert store.frame_count(i) == 0 and got["detail"].shape == (0, sl.GARMENT_VERTICES[i % 3], 3)
            continue
        T = store.frame_count(i)
        part = store.frames(i, slice(1, T), names=["detail", "pose"])
        assert same("detail", part["detail"], arrays["detail"][1:]) and np.array_equal(part["pose"], arrays["pose"][1:])
        picked = store.frames(i, [T - 1, 0])
        assert same("coarse", picked["coarse"], arrays["coarse"][[T - 1, 0]])
        assert np.array_equal(store.frames(i, slice(None, None, 2))["label"], arrays["label"][::2])
    # segments: non-overlapping, every non-failed sample with T >= segment_length
    expected = [(i, t0) for i in range(N) if i not in sl.FAILED
                for t0 in range(0, len(sl.sample(i)[0]["pose"]) - sl.SEGMENT_LENGTH + 1, sl.SEGMENT_LENGTH)]
    assert store.segments.tolist() == [list(e) for e in expected]
    for k in (0, len(expected) - 1):
        seg = store.segment(k)
        i, t0 = expected[k]
        assert seg["sample"] == i and seg["first_frame"] == t0
        assert same("coarse", seg["coarse"], sl.sample(i)[0]["coarse"][t0:t0 + sl.SEGMENT_LENGTH])
    by_split = np.concatenate([store.split_segments(s) for s in ("train", "val", "test")])
    assert sorted(by_split) == list(range(len(expected)))
    # splits and iteration
    assert {k: v.tolist() for k, v in store.splits.items()} == {s: list(range(k, N, 3)) for k, s in
                                                                 enumerate(("train", "val", "test"))}
    ok_test = [i for i in range(2, N, 3) if i not in sl.FAILED]
    assert [i for i, _ in store.iter_split("test", include_failed=False)] == ok_test
    # static groups
    static = sl.static_groups()
    for group, (arrays, names) in static.items():
        got = store.group(group)
        for name, value in arrays.items():
            assert got[name].dtype == value.dtype and np.array_equal(got[name], value,
                                                                     equal_nan=value.dtype.kind == "f"), (group, name)
        for key, value in names.items():
            assert list(store.names[key]) == value
    assert np.array_equal(store.body_model()["shapedirs"], static["body"][0]["shapedirs"])
    assert np.array_equal(store.fit_model()["components"], static["fit"][0]["components"])
    assert np.array_equal(store.betas(), static["bodies"][0]["betas"])
    assert store.motions()["frame_count"].tolist() == [50, 60, 70, 80]
    g = static["garments"][0]
    for k in range(len(sl.GARMENT_VERTICES)):
        mesh = store.garment(k)
        v0, v1 = g["vertex_start"][k:k + 2]
        f0, f1 = g["face_start"][k:k + 2]
        assert np.array_equal(mesh["rest_vertices"], g["rest_vertices"][v0:v1])
        assert np.array_equal(mesh["faces"], g["faces"][f0:f1]) and mesh["faces"].max() < v1 - v0
        assert mesh["type"] == g["type"][k] and np.array_equal(mesh["alpha"], g["alpha"][k])
        assert np.array_equal(mesh["built_vertices"], g["built_vertices"][v0:v1]) and mesh["settled"] == g["settled"][k]
        # the sewing pattern: per-corner rest coordinates, panels, stitches and the design record
        s0, s1 = g["stitch_start"][k:k + 2]
        assert np.array_equal(mesh["rest_uv"], g["rest_uv"][f0:f1], equal_nan=True)
        assert np.array_equal(mesh["panel"], g["panel"][v0:v1]) and np.array_equal(mesh["face_panel"],
                                                                                     g["face_panel"][f0:f1])
        assert np.array_equal(mesh["stitches"], g["stitches"][s0:s1])
        if k == sl.PATTERN_GARMENT:
            assert mesh["design"] == sl.design(k) and len(mesh["stitches"]) == 2
            assert (mesh["panel"] >= 0).all() and np.isfinite(mesh["rest_uv"]).all()
        else:  # a shell garment: no pattern, said the documented way
            assert mesh["design"] is None and mesh["stitches"].shape == (0, 2)
            assert (mesh["panel"] == -1).all() and (mesh["face_panel"] == -1).all() and np.isnan(mesh["rest_uv"]).all()
    assert store.names["failure_names"][1] == "nan" and store.names["split_names"] == ("train", "val", "test")
    assert set(ROOT_ATTRIBUTES) <= set(store.attrs) and store.attrs["units"]["vertex_frames/detail"] == "m"


def test_reader_pickles_and_reads_only_needed_chunks(tmp_path, monkeypatch):
    """Small chunks (512 B): reading one frame fetches a few chunks of each array, not whole shards."""
    import pickle

    from zarr.storage import LocalStore

    path = tmp_path / "ds"
    tiny = Chunking(chunk_bytes=512, shard_bytes=8192)
    build(path, chunking={t: tiny for t in TABLES})
    store = pickle.loads(pickle.dumps(open_store(path, backend="zarr")))
    store.index  # noqa: B018 (load the per-sample tables first)
    reads: list[tuple[str, object]] = []
    get = LocalStore.get

    async def counting_get(self, key, prototype=None, byte_range=None):
        reads.append((key, byte_range))
        return await get(self, key, prototype, byte_range)

    monkeypatch.setattr(LocalStore, "get", counting_get)
    arrays, _ = sl.sample(7)
    got = store.frames(7, slice(2, 3), names=["detail"])
    assert same("detail", got["detail"], arrays["detail"][2:3])
    # positions are decoded from their steps and the frame's root joint: those two arrays only
    assert reads and all(k.startswith(("vertex_frames/detail/", "frames/joints/")) for k, _ in reads)
    assert all(r is not None for _, r in reads), "every read is a byte range inside a shard"
    shard_bytes = sum((path / k).stat().st_size for k in {k for k, _ in reads})
    fetched = sum(getattr(r, "length", None) or getattr(r, "suffix", 0) for _, r in reads)
    assert fetched < shard_bytes / 2, (fetched, shard_bytes)


def test_validate_passes_and_pinpoints_corruption(packed, tmp_path):
    import zarr

    assert validate(packed) == []

    def corrupt(name: str, change) -> list[str]:
        """The problems other than the checksum's (which any rewrite of a shard also trips)."""
        copy = tmp_path / name
        shutil.copytree(packed, copy)
        change(zarr.open_group(str(copy), mode="r+", use_consolidated=False))
        return [p for p in validate(copy) if "differs from what pack wrote" not in p]

    def wrong_dtype(root):
        data = root["frames/trans"][...]
        root.create_array("frames/trans", shape=data.shape, dtype="float64", overwrite=True,
                          attributes={"unit": "m"})[...] = data

    problems = corrupt("dtype", wrong_dtype)
    assert problems[0] == "'frames/trans' has dtype float64; the schema says float32", problems
    assert problems[1].startswith("consolidated metadata of 'frames/trans' has data_type float32 but its zarr.json "
                                  "has float64")
    assert len(problems) == 2

    def broken_offset(root):
        off = root["index/frame_start"]
        off[4] = off[3] - 1

    problems = corrupt("offset", broken_offset)
    assert any(p.startswith("'index/frame_start'[4] = ") and "must not decrease" in p for p in problems), problems

    arrays, _ = sl.sample(4)
    V = sl.GARMENT_VERTICES[1]

    def nan(root):
        store = open_store(packed, backend="zarr")
        row = int(store.index["frame_start"][4]) + 1  # sample 4, frame 1
        root["frames/joints"][row, 3, 2] = np.nan

    problems = corrupt("nan", nan)
    assert len(problems) == 1 and "'frames/joints' has 1 non-finite (NaN) value(s)" in problems[0]
    assert "(first: sample 4, frame 1)" in problems[0], problems

    def overlap(root):
        root["samples/split"][4] = 2  # sample 4 uses the val split's garment, body and motion

    problems = corrupt("overlap", overlap)
    assert "splits overlap: garment instance (type, seed) (1, 8) is in val (sample 1) and test (sample 4)" in problems
    assert "splits overlap: body 1 is in val (sample 1) and test (sample 4)" in problems
    assert "splits overlap: motion 1 is in val (sample 1) and test (sample 4)" in problems

    def bad_code(root):
        root["samples/failure"][3] = 9

    problems = corrupt("code", bad_code)
    from schemas.dataset import FAILURE_NAMES

    above = f"'samples/failure' has 1 value(s) above {len(FAILURE_NAMES) - 1}"
    assert any(above in p and "(first: sample 3)" in p for p in problems), problems

    def incomplete(root):
        meta = json.loads((Path(root.store.root) / "zarr.json").read_text())
        meta["attributes"]["complete"] = False
        (Path(root.store.root) / "zarr.json").write_text(json.dumps(meta))

    assert any(p.startswith("store is not marked complete") for p in corrupt("incomplete", incomplete))

    def no_fit(root):
        shutil.rmtree(Path(root.store.root) / "fit" / "mean")

    problems = corrupt("nofit", no_fit)
    assert any(p.startswith("array 'fit/mean' is missing") for p in problems), problems


def test_motion_segments_hold_every_motion_of_a_split_failed_samples_included(packed):
    """Paper 001's generator reads motions, not samples: every (motion, body) pair a split plays, once,
    from motions/pose, whether its samples passed or failed; a passed sample's frames are its motion's."""
    store = open_store(packed)
    mo = sl.motion_frames()
    L, T_m = sl.SEGMENT_LENGTH, sl.MOTION_FRAMES
    for k, split in enumerate(("train", "val", "test")):  # split k plays motion k on body k (stage_loop)
        rows = store.motion_segments(split)
        assert rows.tolist() == [[k, k, t0] for t0 in range(0, T_m - L + 1, L)]
        for m, b, t0 in rows[[0, -1]]:
            seg = store.motion_segment(m, b, t0)
            assert np.array_equal(seg["pose"], mo["pose"][m, t0:t0 + L]) and np.array_equal(
                seg["trans"], mo["trans"][m, t0:t0 + L])
            assert seg["label"].tolist() == [store.motions()["label"][m]] * L and seg["body"] == b
    # sample 5 (val: motion 1) failed, yet motion 1's segments are all there; its passed samples agree
    assert 5 in sl.FAILED and len(store.motion_segments("val")) == T_m // L
    for i in range(N):
        if i not in sl.FAILED:
            f = store.frames(i, names=["pose"])["pose"]
            assert np.array_equal(f, mo["pose"][i % 3, :len(f)])
    with pytest.raises(IndexError, match="outside the store's 4 motions"):
        store.motion_segment(4, 0, 0)
    with pytest.raises(InputError, match="unknown split"):
        store.motion_segments("training")


def test_validate_finds_frames_that_are_not_their_motions(tmp_path):
    """A sample whose recorded poses are not its motion's (motions/pose) is reported by validate."""
    path = tmp_path / "ds"
    writer = sl.open_writer(path, N, durable=False)
    for group, (arrays, names) in sl.static_groups().items():
        writer.stage_static(group, arrays, names)
    for i in writer.missing():
        arrays, scalars = sl.sample(i)
        if i == 4:
            arrays["pose"] = arrays["pose"] + np.float32(0.1)
        writer.stage_sample(i, arrays, scalars)
    assert writer.pack()
    problems = validate(path)
    assert problems == ["sample 4: frames/pose differs from motions/pose[1] (its motion's recorded frames); the "
                        "motion generator and the regressor would read different poses"]


@pytest.mark.parametrize("version, why", [(3, "derives on read"), (4, "poses of passed samples only"),
                                          (5, "builder's construction as the garment's rest shape")])
def test_an_older_schema_is_refused_with_how_to_make_it_again(packed, tmp_path, version, why):
    """A schema-3 store (float positions and derived arrays stored) and a schema-4 store (no motion
    tables of poses) are refused by the reader, validate and info, each saying why and the command
    that makes it again; the config is still printable."""
    import zarr

    old = tmp_path / f"v{version}"
    shutil.copytree(packed, old)
    meta = json.loads((old / "zarr.json").read_text())
    meta["attributes"]["schema_version"] = version
    (old / "zarr.json").write_text(json.dumps(meta))
    with pytest.raises(InputError) as exc:
        open_store(old)
    message = str(exc.value)
    assert f"has schema version {version}; this drape reads version 6" in message and why in message
    assert f"drape info {old} --config > config.yaml && drape generate config.yaml --out NEW" in message
    assert validate(old) == [message]
    info = store_info(old)
    assert info["outdated"] == message and "splits" not in info
    assert message in format_store_info(info)
    assert zarr.open_group(str(old), mode="r").attrs["config"] == sl.CONFIG


def test_validate_finds_every_kind_of_damage_to_the_files(packed, tmp_path):
    """A deleted, truncated or bit-flipped shard, and a wrong shape in an array's metadata: each is
    reported with the array, the shard and its rows, and never as a traceback."""
    assert validate(packed) == [] and validate(packed, quick=True) == []
    attrs = json.loads((packed / "zarr.json").read_text())["attributes"]
    assert set(attrs["checksums"]) == set(ARRAYS) and attrs["checksums"]["vertex_frames/detail"]

    def damaged(name: str, change) -> list[str]:
        copy = tmp_path / name
        shutil.copytree(packed, copy)
        change(copy)
        return validate(copy)

    shard = "vertex_frames/coarse/c/0/0"
    problems = damaged("deleted", lambda d: (d / shard).unlink())
    assert any("'vertex_frames/coarse': shard file c/0/0 (rows 0 .. " in p and "is missing" in p for p in problems)
    assert all("Traceback" not in p for p in problems)

    def truncate(d: Path):
        f = d / shard
        f.write_bytes(f.read_bytes()[:-40])

    problems = damaged("truncated", truncate)
    assert any("'vertex_frames/coarse': shard file c/0/0" in p and "differs from what pack wrote" in p
               for p in problems), problems

    def flip(d: Path):
        f = d / "frames/pose/c/0/0/0"
        b = bytearray(f.read_bytes())
        b[len(b) // 2] ^= 0x10
        f.write_bytes(bytes(b))

    problems = damaged("flipped", flip)
    assert any("'frames/pose': shard file c/0/0/0" in p and "differs" in p for p in problems), problems
    assert validate(tmp_path / "flipped", quick=True) == []  # quick: structure only, as documented

    def reshape(d: Path):
        m = json.loads((d / "frames/trans/zarr.json").read_text())
        m["shape"][0] += 1
        (d / "frames/trans/zarr.json").write_text(json.dumps(m))

    problems = damaged("shape", reshape)
    assert any("consolidated metadata of 'frames/trans' has shape" in p for p in problems), problems
    # deleted with --quick too: presence is structure; `drape info` says so as well
    assert any("is missing" in p for p in validate(tmp_path / "deleted", quick=True))
    assert "DAMAGED: 1 problem(s)" in format_store_info(store_info(tmp_path / "deleted"))
    assert "DAMAGED" not in format_store_info(store_info(packed))


def test_tensorstore_reads_every_array(packed):
    ts = pytest.importorskip("tensorstore")
    expected = read_everything(packed)
    for path, spec in ARRAYS.items():
        arr = ts.open({"driver": "zarr3", "kvstore": {"driver": "file", "path": str(packed / path)}}).result()
        data = arr.read().result()
        assert data.dtype == np.dtype(spec.dtype) and np.array_equal(data, expected[path],
                                                                     equal_nan=data.dtype.kind == "f"), path


def test_zarr_reads_the_pattern_arrays_by_the_documented_layout(packed):
    """Without drape: zarr-python opens the garments group and finds a garment's corner coordinates,
    stitches and design record through the offsets docs/store.md describes."""
    import zarr

    root = zarr.open_group(str(packed), mode="r")
    gs = root["garments"]
    g = sl.PATTERN_GARMENT
    f0, f1 = gs["face_start"][g:g + 2]
    s0, s1 = gs["stitch_start"][g:g + 2]
    d0, d1 = gs["design_start"][g:g + 2]
    static = sl.static_groups()["garments"][0]
    assert np.array_equal(gs["rest_uv"][f0:f1], static["rest_uv"][f0:f1])
    assert gs["rest_uv"].attrs["unit"] == "m" and gs["rest_uv"].shape[1:] == (3, 2)
    assert gs["stitches"][s0:s1].tolist() == static["stitches"][s0:s1].tolist()
    assert json.loads(bytes(gs["design"][d0:d1]).decode("utf-8")) == sl.design(g)
    assert gs["design_start"][0] == 0 and gs["design_start"][1] == 0  # instance 0 is a shell: no design bytes


def test_validate_finds_a_shell_with_pattern_data_and_foreign_stitches(tmp_path):
    """Staging refuses a garments group whose shell garment has corner coordinates, or whose
    stitches leave their instance."""
    from datagen.store import StoreWriter

    arrays, names = sl.static_groups()["garments"]
    writer = StoreWriter.open(tmp_path / "s", config=sl.CONFIG, seed=sl.SEED, sample_count=N, segment_length=2)
    bad = dict(arrays, rest_uv=np.nan_to_num(arrays["rest_uv"]))
    with pytest.raises(InputError, match="'rest_uv' must be NaN on the rows of shell garments"):
        writer.stage_static("garments", bad, names=names)
    st = arrays["stitches"].copy()
    st[0, 1] = 99
    with pytest.raises(InputError, match="'stitches' of instance 1 has vertex 99"):
        writer.stage_static("garments", dict(arrays, stitches=st), names=names)
    panel = arrays["panel"].copy()
    panel[0] = 0
    with pytest.raises(InputError, match="instance 0 is neither a pattern garment"):
        writer.stage_static("garments", dict(arrays, panel=panel), names=names)


def test_info_summarises_splits_sizes_failures(packed, tmp_path):
    info = store_info(packed)
    assert info["complete"] and info["totals"]["samples"] == N and info["totals"]["failed"] == 1
    assert info["splits"]["test"]["failed"] == 1 and info["splits"]["train"]["garment_instances"] == 1
    assert [(r["name"], r["count"]) for r in info["failures"]] == [("ok", N - 1), ("nan", 1)]
    assert info["sizes"]["vertex_frames"]["on_disk"] > 0
    text = format_store_info(info)
    assert "train" in text and "nan" in text and "vertex_frames" in text
    # the garments: types (0 tshirt, 1 skirt, 2 tshirt), instance 1 a sewing pattern, instance 2 not settled;
    # every template lies 2 cm below its construction (stage_loop's built_vertices = rest_vertices + 0.02)
    g = info["garments"]
    assert (g["instances"], g["pattern"], g["shell"], g["settled"]) == (3, 1, 2, 2)
    assert g["types"]["tshirt"]["instances"] == 2 and g["types"]["tshirt"]["settled"] == 1
    assert g["types"]["skirt"]["pattern"] and not g["types"]["tshirt"]["pattern"]
    assert g["types"]["skirt"]["template_dy_mm"] == pytest.approx(-20.0, abs=1e-3)
    assert g["types"]["skirt"]["template_distance_mm"] == pytest.approx(20.0 * 3 ** 0.5, abs=1e-3)
    assert "garments: 3 instances (2 shell, 1 sewing pattern), 2 settled at rest" in text
    assert "vertical -20.0 mm" in text
    writer = sl.open_writer(tmp_path / "partial", N, durable=False)
    for i in range(3, 7):
        writer.stage_sample(i, *sl.sample(i))
    partial = store_info(tmp_path / "partial")
    assert not partial["complete"] and partial["staged"] == 4 and partial["missing"] == N - 4
    assert "NOT PACKED" in format_store_info(partial)


def test_info_plots_write_one_png_per_view_of_the_store(packed, tmp_path, capsys):
    pytest.importorskip("matplotlib", reason="plots need matplotlib (pip install 'drape[render]')")
    from PIL import Image

    from datagen.cli import main
    from datagen.export.plots import plot_store_info
    from datagen.export.plots import PLOT_FILES

    written = plot_store_info(packed, tmp_path / "plots" / "nested")
    assert [p.name for p in written] == list(PLOT_FILES)
    assert sorted(p.name for p in (tmp_path / "plots" / "nested").iterdir()) == sorted(PLOT_FILES)
    for p in written:
        with Image.open(p) as im:
            assert im.format == "PNG" and im.size[0] >= 400 and im.size[1] >= 250
            pixels = np.asarray(im.convert("RGB"))
        assert (pixels.std(axis=(0, 1)) > 5).any()  # not a blank page
    assert main(["info", str(packed), "--plots", str(tmp_path / "cli")]) == 0
    assert f"wrote {len(PLOT_FILES)} plots" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "cli").iterdir()) == sorted(PLOT_FILES)
    writer = sl.open_writer(tmp_path / "partial", N, durable=False)
    writer.stage_sample(0, *sl.sample(0))
    with pytest.raises(InputError, match="not complete"):
        plot_store_info(tmp_path / "partial", tmp_path / "p2")
    (tmp_path / "afile").write_text("x")
    with pytest.raises(InputError, match="not a directory"):
        plot_store_info(packed, tmp_path / "afile")


# ------------------------------------------------------------------------------------ refusals


def test_config_change_and_foreign_directory_are_refused(tmp_path):
    path = tmp_path / "ds"
    writer = sl.open_writer(path, N, durable=False)
    writer.stage_sample(0, *sl.sample(0))
    before = snapshot(path)
    changed = json.loads(json.dumps(sl.CONFIG))
    changed["sim"]["substeps"] = 10
    changed["sim"]["extra"] = True
    from datagen.store import StoreWriter

    with pytest.raises(InputError) as exc:
        StoreWriter.open(path, config=changed, seed=sl.SEED + 1, sample_count=N, segment_length=sl.SEGMENT_LENGTH)
    msg = str(exc.value)
    assert "config.sim.substeps (stored 8, given 10)" in msg and "config.sim.extra (not stored, given true)" in msg
    assert f"seed (stored {sl.SEED}, given {sl.SEED + 1})" in msg and "Nothing was changed" in msg
    with pytest.raises(InputError, match=r"sample_count \(stored 12, given 13\)"):
        sl.open_writer(path, N + 1)
    # the same settings from other code: a store never mixes samples of two simulator versions
    with pytest.raises(InputError) as exc:
        StoreWriter.open(path, config=sl.CONFIG, seed=sl.SEED, sample_count=N, segment_length=sl.SEGMENT_LENGTH,
                         code_version="0123456789abcdef")
    assert 'code_version (stored "", given "0123456789abcdef")' in str(exc.value)
    assert "finish it with the installation that started it" in str(exc.value)
    assert snapshot(path) == before
    foreign = tmp_path / "photos"
    foreign.mkdir()
    (foreign / "cat.jpg").write_bytes(b"meow")
    with pytest.raises(InputError, match="non-empty directory that is not a drape store"):
        sl.open_writer(foreign, N)
    assert [p.name for p in foreign.iterdir()] == ["cat.jpg"]
    with pytest.raises(InputError, match="is a file"):
        sl.open_writer(foreign / "cat.jpg", N)


def test_stage_sample_rejects_what_the_schema_does_not_allow(tmp_path):
    writer = sl.open_writer(tmp_path / "ds", N, durable=False)
    arrays, scalars = sl.sample(0)

    def refused(arrays=arrays, scalars=scalars) -> str:
        with pytest.raises(InputError) as exc:
            writer.stage_sample(0, arrays, scalars)
        return str(exc.value)

    ints = np.zeros((2, 7, 3), int)
    assert "'detail' has dtype int64; give float positions in metres" in refused({**arrays, "detail": ints})
    assert "'coarse' has V = 6 (axis 1, size 6) but 'detail' gives V = 7" in refused(
        {**arrays, "coarse": arrays["coarse"][:, :6]})
    nan = arrays["detail"].copy()
    nan[1, 2, 0] = np.nan
    assert "'detail' has 1 non-finite (NaN) value(s) at [(1, 2, 0)]" in refused({**arrays, "detail": nan})
    assert "missing array(s) ['trans']" in refused({k: v for k, v in arrays.items() if k != "trans"})
    assert "unknown array(s) ['colour']" in refused({**arrays, "colour": arrays["trans"]})
    assert "'split' has 1 value(s) above 2" in refused(scalars={**scalars, "split": 3})
    failed = {**scalars, "failure": 1, "failure_frame": 1}
    assert "failed (failure = 1) but has 2 recorded frames" in refused(scalars=failed)
    assert "index 12 is not an integer in 0 .. 11" in str(pytest.raises(InputError, writer.stage_sample, N, arrays,
                                                                         scalars).value)
    assert writer.missing() == list(range(N)) and not list((tmp_path / "ds" / STAGING).iterdir())
    with pytest.raises(InputError, match="give names"):
        writer.stage_static("motions", sl.static_groups()["motions"][0], {})


def test_second_pack_and_generation_of_a_finished_store_do_nothing(packed):
    before = snapshot(packed)
    writer = sl.open_writer(packed, N)
    assert writer.is_complete and writer.missing() == [] and writer.has_sample(3)
    assert writer.stage_sample(3, *sl.sample(3)) is False
    assert writer.stage_static("fit", *sl.static_groups()["fit"]) is False
    sl.stage_all(writer)
    assert writer.pack() is False
    assert snapshot(packed) == before


def test_pack_refuses_missing_samples_and_rebuilds_after_interruption(tmp_path, monkeypatch):
    path = tmp_path / "ds"
    writer = sl.open_writer(path, N, durable=False)
    for group, (arrays, names) in sl.static_groups().items():
        writer.stage_static(group, arrays, names)
    for i in range(N):
        if i not in (4, 9):
            writer.stage_sample(i, *sl.sample(i))
    with pytest.raises(InputError, match=r"2 of 12 samples are not staged \(4, 9\)"):
        writer.pack()
    for i in (4, 9):
        writer.stage_sample(i, *sl.sample(i))
    # a pack that dies half way (here: after the first sample table) leaves a store that is not complete
    import datagen.store.pack as w

    real = w.Packer._write
    calls = []

    def dying(self, root, spec, shape, blocks):
        calls.append(spec.path)
        if spec.path == "frames/pose":
            raise KeyboardInterrupt
        return real(self, root, spec, shape, blocks)

    monkeypatch.setattr(w.Packer, "_write", dying)
    with pytest.raises(KeyboardInterrupt):
        writer.pack()
    monkeypatch.setattr(w.Packer, "_write", real)
    assert not writer.is_complete and (path / STAGING).is_dir() and (path / "vertex_frames").is_dir()
    with pytest.raises(InputError, match="not complete"):
        open_store(path)
    assert writer.pack() is True and not (path / STAGING).exists()
    assert validate(path) == []
    reference = tmp_path / "reference"
    build(reference)
    a, b = read_everything(path), read_everything(reference)
    assert all(np.array_equal(a[p], b[p], equal_nan=a[p].dtype.kind == "f") for p in ARRAYS)


# --------------------------------------------------------------------------------- crash safety


def _run_helper(store: Path, *extra: str, kill_after: float | None = None) -> str:
    """Run the staging loop; with ``kill_after``, SIGKILL it that long after it is ready."""
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen([sys.executable, str(HELPER), str(store), "--samples", str(N), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    if kill_after is None:
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err
        return out
    line = proc.stdout.readline()
    assert line.strip() == "ready", proc.stderr.read()
    time.sleep(kill_after)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    proc.stdout.close()
    proc.stderr.close()
    return "killed" if proc.returncode == -signal.SIGKILL else "finished"


def test_killed_staging_resumes_to_the_same_store(tmp_path):
    store = tmp_path / "ds"
    rng = random.Random(3)
    outcomes, staged_counts, partial_seen = [], [], 0
    for _ in range(5):
        outcomes.append(_run_helper(store, "--vertices", "1000", "--pause", "0.002", kill_after=rng.uniform(0.05, 0.6)))
        staging = store / STAGING
        partial_seen += sum(p.name.startswith(TMP_PREFIX) for p in staging.iterdir()) if staging.exists() else 0
        writer = sl.open_writer(store, N)
        staged = [i for i in range(N) if writer.has_sample(i)]
        staged_counts.append(len(staged))
        for i in staged:  # whatever counts as staged is whole and exactly the sample
            arrays, _ = sl.sample(i, tuple(1000 + k for k in sl.GARMENT_VERTICES))
            manifest = json.loads((staging / f"sample-{i:09d}" / MARKER).read_text())
            assert set(manifest["arrays"]) == set(arrays)
            for name, value in arrays.items():
                if name in ("detail", "coarse"):  # staged as the store keeps them: steps from the root joint
                    value = encode_positions(value, arrays["joints"][:, 0], POSITION_QUANTUM)
                assert np.array_equal(np.load(staging / f"sample-{i:09d}" / f"{name}.npy"), value), (i, name)
    assert "killed" in outcomes, outcomes
    assert staged_counts == sorted(staged_counts)
    assert _run_helper(store, "--vertices", "1000").strip().endswith("done")
    writer = sl.open_writer(store, N)
    assert writer.missing() == [] and writer.pack()
    reference = tmp_path / "reference"
    ref = sl.open_writer(reference, N, durable=False)
    sl.stage_all(ref, garment_vertices=tuple(1000 + k for k in sl.GARMENT_VERTICES))
    ref.pack()
    assert validate(store) == []
    a, b = read_everything(store), read_everything(reference)
    for p in ARRAYS:
        assert a[p].shape == b[p].shape and np.array_equal(a[p], b[p], equal_nan=a[p].dtype.kind == "f"), p
    assert not (store / STAGING).exists()
    print(f"kills: {outcomes}, staged after each: {staged_counts}, half-written temporaries left: {partial_seen}")


def test_two_processes_staging_one_store_give_the_same_store(tmp_path, packed):
    """Two processes (two GPUs' Ray tasks, say) stage the same samples into one store at once: each
    writes under its own temporary names, a sample staged by both is kept once, and the packed store
    equals the one a single process makes."""
    store = tmp_path / "ds"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    procs = [subprocess.Popen([sys.executable, str(HELPER), str(store), "--samples", str(N), "--pause", "0.001"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env) for _ in range(2)]
    for proc in procs:
        out, err = proc.communicate(timeout=120)
        assert proc.returncode == 0 and out.strip().endswith("done"), err
    staging = store / STAGING
    assert not [p.name for p in staging.iterdir() if p.name.startswith(TMP_PREFIX)]
    assert sorted(p.name for p in staging.iterdir() if p.name.startswith("sample-")) == \
        [f"sample-{i:09d}" for i in range(N)]
    writer = sl.open_writer(store, N)
    assert writer.missing() == [] and writer.pack()
    assert validate(store) == []
    a, b = read_everything(store), read_everything(packed)
    for p in ARRAYS:
        assert a[p].shape == b[p].shape and np.array_equal(a[p], b[p], equal_nan=a[p].dtype.kind == "f"), p


# ----------------------------------------------------------------------------------- disk errors


_UNWRITABLE_CHECK = r"""
import sys
sys.path.insert(0, {repo!r})
from datagen.store import StorageError
from tests.store import stage_loop as sl
from tests.store.conftest import N, build
try:
    sl.open_writer({new!r}, 12)
except StorageError as exc:
    print("CREATE:", exc)
w = sl.open_writer({existing!r}, 12)
try:
    w.stage_sample(5, *sl.sample(5))
except StorageError as exc:
    print("STAGE:", exc)
"""


def test_unwritable_directory_gives_a_clear_error(tmp_path):
    """Read-only directories (mode 555). Root ignores permission bits, so as root the check runs
    without the capabilities that let it (setpriv drops CAP_DAC_OVERRIDE)."""
    prefix: list[str] = []
    if os.geteuid() == 0:
        if not shutil.which("setpriv"):
            pytest.skip("running as root and setpriv (util-linux) is missing: cannot make a directory unwritable")
        caps = "-dac_override,-dac_read_search"
        prefix = ["setpriv", f"--inh-caps={caps}", f"--bounding-set={caps}"]
    existing = tmp_path / "ds"
    writer = sl.open_writer(existing, N, durable=False)
    writer.stage_sample(0, *sl.sample(0))
    locked = tmp_path / "locked"
    locked.mkdir()
    try:
        for d in (locked, existing, existing / STAGING):
            os.chmod(d, 0o555)
        before = snapshot(existing)
        code = _UNWRITABLE_CHECK.format(repo=str(REPO), new=str(locked / "new-store"), existing=str(existing))
        out = subprocess.run([*prefix, sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        create = next(line for line in out.stdout.splitlines() if line.startswith("CREATE:"))
        stage = next(line for line in out.stdout.splitlines() if line.startswith("STAGE:"))
        assert "could not create the store" in create and "permission denied" in create
        assert "make the directory writable" in create and "Nothing was written" in create
        assert "could not stage sample-000000005" in stage and "permission denied" in stage
        assert "everything staged before is intact" in stage
        assert not (locked / "new-store").exists() and snapshot(existing) == before
    finally:
        for d in (locked, existing, existing / STAGING):
            os.chmod(d, 0o755)


def test_full_disk_gives_a_clear_error_and_keeps_what_was_stored(tmp_path, monkeypatch):
    import datagen.store.writer as w

    path = tmp_path / "ds"
    writer = sl.open_writer(path, N, durable=False)
    sl.stage_all(writer)
    shutil.rmtree(path / STAGING / "sample-000000007")
    before = snapshot(path)
    real_save = w._save_npy
    calls = {"n": 0}

    def filling_save(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 4:
            raise OSError(errno.ENOSPC, "No space left on device", str(args[0]))
        return real_save(*args, **kwargs)

    monkeypatch.setattr(w, "_save_npy", filling_save)
    with pytest.raises(StorageError) as exc:
        writer.stage_sample(7, *sl.sample(7))
    assert "could not stage sample-000000007" in str(exc.value) and "the disk is full" in str(exc.value)
    assert "free space" in str(exc.value) and exc.value.errno == errno.ENOSPC
    assert "MiB free now" in str(exc.value) and "resumes from what is already staged" in str(exc.value)
    assert snapshot(path) == before and writer.missing() == [7]
    monkeypatch.setattr(w, "_save_npy", real_save)
    assert writer.stage_sample(7, *sl.sample(7))

    from zarr.storage import LocalStore

    async def full(self, key, value, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", key)

    monkeypatch.setattr(LocalStore, "set", full)
    with pytest.raises(StorageError, match="could not pack the store .* the disk is full.*staging area is intact"):
        writer.pack()
    monkeypatch.undo()
    assert not writer.is_complete and writer.missing() == []
    assert writer.pack() and validate(path) == []


def test_reading_a_store_loads_the_reader_alone():
    """A trainer's DataLoader workers import the reader on every worker: ``from datagen.store import
    open_store`` must not bring in the writer (``fcntl``), the validator or the summary."""
    import subprocess
    import sys

    code = ("import sys; from datagen.store import open_store, DatasetStore; "
            "print(sorted(m for m in sys.modules if m.startswith('datagen') or m in ('fcntl', 'torch')))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "datagen.store.reader" in loaded
    for heavy in ("datagen.store.writer", "datagen.store.checks", "datagen.store.pack", "datagen.store.validation",
                  "datagen.store.info", "'fcntl'", "'torch'", "datagen.features",
                  "datagen.sim",
                  "datagen.garment", "datagen.body"):
        assert heavy not in loaded, (heavy, loaded)
