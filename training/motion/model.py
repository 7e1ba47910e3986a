"""Paper 001's body-motion generator (§3.2, Fig. 3): a Transformer conditional VAE over T-frame
pose sequences.

A frame is its 24 joint rotations in the 6D representation (``datagen.geometry.rotations``'s
convention: the first two columns of the rotation matrix) and the root translation relative to the
sequence's first frame: 24 x 6 + 3 = 147 numbers.

- Encoder M_E: a label encoder L_E (one-hot -> ``label_hidden``, ReLU -> 2 d_model) gives the class
  tokens μ_cls and σ_cls, put before the linear pose embeddings e_1..e_T; sinusoidal positions;
  N Transformer encoder layers; the first two outputs are μ and log σ² (the rest is discarded).
- Z = μ + σ ε, plus a learnable bias per label.
- Decoder M_D: Z added to the sinusoidal positions of the T frames, N Transformer encoder layers
  (queries, keys and values all from that sequence), a linear map back to 147 numbers a frame.

torch's ``nn.TransformerEncoder`` does the layers; this file adds only what the paper adds.
"""

from __future__ import annotations

import math

import torch
from torch import nn

from datagen.geometry.rotations import matrix_to_rotation_6d, rotation_6d_to_matrix

JOINTS = 24
FRAME_FEATURES = JOINTS * 6 + 3


def sinusoidal_positions(length: int, width: int, device=None) -> torch.Tensor:
    """The Transformer's sinusoidal position code [length, width]."""
    position = torch.arange(length, dtype=torch.float32, device=device)[:, None]
    rate = torch.exp(torch.arange(0, width, 2, dtype=torch.float32, device=device) * (-math.log(10000.0) / width))
    out = torch.zeros(length, width, device=device)
    out[:, 0::2] = torch.sin(position * rate)
    out[:, 1::2] = torch.cos(position * rate[: width // 2])
    return out


def _encoder(d_model: int, heads: int, layers: int, feedforward: int, dropout: float) -> nn.TransformerEncoder:
    layer = nn.TransformerEncoderLayer(d_model, heads, feedforward, dropout, activation="relu", batch_first=True)
    return nn.TransformerEncoder(layer, layers, enable_nested_tensor=False)


def frames_to_features(rotations: torch.Tensor, trans: torch.Tensor) -> torch.Tensor:
    """[B, T, 24, 3, 3] rotation matrices and [B, T, 3] translations -> [B, T, 147] (translation
    relative to each sequence's first frame)."""
    B, T = rotations.shape[:2]
    six = matrix_to_rotation_6d(rotations).reshape(B, T, JOINTS * 6)
    return torch.cat([six, trans - trans[:, :1]], dim=-1)


def features_to_frames(x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """[B, T, 147] -> rotation matrices [B, T, 24, 3, 3] (Gram-Schmidt of the 6D part) and the
    translation [B, T, 3] (from the first frame)."""
    B, T = x.shape[:2]
    rot = rotation_6d_to_matrix(x[..., : JOINTS * 6].reshape(B, T, JOINTS, 6))
    return rot, x[..., JOINTS * 6:]


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
