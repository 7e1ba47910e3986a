"""The model-kind registry: every built-in record resolves, a dummy kind registered by a test trains
and evaluates through ``drape train`` / ``drape evaluate`` with nothing else edited, and a run of
a kind drape does not know is refused in one line (never sent down another kind's path)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import pytest
import pytorch_lightning as pl
import torch

from training.config import BaseConfig
from training.datamodule import StoreDataModule
from training.kinds import EvaluateRequest, ModelKind, get_kind, kinds, register, unregister


# -- a dummy model kind, as a new model's package would hold it: config, data module, module, train, evaluate


@dataclass(frozen=True, kw_only=True)
class DummyConfig(BaseConfig):
    """A linear map from a segment's mean pose to its mean translation."""

    hidden: int = field(default=8, metadata={"min": 1, "max": 64})


class DummyData(StoreDataModule):
    config: DummyConfig

    def build(self):
        from training.paper001.data import SegmentDataset

        self.train_set = SegmentDataset(self.store, "train", names=("pose", "trans"))
        self.val_set = SegmentDataset(self.store, "val", names=("pose", "trans"))

    def train_dataloader(self):
        return self.loader(self.train_set, shuffle=True)

    def val_dataloader(self):
        return self.loader(self.val_set)

    def summary(self):
        return {"train_segments": len(self.train_set)}


class DummyModule(pl.LightningModule):
    def __init__(self, config: DummyConfig | dict):
        super().__init__()
        self.config = config if isinstance(config, DummyConfig) else DummyConfig.from_dict(config)
        config = self.config.as_dict()  # what the checkpoint keeps
        self.save_hyperparameters("config")
        self.net = torch.nn.Sequential(torch.nn.Linear(72, self.config.hidden), torch.nn.Tanh(),
                                       torch.nn.Linear(self.config.hidden, 3))

    @classmethod
    def from_data(cls, config, data):
        return cls(config)

    def error(self, batch):
        return torch.nn.functional.mse_loss(self.net(batch["pose"].float().mean(1).flatten(1)),
                                            batch["trans"].float().mean(1))

    def training_step(self, batch, _):
        loss = self.error(batch)
        self.log("train/loss", loss, on_epoch=True, batch_size=len(batch["pose"]))
        return loss

    def validation_step(self, batch, _):
        self.log("val/loss", self.error(batch), batch_size=len(batch["pose"]))

    def configure_optimizers(self):
        from training.loop import plateau_optimizer

        return plateau_optimizer(self, self.parameters(), self.config, "val/loss")


def train_dummy(data, out, config, *, device="auto", resume=False, force=False):
    from datagen.store import open_store
    from training.loop import fit, prepare_run, seed_everything, store_identity, write_summary

    store = open_store(data)
    segments = DummyData(store, config)
    segments.setup()
    out = prepare_run(out, resume=resume, force=force,
                      meta={"kind": "dummy", "config": config.as_dict(), "store": store_identity(store)})
    seed_everything(config.seed)
    result = fit(DummyModule.from_data(config, segments), segments, config, out, device=device, resume=resume,
                 monitor="val/loss")
    result |= {"seconds": 0.0, **segments.summary()}
    write_summary(out, result)
    return result


@torch.no_grad()
def evaluate_dummy(r: EvaluateRequest) -> dict:
    from datagen.store import open_store
    from training.loop import run_checkpoint
    from training.paper001.data import SegmentDataset

    meta, path = run_checkpoint(r.run, "dummy", "the dummy model")
    module = DummyModule.load_from_checkpoint(path, map_location="cpu").eval()
    ds = SegmentDataset(open_store(r.data or meta["store"]["path"]), r.split, names=("pose", "trans"))
    batch = next(iter(torch.utils.data.DataLoader(ds, batch_size=len(ds))))
    return {"split": r.split, "segments": len(ds), "mse": float(module.error(batch))}


DUMMY = ModelKind(name="dummy", help="a test's dummy model", config=DummyConfig, datamodule=DummyData,
                  module=DummyModule, train=train_dummy, evaluate=evaluate_dummy,
                  format_evaluation=lambda e: f"{e['split']}: {e['segments']} segments, mse {e['mse']:.6f}",
                  report=lambda result, config: f"dummy trained {result['epochs']} epochs",
                  arguments=lambda p: p.add_argument("--hidden", type=int, default=None),
                  overrides=lambda args: {"hidden": args.hidden})


@pytest.fixture
def dummy_kind():
    register(DUMMY)
    yield DUMMY
    unregister("dummy")


