"""Paper 001's motion generator in the training loop: L_B = L_P + L_V^B + λ_KL L_KL (eq. 2).

- L_P: mean squared error of the frame features (6D joint rotations and the root translation from
  the first frame), the pose term of eq. 1.
- L_V^B: mean squared error of the posed body's vertices [m], from the predicted and the true
  rotations through drape's differentiable skinning (``datagen.geometry.skinning``) on the segment's
  own body (its β from the store); ``vertex_loss = false`` drops it (Table 8's ablation).
- L_KL: the KL divergence of N(μ, σ²) from N(0, I), averaged over the batch.
Adam, and the rate times ``lr_factor`` when the validation loss has not fallen for ``lr_patience``
epochs (§4.2).

On one CUDA device the forward and backward pass of a full training batch is one CUDA graph
(``MotionConfig.cuda_graph``): captured at the first full batch, replayed for every later one with
the batch copied into its input tensors; the gradients it writes (into its own memory) are the
parameters' ``.grad`` after each replay, so Lightning's clipping and Adam's step run on them as
after an eager backward. A batch of another size (an epoch's last) runs eagerly and accumulates
into the same tensors (zeroed in place before each step, never set to None).
"""

from __future__ import annotations

import pytorch_lightning as pl
import torch

from datagen.geometry.skinning import blend_skinning, rigid_transforms
from training.motion.model import MotionCVAE, features_to_frames, frames_to_features


class BodyLayer(torch.nn.Module):
    """The store's SMPL-format body as a differentiable layer: rotation matrices [N, 24, 3, 3],
    translations [N, 3] and β [N, S] -> vertices [N, V', 3] (every ``stride``-th vertex)."""

    def __init__(self, body: dict, stride: int = 1):
        super().__init__()
        f32 = torch.float32
        self.parents = [int(p) for p in body["parents"]]
        self.register_buffer("parent_index", torch.as_tensor(self.parents[1:], dtype=torch.long), persistent=False)
        self.register_buffer("v_template", torch.as_tensor(body["v_template"], dtype=f32), persistent=False)
        self.register_buffer("shapedirs", torch.as_tensor(body["shapedirs"], dtype=f32), persistent=False)
        self.register_buffer("J_regressor", torch.as_tensor(body["J_regressor"], dtype=f32), persistent=False)
        keep = torch.arange(0, len(body["v_template"]), stride)
        self.register_buffer("keep", keep, persistent=False)
        self.register_buffer("weights", torch.as_tensor(body["weights"], dtype=f32)[keep], persistent=False)

    def forward(self, rot: torch.Tensor, trans: torch.Tensor, betas: torch.Tensor) -> torch.Tensor:
        S = betas.shape[-1]
        shaped = self.v_template[None] + torch.einsum("vcs,bs->bvc", self.shapedirs[:, :, :S], betas)
        joints = torch.einsum("jv,bvc->bjc", self.J_regressor, shaped)
        _, rel = rigid_transforms(rot, joints, self.parents, self.parent_index)
        return blend_skinning(shaped[:, self.keep], self.weights, rel) + trans[:, None, :]


def pose_features(batch: dict) -> tuple[torch.Tensor, torch.Tensor]:
    """(features [B, T, 147], rotation matrices [B, T, 24, 3, 3]) of a batch's true poses."""
    from datagen.geometry.rotations import axis_angle_to_matrix

    rot = axis_angle_to_matrix(batch["pose"].float())
    return frames_to_features(rot, batch["trans"].float()), rot


