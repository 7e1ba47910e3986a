"""A corpus of bad inputs to every command, as a new user makes them: each gets one line that says
what is wrong and what to do (``error: ...``, exit status 2; a store that fails validation gets its
report and exit status 1), never a traceback, and leaves nothing half written.

The commands run in this process (``datagen.cli.main``), so an exception that escapes is a test
failure with its traceback. Inputs are made once per module: BVH files (a skeleton in metres
without its left arm below the shoulder, one without a left leg, one that is not BVH), garbage
``.npz`` files, a config with each kind of mistake, and a small synthetic store (complete, and one
interrupted before pack).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from tests.generate.test_generate import MICRO
from tests.motion.test_bvh import cmu_skeleton, write_bvh_text
from tests.store import stage_loop as sl


def _bvh(path: Path, drop: tuple[str, ...] = (), scale: float = 1.0) -> Path:
    joints = [j for j in cmu_skeleton() if not any(j[0].startswith(d) for d in drop)]
    names = {j[0] for j in joints}
    joints = [j for j in joints if j[1] is None or j[1] in names]
    T = 4
    rotations = {name: np.zeros((T, 3)) for name, *_ in joints}
    positions = np.stack([np.linspace(0, 1, T), np.full(T, 17.0), np.zeros(T)], axis=1)
    write_bvh_text(path, joints, rotations, positions, scale=scale)
    return path


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad")
    # CMU units are 0.0254/0.45 m: scaled so that the file is in metres (about 1.6 m tall)
    metres = 0.0254 / 0.45
    _bvh(d / "no_left_arm.bvh", drop=("LeftForeArm", "LeftHand", "LeftFingerBase", "LThumb", "LeftHandIndex1"),
         scale=metres)
    _bvh(d / "no_left_leg.bvh", drop=("LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase"), scale=metres)
    _bvh(d / "good.bvh", scale=metres)
    (d / "garbage.bvh").write_text("this is not a BVH file\n")
    (d / "garbage.npz").write_bytes(b"PK\x03\x04 definitely not a zip archive")
    np.savez(d / "wrong_pose.npz", something=np.zeros(3))
    (d / "configs").mkdir()
    for name, change in {
        "negative_seed": {"train": {**MICRO["train"], "garments": ["tshirt:-1", "pants:0"]}},
        "huge_frames": {"frames": 100000},
        "one_pair": {"train": {**MICRO["train"], "bodies": ["regular"], "garments": ["tshirt:0"]}},
        "unknown_key": {"framez": 6},
        "bad_motion_seed": {"train": {**MICRO["train"], "motions": ["walk:-3"]}},
        "zero_batch": {"simulation": {**MICRO["simulation"], "batch_size": 0}},
        "negative_dataset_seed": {"seed": -1},
    }.items():
        (d / "configs" / f"{name}.json").write_text(json.dumps({**MICRO, **change}))
    (d / "configs" / "micro.json").write_text(json.dumps(MICRO))
    (d / "configs" / "broken.yaml").write_text("frames: [1, 2\n")
    (d / "configs" / "duplicate.yaml").write_text("frames: 6\nseed: 0\nframes: 8\n")
    (d / "configs" / "duplicate.json").write_text('{"frames": 6, "frames": 8}')
    (d / "configs" / "latin1.yaml").write_bytes("name: café\n".encode("latin-1"))
    (d / "configs" / "latin1.json").write_bytes('{"name": "café"}'.encode("latin-1"))
    np.savez(d / "amass.npz", poses=np.zeros((4, 156)), trans=np.zeros((4, 3)))
    (d / "amass.npz").rename(d / "motion.bvh")  # an AMASS-style .npz saved under a .bvh name
    (d / "bvh_named.npz").write_text((d / "good.bvh").read_text())
    (d / "random.npz").write_bytes(np.random.default_rng(0).bytes(300))
    store = d / "store"
    writer = sl.open_writer(store, 12, durable=False)
    sl.stage_all(writer)
    writer.pack()
    half = d / "half"
    writer = sl.open_writer(half, 12, durable=False)
    sl.stage_all(writer)
    (d / "not_a_store").mkdir()
    (d / "not_a_store" / "notes.txt").write_text("mine")
    (d / "run").mkdir()
    return d


# (id, argv with IN for the inputs directory and OUT for a fresh output directory, exit status,
#  words the message must hold, paths under OUT that must not exist afterwards)
CASES = [
    # --- generate: checked before anything is created
    ("generate-cuda-absent", ["generate", "IN/configs/micro.json", "--out", "OUT/s.zarr", "--device", "cuda"], 2,
     ["no CUDA device", "--device cpu"], ["s.zarr"]),
    ("generate-device-typo", ["generate", "IN/configs/micro.json", "--out", "OUT/s.zarr", "--device", "gpu"], 2,
     ["--device", "cpu or cuda"], ["s.zarr"]),
    ("generate-gpu-twice", ["generate", "IN/configs/micro.json", "--out", "OUT/s.zarr", "--device", "cuda:0,cuda:0"],
     2, ["cuda:0 more than once", "cuda:0,cuda:1"], ["s.zarr"]),
    ("generate-device-list-hole", ["generate", "IN/configs/micro.json", "--out", "OUT/s.zarr", "--device", "cpu,"],
     2, ["empty name"], ["s.zarr"]),
    ("generate-gpus-absent", ["generate", "IN/configs/micro.json", "--out", "OUT/s.zarr", "--device",
                              "cuda:0,cuda:1"], 2, ["no CUDA device", "--device cpu"], ["s.zarr"]),
    ("generate-ray-device-list", ["generate", "IN/configs/micro.json", "--out", "OUT/s.zarr", "--executor", "ray",
                                  "--device", "cuda:0,cuda:1"], 2, ["local executor", "--device cuda"], ["s.zarr"]),
    ("generate-negative-garment-seed", ["generate", "IN/configs/negative_seed.json", "--out", "OUT/s.zarr"], 2,
     ["tshirt:-1", "seed"], ["s.zarr"]),
    ("generate-negative-motion-seed", ["generate", "IN/configs/bad_motion_seed.json", "--out", "OUT/s.zarr"], 2,
     ["walk:-3", "seed"], ["s.zarr"]),
    ("generate-huge-frames", ["generate", "IN/configs/huge_frames.json", "--out", "OUT/s.zarr"], 2,
     ["frames"], ["s.zarr"]),
    ("generate-too-few-pairs", ["generate", "IN/configs/one_pair.json", "--out", "OUT/s.zarr"], 2,
     ["train split", "pairs", "fit_attribute"], ["s.zarr"]),
    ("generate-unknown-key", ["generate", "IN/configs/unknown_key.json", "--out", "OUT/s.zarr"], 2,
     ["framez"], ["s.zarr"]),
    ("generate-zero-batch", ["generate", "IN/configs/zero_batch.json", "--out", "OUT/s.zarr"], 2,
     ["batch_size"], ["s.zarr"]),
    ("generate-broken-yaml", ["generate", "IN/configs/broken.yaml", "--out", "OUT/s.zarr"], 2,
     ["broken.yaml"], ["s.zarr"]),
    ("generate-negative-dataset-seed", ["generate", "IN/configs/negative_dataset_seed.json", "--out", "OUT/s.zarr"], 2,
     ["seed", "-1"], ["s.zarr"]),
    ("generate-duplicate-yaml-key", ["generate", "IN/configs/duplicate.yaml", "--out", "OUT/s.zarr"], 2,
     ["'frames' twice", "line 1"], ["s.zarr"]),
    ("generate-duplicate-json-key", ["generate", "IN/configs/duplicate.json", "--out", "OUT/s.zarr"], 2,
     ["'frames' twice", "not valid json"], ["s.zarr"]),
    ("generate-config-not-utf8", ["generate", "IN/configs/latin1.yaml", "--out", "OUT/s.zarr"], 2,
     ["latin1.yaml", "not utf-8"], ["s.zarr"]),
    ("generate-missing-config", ["generate", "IN/configs/none.toml", "--out", "OUT/s.zarr"], 2,
     ["none.toml", "does not exist"], ["s.zarr"]),
    ("generate-unknown-preset", ["generate", "--preset", "huge", "--out", "OUT/s.zarr"], 2,
     ["unknown preset", "tiny"], ["s.zarr"]),
    ("generate-negative-workers", ["generate", "IN/configs/micro.json", "--out", "OUT/s.zarr", "--workers", "-1"], 2,
     ["--workers"], ["s.zarr"]),
    ("generate-into-foreign-directory", ["generate", "IN/configs/micro.json", "--out", "IN/not_a_store"], 2,
     ["not_a_store", "not a drape"], []),
    ("generate-into-a-file", ["generate", "IN/configs/micro.json", "--out", "IN/good.bvh"], 2,
     ["good.bvh"], []),
    # --- validate, info
    ("validate-missing", ["validate", "OUT/none.zarr"], 2, ["none.zarr", "does not exist"], []),
    ("validate-interrupted", ["validate", "IN/half"], 1, ["drape generate", "again"], []),
    ("validate-foreign", ["validate", "IN/not_a_store"], 2, ["not a drape dataset store"], []),
    ("info-foreign", ["info", "IN/not_a_store"], 2, ["not a drape dataset store"], []),
    ("info-a-file", ["info", "IN/good.bvh"], 2, ["good.bvh"], []),
    # --- garment make
    ("garment-missing-dir", ["garment", "make", "--type", "tshirt", "--out", "OUT/none/t.obj"], 2,
     ["does not exist"], ["none"]),
    ("garment-unknown-type", ["garment", "make", "--type", "gown", "--out", "OUT/g.obj"], 2,
     ["unknown garment", "gown"], ["g.obj"]),
    ("garment-edge-huge", ["garment", "make", "--type", "tshirt", "--edge-length", "5", "--out", "OUT/t.obj"], 2,
     ["--edge-length"], ["t.obj"]),
    ("garment-edge-coarse", ["garment", "make", "--type", "tshirt", "--edge-length", "0.5", "--out", "OUT/t.obj"], 2,
     ["--edge-length"], ["t.obj"]),
    ("garment-edge-negative", ["garment", "make", "--type", "tshirt", "--edge-length", "-0.01", "--out", "OUT/t.obj"],
     2, ["--edge-length"], ["t.obj"]),
    ("garment-negative-seed", ["garment", "make", "--type", "tshirt", "--seed", "-1", "--out", "OUT/t.obj"], 2,
     ["--seed"], ["t.obj"]),
    ("garment-bad-param", ["garment", "make", "--type", "tshirt", "--param", "sleeve=abc", "--out", "OUT/t.obj"], 2,
     ["sleeve"], ["t.obj"]),
    ("garment-unknown-material", ["garment", "make", "--type", "tshirt", "--material", "kevlar", "--out", "OUT/t.obj"],
     2, ["kevlar"], ["t.obj"]),
    ("garment-bad-format", ["garment", "make", "--type", "tshirt", "--out", "OUT/t.xyz"], 2, ["xyz"], ["t.xyz"]),
    # --- motion import
    ("bvh-missing-arm", ["motion", "import", "IN/no_left_arm.bvh", "--label-name", "walk", "--out", "OUT/m.npz"], 2,
     ["left_elbow", "no joint"], ["m.npz"]),
    ("bvh-missing-leg", ["motion", "import", "IN/no_left_leg.bvh", "--label-name", "walk", "--out", "OUT/m.npz"], 2,
     ["left_knee"], ["m.npz"]),
    ("bvh-garbage", ["motion", "import", "IN/garbage.bvh", "--label-name", "walk", "--out", "OUT/m.npz"], 2,
     ["garbage.bvh"], ["m.npz"]),
    ("bvh-missing-file", ["motion", "import", "IN/none.bvh", "--label-name", "walk", "--out", "OUT/m.npz"], 2,
     ["none.bvh", "does not exist"], ["m.npz"]),
    ("bvh-unlabelled", ["motion", "import", "IN/good.bvh", "--out", "OUT/m.npz"], 2,
     ["--label-name", "--allow-unlabelled"], ["m.npz"]),
    ("bvh-new-label", ["motion", "import", "IN/good.bvh", "--label-name", "moonwalk", "--out", "OUT/m.npz"], 2,
     ["moonwalk", "--new-label"], ["m.npz"]),
    ("bvh-bad-scale", ["motion", "import", "IN/good.bvh", "--label-name", "walk", "--scale", "-1", "--out",
                       "OUT/m.npz"], 2, ["--scale"], ["m.npz"]),
    ("bvh-bad-fps", ["motion", "import", "IN/good.bvh", "--label-name", "walk", "--fps", "0", "--out", "OUT/m.npz"], 2,
     ["--fps"], ["m.npz"]),
    ("amass-garbage", ["motion", "import", "IN/garbage.npz", "--label-name", "walk", "--out", "OUT/m.npz"], 2,
     ["garbage.npz"], ["m.npz"]),
    ("bvh-that-is-an-npz", ["motion", "import", "IN/motion.bvh", "--label-name", "walk", "--out", "OUT/m.npz"], 2,
     ["motion.bvh", "npz archive", ".npz suffix"], ["m.npz"]),
    ("npz-that-is-a-bvh", ["motion", "import", "IN/bvh_named.npz", "--label-name", "walk", "--out", "OUT/m.npz"], 2,
     ["bvh_named.npz", "bvh text", ".bvh suffix"], ["m.npz"]),
    ("motion-make-unknown-label", ["motion", "make", "--label", "moonwalk", "--out", "OUT/m.npz"], 2,
     ["moonwalk"], ["m.npz"]),
    # --- simulate, preview, body export
    ("simulate-negative-fps", ["simulate", "--fps", "-30", "--out", "OUT/r.npz"], 2, ["--fps"], ["r.npz"]),
    ("simulate-zero-frames", ["simulate", "--frames", "0", "--out", "OUT/r.npz"], 2, ["--frames"], ["r.npz"]),
    ("simulate-cuda-absent", ["simulate", "--device", "cuda", "--frames", "2", "--out", "OUT/r.npz"], 2,
     ["no CUDA device"], ["r.npz"]),
    ("simulate-unknown-motion", ["simulate", "--motion", "moonwalk", "--out", "OUT/r.npz"], 2, ["moonwalk"],
     ["r.npz"]),
    ("preview-negative-frame", ["preview", "IN/store", "--sample", "0", "--frame", "-1", "--out", "OUT/p.png"], 2,
     ["--frame"], ["p.png"]),
    ("preview-sample-out-of-range", ["preview", "IN/store", "--sample", "999", "--out", "OUT/p.png"], 2,
     ["999"], ["p.png"]),
    ("body-export-garbage-pose", ["body", "export", "--pose", "IN/garbage.npz", "--out", "OUT/b.obj"], 2,
     ["garbage.npz", "not"], ["b.obj"]),
    ("body-export-pose-without-poses", ["body", "export", "--pose", "IN/wrong_pose.npz", "--out", "OUT/b.obj"], 2,
     ["wrong_pose.npz"], ["b.obj"]),
    # --- export, train, evaluate, predict
    ("export-sample-out-of-range", ["export", "usd", "IN/store", "--sample", "999", "--out", "OUT/a.usda"], 2,
     ["999"], ["a.usda"]),
    ("train-foreign-store", ["train", "gnn", "--data", "IN/not_a_store", "--out", "OUT/run"], 2,
     ["not a drape dataset store"], ["run"]),
    ("train-zero-epochs", ["train", "gnn", "--data", "IN/store", "--out", "OUT/run", "--epochs", "0"], 2,
     ["epochs"], ["run"]),
    ("train-unknown-ablation", ["train", "gnn", "--data", "IN/store", "--out", "OUT/run", "--ablation", "nope"], 2,
     ["nope"], ["run"]),
    ("evaluate-not-a-run", ["evaluate", "IN/not_a_store"], 2, ["not a drape run directory"], []),
    ("predict-not-a-run", ["predict", "IN/run", "--data", "IN/store", "--sample", "0", "--out", "OUT/p.usda"], 2,
     ["not a drape run directory"], ["p.usda"]),
    ("predict-zero-max-error", ["predict", "IN/run", "--data", "IN/store", "--sample", "0", "--max-error", "0",
                                "--out", "OUT/p.usda"], 2, ["--max-error", "> 0"], ["p.usda"]),
    # --- random bytes, a half store: the words say what the file is and what to run
    ("preview-random-prediction", ["preview", "IN/store", "--sample", "0", "--prediction", "IN/random.npz",
                                   "--out", "OUT/p.png"], 2, ["random.npz", "not a numpy .npz"], ["p.png"]),
    ("export-random-npz", ["export", "usd", "IN/random.npz", "--out", "OUT/a.usda"], 2,
     ["random.npz", "not a numpy .npz"], ["a.usda"]),
    ("preview-half-store", ["preview", "IN/half", "--sample", "0", "--out", "OUT/p.png"], 2,
     ["not complete", "drape generate", "again"], ["p.png"]),
]

MISLEADING = {
    "preview-random-prediction": ["pickle", "allow_pickle"],
    "export-random-npz": ["pickle", "allow_pickle"],
    "generate-config-not-utf8": ["toml"],
    "preview-half-store": ["pack()", "StoreWriter"],
}
"""Words a case's message must not hold: what numpy, the wrong parser or the library would say."""


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_input_gets_one_clear_line(case, inputs, tmp_path, capsys, monkeypatch):
    from datagen.cli import main

    _name, argv, status, words, absent = case
    monkeypatch.setenv("CUDA_VISIBLE_DEVICES", "")  # no GPU here, whatever the machine has
    argv = [a.replace("IN", str(inputs)).replace("OUT", str(tmp_path)) for a in argv]
    before = sorted(p.name for p in tmp_path.iterdir())
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own usage errors
        code = exc.code
    captured = capsys.readouterr()
    err = captured.err
    assert "Traceback" not in err
    assert code == status, err[-1500:]
    if status == 2:
        lines = [ln for ln in err.splitlines() if "error:" in ln]
        assert len(lines) == 1, err[-1500:]
        message = lines[0]
    else:  # a validation report, printed
        message = captured.out + err
    for w in words:
        assert w.lower() in message.lower(), (w, message)
    for w in MISLEADING.get(_name, []):
        assert w.lower() not in message.lower(), (w, message)
    for rel in absent:
        assert not (tmp_path / rel).exists(), f"{rel} was left behind"
    assert sorted(p.name for p in tmp_path.iterdir()) == before or absent == []


