"""Paper 001's motion generator in the training loop: L_B = L_P + L_V^B + λ_KL L_KL (eq. 2).

- L_P: mean squared error of the frame features (6D joint rotations and the root translation from
  the first frame), the pose term of eq. 1.
- L_V^B: mean squared error of the posed body's vertices [m], from the predicted and the true
  rotations through drape's differentiable skinning (``datagen.geometry.skinning``) on the segment's
  own body (its β from the store); ``vertex_loss = false`` drops it (Table 8's ablation).
- L_KL: the KL divergence of N(μ, σ²) from N(0, I), summed over the latent dimensions and over the
  batch, as ACTOR computes it (``compute_kl_loss``: ``-0.5 * torch.sum(...)`` over the whole batch;
  paper 001's λ_KL = 1e-5 is ACTOR's, set for that sum) while L_P and L_V^B are means: the
  segments' mean KL times the config's (global) batch size, which is ACTOR's sum for every full
  batch, under DDP too, and weighs an epoch's short last batch, and validation, as a full one.
  Until issue 62 drape averaged it over the batch: 1/20 of ACTOR's weight at the paper's batch.
Adam, and the rate times ``lr_factor`` when the validation loss has not fallen for ``lr_patience``
epochs (§4.2).

On one CUDA device the forward and backward pass of a full training batch is one CUDA graph
(``MotionConfig.cuda_graph``): captured at the first full batch, replayed for every later one with
the batch copied into its input tensors; the gradients it writes (into its own memory) are the
parameters' ``.grad`` after each replay, so Lightning's clipping and Adam's step run on them as
after an eager backward. A batch of another size (an epoch's last) runs eagerly and accumulates
into the same tensors (zeroed in place before each step, never set to None). On the CPU, under DDP
or with "16-mixed" precision (whose loss scaling happens in the backward) every step is eager.

``torch.cuda.make_graphed_callables`` was tried in its place (issue 58) and not kept: on an H200 it
trained 0.70x as fast in bf16-mixed (1,648 against 2,362 segments/s) and 0.95x in float32, and the
gradients it hands to autograd become ``.grad`` itself, so a step that zeroes in place doubles them
(docs/bench/house_refactor_h200/motion_graph_gpu.txt).
"""

from __future__ import annotations

import pytorch_lightning as pl
import torch

from training.motion.config import MotionConfig
from training.motion.model import MotionCVAE
from training.paper001.body import BodyLayer
from training.paper001.frames import features_to_frames, pose_features


def motion_losses(model: MotionCVAE, body: BodyLayer, betas: torch.Tensor, batch: dict, config: MotionConfig, *,
                  sample: bool = True) -> dict[str, torch.Tensor]:
    """L_B and its terms (see the module docstring) of a batch: ``loss``, ``pose``, ``vertex``, ``kl``
    (the mean KL of a segment; the loss weighs ``config.batch_size`` times it) and the mean vertex
    error ``vertex_mm`` (mm); ``sample`` False: through the posterior mean."""
    x, rot = pose_features(batch)
    label = batch["label"][:, 0].long()
    if sample:
        out, mu, logvar = model(x, label)
    else:  # the posterior mean: reconstruction as evaluated
        mu, logvar = model.encode(x, label)
        out = model.decode(mu, label, x.shape[1])
    out = out.float()
    mse = torch.nn.functional.mse_loss
    pose = mse(out, x)
    kl = -0.5 * torch.mean(torch.sum(1 + logvar - mu.pow(2) - logvar.exp(), dim=1))  # per segment
    prot, ptrans = features_to_frames(out)
    b = batch["body"].long()
    v_true = posed_vertices(body, betas, rot, x[..., -3:], b)
    v_pred = posed_vertices(body, betas, prot, ptrans, b)
    vertex = mse(v_pred, v_true)
    total = pose + config.kl_weight * config.batch_size * kl  # ACTOR's sum over a batch
    if config.vertex_loss:
        total = total + vertex
    return {"loss": total, "pose": pose, "vertex": vertex, "kl": kl,
            "vertex_mm": 1000 * (v_pred - v_true).norm(dim=-1).mean()}


def posed_vertices(body: BodyLayer, betas: torch.Tensor, rot: torch.Tensor, trans: torch.Tensor,
                   which: torch.Tensor) -> torch.Tensor:
    """Posed vertices [B, T, V', 3] of rotations [B, T, 24, 3, 3], translations [B, T, 3] on the
    bodies ``which`` [B] (rows of ``betas``)."""
    B, T = rot.shape[:2]
    v = body(rot.reshape(B * T, 24, 3, 3), trans.reshape(B * T, 3), betas[which].repeat_interleave(T, 0))
    return v.reshape(B, T, -1, 3)


class MotionModule(pl.LightningModule):
    """The Lightning module of the motion generator.

    Args:
        config: the run's :class:`~training.motion.config.MotionConfig` (a checkpoint stores it as a
            dict, which loading turns back into the dataclass).
        labels: motion classes.
        body, betas: the store's body model and every body's β [bodies, S] (not saved: loading
            takes them from the store again).
    """

    def __init__(self, config: MotionConfig | dict, labels: int, body: dict, betas):
        super().__init__()
        self.config = config if isinstance(config, MotionConfig) else MotionConfig.from_dict(config)
        config = self.config.as_dict()  # what the checkpoint keeps (loading passes it back as a dict)
        self.save_hyperparameters("config", "labels")
        c = self.config
        self.model = MotionCVAE(labels, d_model=c.d_model, heads=c.heads, layers=c.layers, feedforward=c.feedforward,
                                dropout=c.dropout, label_hidden=c.label_hidden)
        self.body = BodyLayer(body, c.vertex_stride)
        self.register_buffer("betas", torch.as_tensor(betas, dtype=torch.float32), persistent=False)
        self._graph = None  # (CUDAGraph, static inputs, static losses, [(parameter, its gradient)]) once captured
        self._graphed_step = False  # whether the current training step's backward ran in the graph

    @classmethod
    def from_data(cls, config: MotionConfig, data) -> MotionModule:
        """The module for ``data`` (a :class:`~training.motion.data.MotionDataModule`)."""
        data.setup()
        return cls(config, len(data.labels), data.store.body_model(), data.store.betas())

    def vertices(self, rot: torch.Tensor, trans: torch.Tensor, body: torch.Tensor) -> torch.Tensor:
        """Posed vertices [B, T, V', 3] of rotations [B, T, 24, 3, 3], translations [B, T, 3] on the
        bodies ``body`` [B] of the store."""
        return posed_vertices(self.body, self.betas, rot, trans, body)

    def losses(self, batch: dict, *, sample: bool = True) -> dict[str, torch.Tensor]:
        return motion_losses(self.model, self.body, self.betas, batch, self.config, sample=sample)

    def _use_graph(self, batch) -> bool:
        trainer = getattr(self, "_trainer", None)
        return (self.config.cuda_graph and self.device.type == "cuda"
                and (trainer is None or (trainer.world_size == 1 and str(trainer.precision) != "16-mixed"))
                and len(batch["label"]) == self.config.batch_size)

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
        from training.loop import plateau_optimizer

        return plateau_optimizer(self, self.parameters(), self.config, "val/loss",
                                 patience_steps=self.config.lr_patience_steps)
