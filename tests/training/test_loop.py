"""The shared training loop's helpers."""

import torch
from torch_geometric.data import Batch, Data

from training.loop import batch_samples


def test_batch_samples_counts_graphs_segments_and_rows():
    """The throughput counts samples, not a batch's keys: a PyG batch by its graphs, a dict of
    segments (the garment regressor's and the motion generator's batches) by its first tensor's
    leading size, a tuple by its first tensor's."""
    graphs = Batch.from_data_list([Data(x=torch.zeros(5, 3)) for _ in range(3)])
    segments = {"pose": torch.zeros(7, 60, 24, 3), "trans": torch.zeros(7, 60, 3), "label": torch.zeros(7, 60),
                "detail": torch.zeros(7, 60, 10, 3), "garment": torch.zeros(7)}
    assert batch_samples(graphs) == 3
    assert batch_samples(segments) == 7
    assert batch_samples((torch.zeros(4, 2), torch.zeros(4))) == 4


def test_a_run_whose_validation_loss_turns_nan_is_reported_as_diverged(tmp_path):
    """Early stopping ends a run whose monitored value is NaN; the loop says so (``diverged``, and
    one line for the train commands) instead of reporting a normal end, and keeps the best epoch."""
    import pytorch_lightning as pl

    from training.config import BaseConfig
    from training.loop import divergence_note, fit

    class Blows(pl.LightningModule):
        def __init__(self):
            super().__init__()
            self.w = torch.nn.Parameter(torch.ones(1))

        def training_step(self, batch, _):
            return ((self.w * batch[0]) ** 2).mean()

        def validation_step(self, batch, _):
            loss = ((self.w * batch[0]) ** 2).mean()
            self.log("val/loss", loss if self.current_epoch < 2 else loss * float("nan"))

        def configure_optimizers(self):
            return torch.optim.SGD(self.parameters(), lr=0.01)

    data = torch.utils.data.TensorDataset(torch.ones(4, 1))
    loaders = pl.LightningDataModule.from_datasets(data, data, batch_size=2)
    result = fit(Blows(), loaders, BaseConfig(epochs=6, precision="32", workers=0), tmp_path, device="cpu",
                 monitor="val/loss")
    assert result["diverged"]["epoch"] == 2 and result["diverged"]["metric"] == "val/loss"
    assert result["best"] is not None and result["best"] == result["best"]  # the finite best epoch is kept
    note = divergence_note(result, "bf16-mixed")
    assert "diverged" in note and "epoch 2" in note and "precision" in note
    assert divergence_note({"best_checkpoint": "x"}, "32") is None


def test_the_loop_logs_the_training_throughput_of_every_epoch(tmp_path):
    """Lightning's ThroughputMonitor (validation excluded) gives one figure per epoch: in the CSV log
    and in fit's result."""
    import pytorch_lightning as pl

    from training.config import BaseConfig
    from training.loop import THROUGHPUT_KEY, fit, read_metrics

    class Line(pl.LightningModule):
        def __init__(self):
            super().__init__()
            self.w = torch.nn.Parameter(torch.ones(1))

        def training_step(self, batch, _):
            return ((self.w * batch[0] - 2) ** 2).mean()

        def validation_step(self, batch, _):
            self.log("val/loss", ((self.w * batch[0] - 2) ** 2).mean())

        def configure_optimizers(self):
            return torch.optim.SGD(self.parameters(), lr=0.01)

    data = torch.utils.data.TensorDataset(torch.ones(16, 1))
    result = fit(Line(), pl.LightningDataModule.from_datasets(data, data, batch_size=2),
                 BaseConfig(epochs=3, precision="32", workers=0), tmp_path, device="cpu", monitor="val/loss")
    rates = result["train_samples_per_second"]
    assert len(rates) == 3 and all(r > 0 for r in rates)
    assert list(read_metrics(tmp_path, THROUGHPUT_KEY)) == [0, 1, 2]
