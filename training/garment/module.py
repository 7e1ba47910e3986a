"""Paper 001's garment regressor in the training loop: L_G = L_V^G + λ_Lap L_Lap (eq. 3).

L_V^G is the mean squared error of the garment's vertices (relative to the root translation, or with
``relative_to: skinned`` to the template skinned to the pose; in ``target_scale`` units); L_Lap that
of their uniform mesh Laplacians (each vertex minus the mean of its neighbours on the template),
which keeps wrinkles. Training uses teacher forcing; validation
decodes greedily, as inference does, and reports the mean vertex error in mm.
"""

from __future__ import annotations

import numpy as np
import pytorch_lightning as pl
import torch

from training.garment.config import GarmentConfig
from training.garment.model import GarmentRegressor


def template_edges(faces: np.ndarray) -> np.ndarray:
    from training.paper001.sted import mesh_edges

    return mesh_edges(faces)


def uniform_laplacian(x: torch.Tensor, edges: torch.Tensor, degree: torch.Tensor) -> torch.Tensor:
    """x_i - mean of x over i's neighbours, for x [..., V, 3]."""
    a, b = edges[:, 0], edges[:, 1]
    s = torch.zeros_like(x).index_add(-2, a, x[..., b, :]).index_add(-2, b, x[..., a, :])
    return x - s / degree[:, None]


class GarmentModule(pl.LightningModule):
    """The Lightning module of the garment regressor.

    Args:
        config: the run's :class:`~training.garment.config.GarmentConfig` (a checkpoint stores it as a
            dict, which loading turns back into the dataclass; runs from before ``relative_to``
            existed load as ``translation``).
        vertices: the template's vertex count.
        faces: the template's triangles [F, 3] (not saved: loading takes them from the store again).
    """

    def __init__(self, config: GarmentConfig | dict, vertices: int, faces):
        super().__init__()
        self.config = config if isinstance(config, GarmentConfig) else GarmentConfig.from_dict(config)
        config = self.config.as_dict()  # what the checkpoint keeps (loading passes it back as a dict)
        self.save_hyperparameters("config", "vertices")
        c = self.config
        self.model = GarmentRegressor(vertices, d_model=c.d_model, heads=c.heads, layers=c.layers,
                                      feedforward=c.feedforward, dropout=c.dropout, bos=c.bos,
                                      bos_hidden=tuple(c.bos_hidden))
        edges = torch.as_tensor(template_edges(np.asarray(faces)))
        degree = torch.zeros(vertices).index_add(0, edges[:, 0], torch.ones(len(edges)))
        degree = degree.index_add(0, edges[:, 1], torch.ones(len(edges))).clamp(min=1)
        self.register_buffer("edges", edges, persistent=False)
        self.register_buffer("degree", degree, persistent=False)
        self.scale = float(c.target_scale)
        self.relative_to = c.relative_to
        self.binding = None  # the template on its body (DatasetStore.binding), for the skinned frame
        if self.model.bos is not None:  # pretrained before fitting, then frozen (§4.2)
            for p in self.model.bos.parameters():
                p.requires_grad_(False)

    @classmethod
    def from_data(cls, config: GarmentConfig, data) -> GarmentModule:
        """The module for ``data`` (a :class:`~training.garment.data.GarmentDataModule`), with the
        template's binding for the skinned frame (derived on the training device)."""
        data.setup()
        module = cls(config, len(data.template["rest_vertices"]), data.template["faces"])
        module.binding = data.store.binding(data.template_index)
        return module

    def base(self, batch) -> torch.Tensor:
        """What the regressor's frames are relative to, [B, T, V or 1, 3] m: the root translation
        (paper 001) or the template skinned to each frame's pose (``relative_to: skinned``): the
        batch's ``skin`` where it has one (evaluation reads it for the baseline), else derived here
        from ``pose`` by the store's feature function on the batch's device (:meth:`skinned`)."""
        base = batch["trans"].float()[:, :, None]
        if self.relative_to != "skinned":
            return base
        skin = batch.get("skin")
        return base + (self.skinned(batch["pose"]) if skin is None else skin.float())

    def skinned(self, pose: torch.Tensor) -> torch.Tensor:
        """The template skinned to axis-angle poses [B, T, J, 3], without the translation: [B, T, V, 3]
        (the store's derived ``skin``), on the poses' device; needs :attr:`binding` (the template
        on its body, ``DatasetStore.binding``), which training and loading set."""
        if self.binding is None:
            raise RuntimeError("the skinned frame needs the template's binding: set module.binding = "
                               "store.binding(template) (train_garment and load_garment do)")
        from datagen.features import derive

        B, T = pose.shape[:2]
        skin = derive(self.binding, ["skin"], pose=pose.float().reshape(B * T, *pose.shape[2:]))["skin"]
        return skin.reshape(B, T, -1, 3)

    def garment(self, out: torch.Tensor, base: torch.Tensor) -> torch.Tensor:
        """Garment positions [B, T, V, 3] m of the regressor's output frames [B, T, V*3] on ``base``."""
        B, T = out.shape[:2]
        return out.float().reshape(B, T, -1, 3) / self.scale + base

    def targets(self, batch) -> tuple[torch.Tensor, torch.Tensor]:
        """(pose features [B, T, 147], garment frames [B, T, V*3] relative to :meth:`base`, scaled)."""
        from training.paper001.frames import pose_features

        x, _ = pose_features(batch)
        g = (batch["detail"].float() - self.base(batch)) * self.scale
        return x, g.flatten(2)

    def losses(self, pred: torch.Tensor, true: torch.Tensor) -> dict[str, torch.Tensor]:
        B, T = true.shape[:2]
        p, t = pred.float().reshape(B, T, -1, 3), true.reshape(B, T, -1, 3)
        vertex = torch.nn.functional.mse_loss(p, t)
        lap = torch.nn.functional.mse_loss(uniform_laplacian(p, self.edges, self.degree),
                                           uniform_laplacian(t, self.edges, self.degree))
        return {"vertex": vertex, "laplacian": lap, "loss": vertex + self.config.laplacian_weight * lap,
                "vertex_mm": 1000 / self.scale * (p - t).norm(dim=-1).mean()}

    def training_step(self, batch, _):
        x, g = self.targets(batch)
        r = self.losses(self.model(x, g), g)
        n = len(x)
        for k in ("loss", "vertex", "laplacian"):
            self.log(f"train/{k}", r[k], batch_size=n, prog_bar=k == "loss", sync_dist=True, on_epoch=True,
                     on_step=k == "loss")
        return r["loss"]

    def validation_step(self, batch, _):
        x, g = self.targets(batch)
        r = self.losses(self.model.generate(x), g)
        n = len(x)
        self.log("val/loss", r["loss"], batch_size=n, prog_bar=True, sync_dist=True)
        self.log("val/vertex_mm", r["vertex_mm"], batch_size=n, prog_bar=True, sync_dist=True)

    def configure_optimizers(self):
        from training.loop import plateau_optimizer

        return plateau_optimizer(self, [p for p in self.parameters() if p.requires_grad], self.config, "val/loss",
                                 patience_steps=self.config.lr_patience_steps)
