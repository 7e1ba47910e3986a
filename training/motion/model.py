"""Paper 001's body-motion generator (§3.2, Fig. 3): a Transformer conditional VAE over T-frame
pose sequences.

A frame is the 147 numbers of :mod:`training.paper001.frames` (6D joint rotations and the root
translation from the first frame).

- Encoder M_E: a label encoder L_E (one-hot -> ``label_hidden``, ReLU -> 2 d_model) gives the class
  tokens μ_cls and σ_cls, put before the linear pose embeddings e_1..e_T; sinusoidal positions;
  N Transformer encoder layers; the first two outputs are μ and log σ² (the rest is discarded).
- Z = μ + σ ε, plus a learnable bias per label.
- Decoder M_D: Z added to the sinusoidal positions of the T frames, N Transformer encoder layers
  (queries, keys and values all from that sequence), a linear map back to 147 numbers a frame.

torch's ``nn.TransformerEncoder`` does the layers; this file adds only what the paper adds.
"""

from __future__ import annotations

import torch
from torch import nn

from training.paper001.frames import FRAME_FEATURES, sinusoidal_positions


def _encoder(d_model: int, heads: int, layers: int, feedforward: int, dropout: float) -> nn.TransformerEncoder:
    layer = nn.TransformerEncoderLayer(d_model, heads, feedforward, dropout, activation="relu", batch_first=True)
    return nn.TransformerEncoder(layer, layers, enable_nested_tensor=False)


class MotionCVAE(nn.Module):
    """The generator of paper 001 §3.2 for ``labels`` motion classes."""

    def __init__(self, labels: int, *, d_model: int = 256, heads: int = 4, layers: int = 8, feedforward: int = 1024,
                 dropout: float = 0.1, label_hidden: int = 128):
        super().__init__()
        self.labels, self.d_model = labels, d_model
        self.label_encoder = nn.Sequential(nn.Linear(labels, label_hidden), nn.ReLU(), nn.Linear(label_hidden, 2 * d_model))
        self.pose_embedding = nn.Linear(FRAME_FEATURES, d_model)
        self.encoder = _encoder(d_model, heads, layers, feedforward, dropout)
        self.label_bias = nn.Parameter(torch.zeros(labels, d_model))
        self.decoder = _encoder(d_model, heads, layers, feedforward, dropout)
        self.output = nn.Linear(d_model, FRAME_FEATURES)

    def encode(self, x: torch.Tensor, label: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(μ, log σ²) [B, d_model] of sequences ``x`` [B, T, 147] of class ``label`` [B]."""
        B, T, _ = x.shape
        # one-hot by a scatter: F.one_hot checks its classes on the host, which a CUDA graph cannot hold
        one_hot = torch.zeros(B, self.labels, dtype=x.dtype, device=x.device).scatter_(1, label[:, None], 1.0)
        tokens = self.label_encoder(one_hot).reshape(B, 2, self.d_model)
        h = torch.cat([tokens, self.pose_embedding(x)], dim=1)
        h = h + sinusoidal_positions(T + 2, self.d_model, x.device)[None]
        out = self.encoder(h)
        return out[:, 0], out[:, 1]

    def decode(self, z: torch.Tensor, label: torch.Tensor, frames: int) -> torch.Tensor:
        """Sequences [B, frames, 147] from latents ``z`` [B, d_model] (the label's bias is added here)."""
        z = z + self.label_bias[label]
        h = sinusoidal_positions(frames, self.d_model, z.device)[None] + z[:, None, :]
        return self.output(self.decoder(h))

    def forward(self, x: torch.Tensor, label: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Reconstruction [B, T, 147] through a sampled Z (training), with μ and log σ²."""
        mu, logvar = self.encode(x, label)
        z = mu + torch.exp(0.5 * logvar) * torch.randn_like(mu)
        return self.decode(z, label, x.shape[1]), mu, logvar

    @torch.no_grad()
    def sample(self, label: torch.Tensor, frames: int, generator: torch.Generator | None = None,
               latent: tuple[torch.Tensor, torch.Tensor] | None = None) -> torch.Tensor:
        """New sequences [B, frames, 147] of classes ``label`` [B], plus the label's bias. ``latent``
        None: Z ~ N(0, I), the paper's prior; ``(mean, std)`` [labels, d_model]: Z ~ N(mean[label],
        std[label]²), a per-label Gaussian fitted to the training posteriors (``run.fit_latents``)."""
        eps = torch.randn(len(label), self.d_model, generator=generator, device="cpu").to(self.label_bias.device)
        if latent is None:
            z = eps
        else:
            mean, std = (t.to(eps.device, eps.dtype) for t in latent)
            z = mean[label] + std[label] * eps
        return self.decode(z, label, frames)