def test_every_built_in_kind_resolves():
    """Each record's parts import and fit together: a config class of the base config, a data module of
    the base data module, a LightningModule with ``from_data``, and callables."""
    names = [k.name for k in kinds()]
    assert names[:3] == ["gnn", "motion", "garment"]
    for kind in kinds()[:3]:
        assert issubclass(kind.config_class(), BaseConfig), kind.name
        assert issubclass(kind.part("datamodule"), StoreDataModule), kind.name
        assert issubclass(kind.part("module"), pl.LightningModule) and hasattr(kind.part("module"), "from_data")
        for part in ("train", "evaluate", "format_evaluation", "report"):
            assert callable(kind.part(part)), (kind.name, part)
    assert get_kind("gnn").part("predict") is not None and get_kind("motion").part("predict") is None


@pytest.mark.slow
def test_a_registered_dummy_kind_trains_and_evaluates_through_the_command_line(dummy_kind, train_store, tmp_path,
                                                                              capsys):
    from datagen.cli import main

    run = tmp_path / "dummy"
    cfg = tmp_path / "dummy.json"
    cfg.write_text(json.dumps({"epochs": 3, "batch_size": 2, "workers": 0, "precision": "32", "lr": 1e-2}))
    assert main(["train", "dummy", "--data", str(train_store), "--out", str(run), "--config", str(cfg),
                 "--hidden", "4", "--device", "cpu"]) == 0
    assert "dummy trained 3 epochs" in capsys.readouterr().out
    meta = json.loads((run / "run.json").read_text())
    assert meta["kind"] == "dummy" and meta["config"]["hidden"] == 4 and meta["config"]["epochs"] == 3
    assert (run / "checkpoints" / "best.ckpt").is_file() and (run / "checkpoints" / "last.ckpt").is_file()
    out = tmp_path / "e.json"
    assert main(["evaluate", str(run), "--split", "test", "--device", "cpu", "--json", str(out)]) == 0
    e = json.loads(out.read_text())
    assert e["split"] == "test" and e["segments"] > 0 and e["mse"] > 0
    assert f"test: {e['segments']} segments" in capsys.readouterr().out
    # the kind's module loads from its checkpoint with its typed config
    module = DummyModule.load_from_checkpoint(run / "checkpoints" / "last.ckpt", map_location="cpu")
    assert module.config == DummyConfig(epochs=3, batch_size=2, workers=0, precision="32", lr=1e-2, hidden=4)


def test_a_run_of_an_unknown_kind_is_refused_in_one_line(tmp_path, capsys):
    from datagen.cli import main

    run = tmp_path / "other"
    run.mkdir()
    (run / "run.json").write_text(json.dumps({"kind": "nope", "config": {}}))
    assert main(["evaluate", str(run), "--device", "cpu"]) == 2
    err = capsys.readouterr().err
    assert "model kind 'nope', which drape does not know" in err and "gnn, motion, garment" in err
    assert main(["predict", str(run), "--data", str(tmp_path), "--sample", "0", "--out", str(tmp_path / "p.usda")]) == 2
    assert "drape does not know" in capsys.readouterr().err
    assert main(["evaluate", str(tmp_path / "missing"), "--device", "cpu"]) == 2
    assert "not a drape run directory" in capsys.readouterr().err


def test_the_configs_share_one_base_and_keep_their_defaults_and_limits():
    """The three configs extend the base: the shared fields are declared once (a kind changes only
    their defaults, and the limits stay the base's), and a stored config of an older run loads with
    the values that run trained with."""
    from datagen.config import load_config
    from datagen.errors import ConfigError
    from training.garment.config import GarmentConfig
    from training.gnn.config import GNNConfig
    from training.motion.config import MotionConfig

    for cls, epochs, lr in ((GNNConfig, 40, 1e-3), (MotionConfig, 5000, 1e-4), (GarmentConfig, 2000, 1e-3)):
        assert issubclass(cls, BaseConfig) and cls().epochs == epochs and cls().lr == lr
        assert cls.__dataclass_fields__["epochs"].metadata == BaseConfig.__dataclass_fields__["epochs"].metadata
        with pytest.raises(ConfigError, match="lr"):
            load_config(cls, {"lr": 5.0})
    old = {k: v for k, v in GarmentConfig().as_dict().items() if k not in ("relative_to", "lr_patience_steps")}
    assert GarmentConfig.from_dict(old).relative_to == "translation"  # runs from before the switch: the paper's
    assert MotionConfig.from_dict({"epochs": 7}).lr_patience_steps is None


def test_kinds_are_registered_once(dummy_kind):
    with pytest.raises(ValueError, match="registered already"):
        register(dummy_kind)
    assert register(dummy_kind, replace=True) is dummy_kind and get_kind("dummy") is dummy_kind
