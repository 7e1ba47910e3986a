"""A newcomer's CPU path (issue 62): every model has a ready config in ``configs/`` that the strict
loader reads, that keeps torch's threads plus DataLoader workers within a 2-core machine, and that
trains through ``drape train KIND --config configs/...`` (one epoch here, on the session's micro
stores); ``configs/tiny_paper001_store.yaml`` is a store paper 001's models can both train on."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

pytestmark = pytest.mark.slow

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
CORES = 2
"""The small machine the configs are for."""

KINDS = {"gnn": ("gnn_cpu.yaml", "train_store", []), "motion": ("motion_cpu.yaml", "train_store", []),
         "garment": ("garment_cpu.yaml", "motion_store", ["--garment", "skirt"])}


@pytest.fixture
def keep_threads():
    """The configs set torch's threads in this process; later tests get the number back."""
    threads = torch.get_num_threads()
    yield
    torch.set_num_threads(threads)


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_each_models_cpu_config_loads_and_stays_within_two_cores(kind):
    from datagen.config import load_config
    from training.kinds import get_kind

    name, _, _ = KINDS[kind]
    config = load_config(get_kind(kind).config_class(), CONFIGS / name)
    assert config.threads is not None and config.threads + config.workers <= CORES
    assert config.precision in ("32", "auto")


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_each_models_cpu_config_trains_an_epoch_through_drape_train(kind, request, tmp_path, keep_threads, capsys):
    from datagen.cli import main
    from training.loop import read_metrics

    name, store_fixture, extra = KINDS[kind]
    store = request.getfixturevalue(store_fixture)
    out = tmp_path / kind
    code = main(["train", kind, "--data", str(store), "--out", str(out), "--config", str(CONFIGS / name),
                 "--epochs", "1", "--device", "cpu", *extra])
    assert code == 0, capsys.readouterr().err
    assert torch.get_num_threads() == 2  # the config's threads, set for the run
    assert (out / "checkpoints" / "best.ckpt").is_file()
    stored = json.loads((out / "run.json").read_text())["config"]
    assert stored["threads"] == 2 and stored["workers"] == 0 and stored["epochs"] == 1
    losses = list(read_metrics(out, "train/loss_epoch").values())
    assert len(losses) == 1 and all(torch.isfinite(torch.tensor(losses)))


def test_the_tiny_paper001_store_config_holds_one_template_in_every_split_and_splits_by_motion():
    from datagen.config import load_config
    from datagen.generate.config import DatasetConfig

    c = load_config(DatasetConfig, CONFIGS / "tiny_paper001_store.yaml")
    splits = c.splits
    assert {tuple(s.garments) for s in splits.values()} == {("skirt:0",)}  # the regressor's template everywhere
    assert c.split_disjoint == ("motions",) and not c.fit_attribute
    train_labels = {m.split(":")[0] for m in splits["train"].motions}
    for split in ("val", "test"):  # other seeds of labels the generator trains on (none left out)
        assert {m.split(":")[0] for m in splits[split].motions} <= train_labels
        assert not set(splits[split].motions) & set(splits["train"].motions)
