"""Paper 000's model in the training loop: losses, the inference path and the validation error.

Training follows the paper: W_coarse learns Δ_coarse from the body graph; W_parser and W_detail
learn Δ_detail from the garment graph whose features come from the ground-truth coarse mesh
(MSE on both, optimised together; each step's graph is independent of the other's prediction).
Inference (validation, evaluation, prediction) chains them: the detail features (coarse normals
and joint distances) are recomputed from the *predicted* coarse mesh with the store's feature
function (``datagen.features``), so the validation error is the error a user gets.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytorch_lightning as pl
import torch

from training.gnn.config import GNNConfig
from training.gnn.features import node_features
from training.gnn.model import DetailAwareGNN


def detail_features(coarse: torch.Tensor, batch) -> torch.Tensor:
    """[n, p, x] (R^30) of a batch's garments at the coarse positions ``coarse`` [N, 3]: the
    dataset's :func:`~training.gnn.features.node_features` on the batch."""
    return node_features(coarse, batch.face, batch.skin, batch.joints, batch.batch)


class GNNModule(pl.LightningModule):
    """The Lightning module of paper 000's GNN.

    Args:
        config: the run's :class:`~training.gnn.config.GNNConfig` (a checkpoint stores it as a dict,
            which loading turns back into the dataclass).
        attribute_features: length of the parser's input (α, β, θ): :attr:`GNNDataModule.attribute_features`.
    """

    PREDICT_INPUTS = ("x_coarse", "edge_index", "batch", "attributes", "anchor", "face", "joints", "skin")
    """The batch's fields :meth:`predict_frames` reads (what a captured or compiled prediction takes)."""

    def __init__(self, config: GNNConfig | dict, attribute_features: int):
        super().__init__()
        self.config = config if isinstance(config, GNNConfig) else GNNConfig.from_dict(config)
        config = self.config.as_dict()  # what the checkpoint keeps (loading passes it back as a dict)
        self.save_hyperparameters("config", "attribute_features")
        self.model = DetailAwareGNN(attribute_features=attribute_features, ablation=self.config.ablation)
        self.scale = float(self.config.target_scale)

    @classmethod
    def from_data(cls, config: GNNConfig, data) -> GNNModule:
        """The module for ``data`` (a :class:`~training.gnn.data.GNNDataModule`)."""
        return cls(config, data.attribute_features)

    def on_load_checkpoint(self, checkpoint: dict) -> None:
        """Checkpoints written before the fully connected layers were torch_geometric's ``MLP`` load too."""
        from training.gnn.model import upgrade_state_dict

        checkpoint["state_dict"] = upgrade_state_dict(checkpoint["state_dict"])

    # -- prediction

    def predict_frames(self, batch) -> tuple[torch.Tensor, torch.Tensor]:
        """(coarse, detail) garment positions [N, 3] (m) for a batch, as at inference."""
        if self.model.coarse is None:  # single step: straight from the body graph
            d = self.model.forward_detail(batch.x_coarse, batch.edge_index, batch.batch, batch.attributes)
            detail = batch.anchor + d / self.scale
            return detail, detail
        dc = self.model.forward_coarse(batch.x_coarse, batch.edge_index, batch.batch)
        coarse = batch.anchor + dc.float() / self.scale
        x = detail_features(coarse, batch)
        dd = self.model.forward_detail(x, batch.edge_index, batch.batch, batch.attributes)
        return coarse, coarse + dd.float() / self.scale

    def captured_predictor(self, example, warmup: int = 3, parallel_branches: bool = True):
        """:meth:`predict_frames` for batches shaped like ``example`` (same garments, same batch
        size; on a CUDA device), captured once as a CUDA graph and replayed: the returned function
        copies a batch's inputs into the graph's buffers, replays it and returns (coarse, detail),
        tensors the next call overwrites. The model is switched to static shapes
        (:meth:`DetailAwareGNN.set_static_shapes`: the same outputs). A single frame's forward pass
        is ~900 kernel launches, most of its time on the host; a replay is one. With
        ``parallel_branches`` each step's magnitude and direction branches are captured on two
        streams, so the graph runs them side by side (:meth:`DetailAwareGNN.set_side_stream`): on an
        H200 one 3,481-vertex frame in 4.7 ms against 6.2 on one stream, the same in batches of 60
        (docs/bench/gnn_medium_h200x4_20261127/bench_gnn_b60.txt; its test covers both)."""
        if example.x_coarse.device.type != "cuda":
            raise ValueError("a CUDA graph needs the batch on a CUDA device")
        self.eval()
        self.model.set_static_shapes(True)
        names = self.PREDICT_INPUTS
        buffers = {k: getattr(example, k).clone() for k in names}
        inputs = SimpleNamespace(**buffers)  # what predict_frames reads, at fixed addresses
        stream = torch.cuda.Stream()
        stream.wait_stream(torch.cuda.current_stream())
        # the side stream is warmed up too (its cuBLAS workspace is made outside the capture)
        self.model.set_side_stream(torch.cuda.Stream() if parallel_branches else None)
        try:
            with torch.no_grad(), torch.cuda.stream(stream):
                for _ in range(warmup):
                    self.predict_frames(inputs)
            torch.cuda.current_stream().wait_stream(stream)
            graph = torch.cuda.CUDAGraph()
            with torch.no_grad(), torch.cuda.graph(graph):
                out = self.predict_frames(inputs)
        finally:
            self.model.set_side_stream(None)

        def predict(batch):
            for k in names:
                buffers[k].copy_(getattr(batch, k))
            graph.replay()
            return out

        return predict

    def detail_on_truth(self, batch) -> torch.Tensor | None:
        """W_detail as it is trained: on the ground-truth coarse mesh's features, added to it
        ([N, 3], m); None for ``single_step``, which has no coarse mesh. Its error against the
        simulated garment, beside the coarse target's own, measures the detail step alone."""
        if self.model.coarse is None:
            return None
        dd = self.model.forward_detail(batch.x_detail, batch.edge_index, batch.batch, batch.attributes)
        return batch.coarse + dd.float() / self.scale

    # -- steps

    def training_step(self, batch, _):
        mse = torch.nn.functional.mse_loss
        n = batch.num_graphs
        if self.model.coarse is None:
            d = self.model.forward_detail(batch.x_coarse, batch.edge_index, batch.batch, batch.attributes)
            loss = mse(d.float(), (batch.detail - batch.anchor) * self.scale)
            self.log("train/loss", loss, batch_size=n, prog_bar=True, sync_dist=True, on_epoch=True)
            return loss
        dc = self.model.forward_coarse(batch.x_coarse, batch.edge_index, batch.batch)
        dd = self.model.forward_detail(batch.x_detail, batch.edge_index, batch.batch, batch.attributes)
        loss_c = mse(dc.float(), batch.y_coarse * self.scale)
        loss_d = mse(dd.float(), batch.y_detail * self.scale)
        loss = loss_c + loss_d
        self.log_dict({"train/loss": loss, "train/loss_coarse": loss_c, "train/loss_detail": loss_d}, batch_size=n,
                      prog_bar=True, sync_dist=True, on_epoch=True)
        return loss

    def validation_step(self, batch, _):
        coarse, detail = self.predict_frames(batch)
        n = batch.num_nodes
        err_c = 1000 * (coarse - batch.coarse).norm(dim=-1).mean()
        err_d = 1000 * (detail - batch.detail).norm(dim=-1).mean()
        self.log_dict({"val/coarse_mm": err_c, "val/detail_mm": err_d}, batch_size=n, prog_bar=True,
                      sync_dist=True, on_epoch=True, on_step=False)

    def configure_optimizers(self):
        from training.loop import plateau_optimizer

        return plateau_optimizer(self, self.parameters(), self.config, "val/detail_mm")