class MotionModule(pl.LightningModule):
    """The Lightning module of the motion generator (config: :class:`MotionConfig` as a dict)."""

    def __init__(self, config: dict, labels: int, body: dict, betas):
        super().__init__()
        self.save_hyperparameters(ignore=["body", "betas"])
        self.config = config
        self.model = MotionCVAE(labels, d_model=config["d_model"], heads=config["heads"], layers=config["layers"],
                                feedforward=config["feedforward"], dropout=config["dropout"],
                                label_hidden=config["label_hidden"])
        self.body = BodyLayer(body, config["vertex_stride"])
        self.register_buffer("betas", torch.as_tensor(betas, dtype=torch.float32), persistent=False)
        self._graph = None  # (CUDAGraph, static inputs, static losses, [(parameter, its gradient)]) once captured
        self._graphed_step = False  # whether the current training step's backward ran in the graph

    def vertices(self, rot: torch.Tensor, trans: torch.Tensor, body: torch.Tensor) -> torch.Tensor:
        """Posed vertices [B, T, V', 3] of rotations [B, T, 24, 3, 3], translations [B, T, 3] on the
        bodies ``body`` [B] of the store."""
        B, T = rot.shape[:2]
        betas = self.betas[body].repeat_interleave(T, 0)
        v = self.body(rot.reshape(B * T, 24, 3, 3), trans.reshape(B * T, 3), betas)
        return v.reshape(B, T, -1, 3)

    def losses(self, batch: dict, *, sample: bool = True) -> dict[str, torch.Tensor]:
        x, rot = pose_features(batch)
        label = batch["label"][:, 0].long()
        if sample:
            out, mu, logvar = self.model(x, label)
        else:  # the posterior mean: reconstruction as evaluated
            mu, logvar = self.model.encode(x, label)
            out = self.model.decode(mu, label, x.shape[1])
        out = out.float()
        mse = torch.nn.functional.mse_loss
        pose = mse(out, x)
        kl = -0.5 * torch.mean(torch.sum(1 + logvar - mu.pow(2) - logvar.exp(), dim=1))
        result = {"pose": pose, "kl": kl}
        prot, ptrans = features_to_frames(out)
        body = batch["body"].long()
        v_true = self.vertices(rot, x[..., -3:], body)
        v_pred = self.vertices(prot, ptrans, body)
        result["vertex"] = mse(v_pred, v_true)
        result["vertex_mm"] = 1000 * (v_pred - v_true).norm(dim=-1).mean()
        total = pose + self.config["kl_weight"] * kl
        if self.config["vertex_loss"]:
            total = total + result["vertex"]
        result["loss"] = total
        return result

    def _use_graph(self, batch) -> bool:
        trainer = getattr(self, "_trainer", None)
        return (bool(self.config.get("cuda_graph", True)) and self.device.type == "cuda"
                and (trainer is None or (trainer.world_size == 1 and str(trainer.precision) != "16-mixed"))
                and len(batch["label"]) == self.config["batch_size"])

    def _graph_losses(self, batch: dict) -> dict[str, torch.Tensor]:
        """Forward and backward of ``batch`` by replaying the captured graph (captured first)."""
        if self._graph is None:
            dtype = torch.get_autocast_dtype("cuda") if torch.is_autocast_enabled("cuda") else None
            static = {k: v.clone() for k, v in batch.items()}

            def forward_backward():
                with torch.autocast("cuda", dtype=dtype or torch.float32, enabled=dtype is not None,
                                    cache_enabled=False):
                    r = self.losses(static)
                r["loss"].backward()
                return {k: v.detach() for k, v in r.items()}

            side = torch.cuda.Stream()
            side.wait_stream(torch.cuda.current_stream())
            with torch.cuda.stream(side):  # warm-up passes (cuBLAS workspaces, autograd's caches)
                for _ in range(3):
                    forward_backward()
            torch.cuda.current_stream().wait_stream(side)
            # no gradients before the capture: the backward then allocates them in the graph's own
            # memory and writes (not adds) them at each replay. Gradients that existed before it
            # would be read by the graph after the capture had freed them (their memory reused
            # by other tensors: a Lightning run trained on garbage and logged zeros)
            params = [p for p in self.parameters() if p.requires_grad]
            for p in params:
                p.grad = None
            graph = torch.cuda.CUDAGraph()
            with torch.cuda.graph(graph):
                out = forward_backward()
            self._graph = (graph, static, out, [(p, p.grad) for p in params])
        graph, static, out, grads = self._graph
        for k, v in batch.items():
            static[k].copy_(v)
        graph.replay()
        for p, g in grads:  # the optimiser reads these (whoever set .grad to None since)
            p.grad = g
        return out

    def training_step(self, batch, _):
        self._graphed_step = self._use_graph(batch)
        if self._graphed_step:  # fresh copies: the graph's outputs are overwritten at each replay
            r = {k: v.clone() for k, v in self._graph_losses(batch).items()}
        else:
            r = self.losses(batch)
        n = len(batch["label"])
        for k in ("loss", "pose", "vertex", "kl"):
            self.log(f"train/{k}", r[k], batch_size=n, prog_bar=k == "loss", sync_dist=True, on_epoch=True,
                     on_step=k == "loss")
        return r["loss"]

    def backward(self, loss, *args, **kwargs):
        if not self._graphed_step:  # a replayed step's backward ran in the graph
            super().backward(loss, *args, **kwargs)

    def optimizer_zero_grad(self, epoch, batch_idx, optimizer):
        # Lightning zeroes between the training step and the backward: a replayed step has written
        # its gradients already (and they are written, not added, so nothing needs zeroing); an
        # eager step accumulates into the graph's gradient tensors, zeroed in place
        if not self._graphed_step:
            optimizer.zero_grad(set_to_none=self._graph is None)

    def validation_step(self, batch, _):
        r = self.losses(batch, sample=False)
        n = len(batch["label"])
        self.log("val/loss", r["loss"], batch_size=n, prog_bar=True, sync_dist=True)
        self.log("val/vertex_mm", r["vertex_mm"], batch_size=n, prog_bar=True, sync_dist=True)

    def configure_optimizers(self):
        opt = torch.optim.Adam(self.parameters(), lr=self.config["lr"])
        from training.loop import plateau_patience

        patience = plateau_patience(self, self.config["lr_patience"], self.config.get("lr_patience_steps"))
        sched = torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=self.config["lr_factor"], patience=patience)
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "monitor": "val/loss"}}