def test_a_config_that_is_not_utf8_is_called_so_in_each_format(inputs, tmp_path):
    from datagen.config import read_config_file
    from datagen.errors import ConfigError

    (tmp_path / "latin1.toml").write_bytes('name = "café"\n'.encode("latin-1"))
    for path in (inputs / "configs" / "latin1.yaml", inputs / "configs" / "latin1.json", tmp_path / "latin1.toml"):
        with pytest.raises(ConfigError) as err:
            read_config_file(path)
        text = str(err.value)
        assert "is not UTF-8 text" in text and "0xe9" in text and "TOML" not in text.replace(".toml", ""), text


def test_a_material_value_against_its_meaning():
    """Stiffness, density and thickness > 0, bending, friction and damping >= 0, Poisson's ratio in
    [0, 1): a garment file's material (the record drape reads) is refused with the key and unit."""
    import dataclasses

    from datagen.errors import InputError
    from datagen.garment.metadata import GarmentMetadata
    from datagen.materials import MATERIALS

    cotton = MATERIALS["cotton"].as_dict()
    for key, value, words in [("stretch_warp", -1.0, "stretch_warp must be > 0 [N/m], got -1"),
                              ("density", 0.0, "density must be > 0 [kg/m²]"),
                              ("bending", -1e-6, "bending must be >= 0 [N·m]"),
                              ("poisson", 1.2, "poisson must be in [0, 1)"),
                              ("shear", float("nan"), "shear must be a finite number"),
                              ("friction", "high", "friction must be a finite number")]:
        with pytest.raises(InputError, match=re.escape(words)):
            GarmentMetadata.from_dict({"type": "tshirt", "material": {**cotton, key: value}})
    with pytest.raises(InputError, match="thickness must be > 0"):
        dataclasses.replace(MATERIALS["silk"], thickness=-0.001)
    assert GarmentMetadata.from_dict({"type": "tshirt", "material": cotton}).material == MATERIALS["cotton"]


def test_the_corpus_is_large_enough():
    assert len(CASES) >= 40


def test_ray_missing_is_refused_before_the_store_is_created(inputs, tmp_path, capsys, monkeypatch):
    import sys

    from datagen.cli import main

    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` fails as if Ray were not installed
    code = main(["generate", str(inputs / "configs" / "micro.json"), "--out", str(tmp_path / "s.zarr"),
                 "--executor", "ray"])
    err = capsys.readouterr().err
    assert code == 2 and "pip install 'drape[ray]'" in err and "Traceback" not in err
    assert not (tmp_path / "s.zarr").exists()


def test_a_garment_that_fails_its_checks_is_not_written(tmp_path, capsys, monkeypatch, default_body):
    import datagen.garment.checks as checks
    from datagen.cli import main

    real = checks.check_garment

    def failing(*a, **k):
        return {**real(*a, **k), "ok": False, "failures": ["an opening is not a single loop (made up by this test)"]}

    monkeypatch.setattr(checks, "check_garment", failing)
    out = tmp_path / "t.obj"
    code = main(["garment", "make", "--type", "skirt", "--edge-length", "0.05", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "fails its checks" in err and "nothing was written" in err and "made up by this test" in err
    assert not out.exists()


def test_ctrl_c_says_how_to_resume(monkeypatch, capsys, tmp_path):
    import datagen.generate.run as run
    from datagen.cli import main

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(run, "generate", interrupted)
    code = main(["generate", "--preset", "tiny", "--out", str(tmp_path / "t.zarr")])
    err = capsys.readouterr().err
    assert code == 130 and "interrupted" in err and "run the same command again" in err and "resumes" in err


def test_beta_far_outside_the_population_warns(tmp_path, capsys, caplog, default_body):
    from datagen.cli import main

    out = tmp_path / "b.obj"
    with caplog.at_level("WARNING"):
        assert main(["body", "export", "--betas", "1000", "--out", str(out)]) == 0
    assert "beyond ±3" in caplog.text and "β[0]" in caplog.text and out.exists()


# --- issue 65: one table of commands x bad values, generated. Each class (output paths, seeds, numbers,
# a damaged store, a damaged or foreign checkpoint, conflicting flags) for every command it applies to.

OUTPUTS = {  # command -> (argv before --out's value, the flag, a good suffix)
    "body-build": (["body", "build"], "--out", ".pkl"),
    "body-export": (["body", "export"], "--out", ".obj"),
    "motion-make": (["motion", "make", "--label", "walk"], "--out", ".npz"),
    "motion-import": (["motion", "import", "IN/good.bvh", "--label-name", "walk"], "--out", ".npz"),
    "motion-export": (["motion", "export", "IN/walk.npz", "--format", "bvh"], "--out", ".bvh"),
    "garment-make": (["garment", "make", "--type", "tshirt"], "--out", ".obj"),
    "garment-show": (["garment", "make", "--type", "tshirt", "--out", "OUT/t.obj"], "--show", ".png"),
    "simulate": (["simulate"], "--out", ".npz"),
    "preview": (["preview", "IN/store", "--sample", "0"], "--out", ".png"),
    "export-usd": (["export", "usd", "IN/store", "--sample", "0"], "--out", ".usda"),
    "evaluate-json": (["evaluate", "IN/not_a_store"], "--json", ".json"),
    "predict": (["predict", "IN/run", "--data", "IN/store", "--sample", "0"], "--out", ".usda"),
    "sample-clothed": (["sample", "clothed", "--garment-model", "IN/run", "--motion", "IN/walk.npz"], "--out", ".usda"),
    "sample-clothed-video": (["sample", "clothed", "--garment-model", "IN/run", "--motion", "IN/walk.npz", "--out",
                              "OUT/a.usda"], "--video", ".mp4"),
}
OUTPUT_DIRS = {  # command -> argv before --out's value (a directory the command creates)
    "generate": ["generate", "IN/configs/micro.json"],
    "train": ["train", "gnn", "--data", "IN/store"],
    "refine": ["train", "refine", "--garment-model", "IN/run", "--motion-model", "IN/run"],
    "sample-motion": ["sample", "motion", "IN/run", "--label", "walk"],
    "export-usd-all": ["export", "usd", "IN/store", "--all"],
    "info-plots": ["info", "IN/store"],
}
READ_ONLY = "/sys"
"""A folder no one may create a file in, root included (the tests run as root in CI containers too)."""

TABLE = []
for name, (argv, flag, suffix) in OUTPUTS.items():
    TABLE += [(f"{name}-missing-folder", [*argv, flag, f"OUT/nodir/x{suffix}"], 2, ["nodir", "does not exist"], ["nodir"]),
              (f"{name}-a-directory", [*argv, flag, "OUT"], 2,
               ["must end in"] if name == "export-usd" else ["is a directory"], []),
              (f"{name}-read-only", [*argv, flag, f"{READ_ONLY}/x{suffix}"], 2, ["not writable"], []),
              (f"{name}-wrong-suffix", [*argv, flag, "OUT/x.txt"], 2, ["x.txt", "must end in"], ["x.txt"])]
for name, argv in OUTPUT_DIRS.items():
    flag = "--plots" if name == "info-plots" else "--out"
    TABLE += [(f"{name}-dir-is-a-file", [*argv, flag, "IN/good.bvh"], 2, ["good.bvh", "not a directory"], []),
              (f"{name}-dir-read-only", [*argv, flag, f"{READ_ONLY}/d"], 2, ["not writable"], [])]
SEEDS = {"body-build": ["body", "build", "--seed"], "body-export": ["body", "export", "--out", "OUT/b.obj", "--seed"],
         "body-measure": ["body", "measure", "--seed"],
         "motion-make": ["motion", "make", "--label", "walk", "--out", "OUT/m.npz", "--seed"],
         "garment-make": ["garment", "make", "--type", "tshirt", "--out", "OUT/t.obj", "--seed"],
         "simulate-garment": ["simulate", "--out", "OUT/r.npz", "--garment-seed"],
         "simulate-motion": ["simulate", "--out", "OUT/r.npz", "--motion-seed"],
         "refine": ["train", "refine", "--garment-model", "IN/run", "--motion-model", "IN/run", "--out", "OUT/r", "--seed"],
         "sample-motion": ["sample", "motion", "IN/run", "--label", "walk", "--out", "OUT/g", "--seed"],
         "sample-clothed": ["sample", "clothed", "--garment-model", "IN/run", "--out", "OUT/a.usda", "--seed"]}
for name, argv in SEEDS.items():
    TABLE += [(f"{name}-negative-seed", [*argv, "-1"], 2, [argv[-1], "out of range"], ["b.obj", "m.npz", "t.obj", "r.npz", "r", "g", "a.usda"]),
              (f"{name}-huge-seed", [*argv, str(2**40)], 2, [argv[-1], "out of range"], []),
              (f"{name}-seed-not-a-number", [*argv, "abc"], 2, [argv[-1], "not a whole number"], [])]
NUMBERS = [  # (id, argv, words)
    ("motion-make-huge-frames", ["motion", "make", "--label", "walk", "--frames", "1000000000", "--out", "OUT/m.npz"],
     ["--frames 1000000000", "GiB", "fewer frames"]),
    ("motion-make-nan-fps", ["motion", "make", "--label", "walk", "--fps", "nan", "--out", "OUT/m.npz"], ["--fps", "finite"]),
    ("simulate-huge-frames", ["simulate", "--frames", "100000", "--out", "OUT/r.npz"], ["--frames 100000", "GiB"]),
    ("simulate-zero-substeps", ["simulate", "--substeps", "0", "--out", "OUT/r.npz"], ["--substeps"]),
    ("simulate-inf-fps", ["simulate", "--fps", "inf", "--out", "OUT/r.npz"], ["--fps", "finite"]),
    ("evaluate-negative-max-frames", ["evaluate", "IN/run", "--max-frames", "-3"], ["--max-frames"]),
    ("evaluate-zero-repetitions", ["evaluate", "IN/run", "--repetitions", "0"], ["--repetitions"]),
    ("preview-nan-view", ["preview", "IN/store", "--sample", "0", "--view", "nan", "--out", "OUT/p.png"], ["--view", "finite"]),
    ("preview-negative-sample", ["preview", "IN/store", "--sample", "-1", "--out", "OUT/p.png"], ["--sample"]),
    ("preview-zero-clip-fps", ["preview", "IN/store", "--sample", "0", "--frames", "0:2", "--clip-fps", "0", "--out",
                               "OUT/p.gif"], ["--clip-fps"]),
    ("export-negative-sample", ["export", "usd", "IN/store", "--sample", "-2", "--out", "OUT/a.usda"], ["--sample"]),
    ("body-export-negative-frame", ["body", "export", "--frame", "-9", "--out", "OUT/b.obj"], ["--frame"]),
    ("generate-zero-batch-size", ["generate", "IN/configs/micro.json", "--batch-size", "0", "--out", "OUT/s.zarr"],
     ["--batch-size"]),
    ("generate-negative-time-limit", ["generate", "IN/configs/micro.json", "--time-limit", "-1", "--out", "OUT/s.zarr"],
     ["--time-limit"]),
    ("train-negative-minutes", ["train", "gnn", "--data", "IN/store", "--max-minutes", "-1", "--out", "OUT/run"],
     ["--max-minutes"]),
    ("refine-zero-steps", ["train", "refine", "--garment-model", "IN/run", "--motion-model", "IN/run", "--steps", "0",
                           "--out", "OUT/r"], ["--steps"]),
    ("sample-motion-zero-count", ["sample", "motion", "IN/run", "--label", "walk", "--count", "0", "--out", "OUT/g"],
     ["--count"]),
    ("sample-motion-huge-frames", ["sample", "motion", "IN/run", "--label", "walk", "--frames", "1000000000", "--out",
                                   "OUT/g"], ["--frames"]),
    ("motion-import-nan-scale", ["motion", "import", "IN/good.bvh", "--label-name", "walk", "--scale", "nan", "--out",
                                 "OUT/m.npz"], ["--scale"]),
]
TABLE += [(i, argv, 2, words, ["m.npz", "r.npz", "p.png", "p.gif", "a.usda", "b.obj", "s.zarr", "run", "r", "g"])
          for i, argv, words in NUMBERS]
DAMAGED = {  # a reader -> its argv with STORE for the damaged store
    "preview": ["preview", "STORE", "--sample", "0", "--out", "OUT/p.png"],
    "export-usd": ["export", "usd", "STORE", "--sample", "0", "--out", "OUT/a.usda"],
    "export-usd-all": ["export", "usd", "STORE", "--all", "--out", "OUT/all"],
    "train": ["train", "gnn", "--data", "STORE", "--out", "OUT/run"],
    "evaluate": ["evaluate", "IN/gnnrun", "--data", "STORE"],
    "predict": ["predict", "IN/gnnrun", "--data", "STORE", "--sample", "0", "--out", "OUT/p.usda"],
}
for damage in ("deleted_array", "metadata_disagrees", "missing_zarr_json", "flipped_shard"):
    for name, argv in DAMAGED.items():
        TABLE.append((f"{name}-{damage}", [a.replace("STORE", f"IN/damaged/{damage}") for a in argv], 1,
                      ["the store is damaged at vertex_frames/detail", "drape validate"], ["p.png", "a.usda", "all", "run", "p.usda"]))
TABLE.append(("info-metadata_disagrees", ["info", "IN/damaged/metadata_disagrees"], 1, ["DAMAGED", "vertex_frames/detail"], []))
TABLE += [  # checkpoints: damaged, another model, a run whose store moved
    ("evaluate-truncated-checkpoint", ["evaluate", "IN/truncated"], 2, ["best.ckpt", "is damaged"], []),
    ("predict-truncated-checkpoint", ["predict", "IN/truncated", "--data", "IN/store", "--sample", "0", "--out",
                                      "OUT/p.usda"], 2, ["best.ckpt", "is damaged"], ["p.usda"]),
    ("resume-truncated-checkpoint", ["train", "gnn", "--data", "IN/store", "--out", "IN/truncated", "--resume"], 2,
     ["last.ckpt", "is damaged"], []),
    ("sample-motion-truncated-checkpoint", ["sample", "motion", "IN/truncated_motion", "--label", "walk", "--out",
                                            "OUT/g"], 2, ["best.ckpt", "is damaged"], ["g"]),
    ("evaluate-another-model", ["evaluate", "IN/foreign"], 2, ["belongs to another model", "paper 000's gnn"], []),
    ("predict-another-model", ["predict", "IN/foreign", "--data", "IN/store", "--sample", "0", "--out", "OUT/p.usda"], 2,
     ["belongs to another model"], ["p.usda"]),
    ("evaluate-other-shapes", ["evaluate", "IN/other_shapes"], 2, ["other shapes", "in this config's model"], []),
    ("evaluate-store-moved", ["evaluate", "IN/gnnrun"], 2, ["no longer at", "--data"], []),
    ("train-resume-and-force", ["train", "gnn", "--data", "IN/store", "--out", "IN/gnnrun", "--resume", "--force"], 2,
     ["--force", "not allowed with", "--resume"], []),
    ("train-force-and-resume", ["train", "gnn", "--data", "IN/store", "--out", "OUT/run", "--force",
                                           "--resume"], 2, ["not allowed with"], ["run"]),
]


def _damage(store: Path, into: Path) -> None:
    """Copies of ``store`` with one kind of damage each at vertex_frames/detail."""
    import shutil

    detail = "vertex_frames/detail"
    for kind in ("deleted_array", "metadata_disagrees", "missing_zarr_json", "flipped_shard"):
        copy = into / kind
        shutil.copytree(store, copy)
        if kind == "deleted_array":
            shutil.rmtree(copy / detail)
        elif kind == "missing_zarr_json":
            (copy / detail / "zarr.json").unlink()
        elif kind == "metadata_disagrees":
            f = copy / detail / "zarr.json"
            m = json.loads(f.read_text())
            m["shape"][0] -= 5
            f.write_text(json.dumps(m))
        else:
            f = copy / detail / "c" / "0" / "0"
            b = bytearray(f.read_bytes())
            b[len(b) // 3:len(b) // 3 + 16] = bytes(x ^ 0xFF for x in b[len(b) // 3:len(b) // 3 + 16])
            f.write_bytes(bytes(b))


def _runs(d: Path) -> None:
    """Run directories with a GNN checkpoint in Lightning's format (made without training: the weights of a
    freshly built module) whose store is no longer there, a truncated one, one of another model, one of
    other shapes, and a truncated motion-generator run."""
    import torch

    from datagen.store import open_store
    from training.gnn.config import GNNConfig
    from training.gnn.module import GNNModule
    from training.loop import store_identity

    config = GNNConfig()
    identity = store_identity(open_store(d / "store"))

    def run(name: str, kind: str, state: dict, hyper: dict, store: dict) -> Path:
        r = d / name
        (r / "checkpoints").mkdir(parents=True)
        (r / "run.json").write_text(json.dumps({"kind": kind, "config": config.as_dict(), "store": store}))
        for ckpt in ("best", "last"):
            torch.save({"state_dict": state, "hyper_parameters": hyper, "epoch": 1, "global_step": 4,
                        "optimizer_states": []}, r / "checkpoints" / f"{ckpt}.ckpt")
        return r

    gnn = GNNModule(config, attribute_features=4)
    hyper = {"config": config.as_dict(), "attribute_features": 4}
    run("gnnrun", "gnn", gnn.state_dict(), hyper, {**identity, "path": str(d / "moved.zarr")})
    for name, kind in (("truncated", "gnn"), ("truncated_motion", "motion")):
        r = run(name, kind, gnn.state_dict(), hyper, identity)
        for f in (r / "checkpoints").iterdir():
            f.write_bytes(f.read_bytes()[: f.stat().st_size // 2])
    run("foreign", "gnn", {"encoder.layers.0.weight": torch.zeros(3, 3)}, {"labels": ["walk"], "latent": 8}, identity)
    other = GNNModule(config, attribute_features=9)
    run("other_shapes", "gnn", other.state_dict(), hyper, identity)


@pytest.fixture(scope="module")
def table_inputs(inputs):
    """The module's inputs plus damaged stores, run directories and a motion file."""
    d = inputs
    if not (d / "damaged").exists():
        (d / "damaged").mkdir()
        _damage(d / "store", d / "damaged")
        _runs(d)
        np.savez(d / "walk.npz", poses=np.zeros((4, 72)), trans=np.zeros((4, 3)), mocap_framerate=30.0, label="walk")
        _bad_animations(d)
    return d


def _bad_animations(d: Path) -> None:
    """Animations of plain arrays with a NaN position or a face out of range, and a prediction with a NaN."""
    from datagen.store import open_store

    rng = np.random.default_rng(0)
    v, b = rng.random((3, 10, 3), np.float32), rng.random((3, 12, 3), np.float32)
    faces, body_faces = np.array([[0, 1, 2], [2, 3, 4]]), np.array([[0, 1, 2]])
    nan = v.copy()
    nan[1, 3] = np.nan
    np.savez(d / "nan_positions.npz", garment_vertices=nan, garment_faces=faces, body_vertices=b, body_faces=body_faces,
             fps=30.0)
    np.savez(d / "faces_out_of_range.npz", garment_vertices=v, garment_faces=np.array([[0, 1, 99]]), body_vertices=b,
             body_faces=body_faces, fps=30.0)
    store = open_store(d / "store")
    pred = np.zeros((store.frame_count(0), store.vertex_count(0), 3), np.float32)
    pred[0, 0, 0] = np.nan
    np.savez(d / "nan_prediction.npz", garment_vertices=pred)


TABLE += [  # animations with NaN positions or faces out of range
    ("preview-nan-positions", ["preview", "IN/nan_positions.npz", "--frame", "1", "--out", "OUT/p.png"], 2,
     ["garment_vertices", "non-finite", "frame(s) [1]"], ["p.png"]),
    ("preview-faces-out-of-range", ["preview", "IN/faces_out_of_range.npz", "--out", "OUT/p.png"], 2,
     ["garment_faces", "outside 0 .. 9"], ["p.png"]),
    ("export-nan-positions", ["export", "usd", "IN/nan_positions.npz", "--out", "OUT/a.usda"], 2,
     ["garment_vertices", "non-finite"], ["a.usda"]),
    ("export-faces-out-of-range", ["export", "usd", "IN/faces_out_of_range.npz", "--out", "OUT/a.usda"], 2,
     ["garment_faces", "outside"], ["a.usda"]),
    ("preview-nan-prediction", ["preview", "IN/store", "--sample", "0", "--prediction", "IN/nan_prediction.npz",
                                "--color-by", "error", "--out", "OUT/p.png"], 2, ["prediction", "non-finite"], ["p.png"]),
]


@pytest.mark.parametrize("case", TABLE, ids=[c[0] for c in TABLE])
def test_the_table_of_commands_and_bad_values(case, table_inputs, tmp_path, capsys, monkeypatch):
    test_bad_input_gets_one_clear_line(case, table_inputs, tmp_path, capsys, monkeypatch)


def test_the_table_covers_every_class():
    assert len(TABLE) >= 150, len(TABLE)
