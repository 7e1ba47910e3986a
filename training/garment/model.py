"""Paper 001's garment regressor (§3.3, Fig. 4, §4.2) for one garment template (one topology).

- Pose encoder P_E: the motion's frames (the motion generator's 147 features: 6D joint rotations
  and the translation from the first frame) through a linear embedding, sinusoidal positions and
  M = 2 Transformer encoder layers (d_model 256, 4 heads, feed-forward 512).
- Garment decoder G_D: the garment's vertex sequence (each frame's V x 3 positions relative to the
  root translation, flattened) through a linear embedding, a BOS element first (T + 1), masked
  self-attention and M = 2 Transformer decoder layers attending to the pose encoding, then a linear
  map back to V x 3. Trained with teacher forcing; greedy decoding at inference (each predicted
  frame is fed back as the next input).
- BOS: an MLP on the sequence's mean pose features (hidden 1024 and 4096, ReLU) that outputs a
  garment frame, pretrained on the sequence's last frame and then frozen (§4.2); ``bos = "zero"``
  is Table 9's ablation (a fixed zero frame).
"""

from __future__ import annotations

import contextlib

import torch
from torch import nn

from training.paper001.frames import FRAME_FEATURES, sinusoidal_positions

BOS_KINDS = ("learned", "zero")


def training_attention(device: torch.device | str):
    """The attention kernels a training step may use on ``device``: on CUDA only the math kernel
    (sequences of 61 frames make its attention matrices tiny; the memory-efficient kernel's
    backward is known to return NaN gradients now and then, pytorch/pytorch#125674 and #178251);
    elsewhere whatever PyTorch picks. Greedy decoding runs without gradients and keeps the fast
    kernels."""
    if torch.device(device).type != "cuda":
        return contextlib.nullcontext()
    from torch.nn.attention import SDPBackend, sdpa_kernel

    return sdpa_kernel([SDPBackend.MATH])


class GarmentRegressor(nn.Module):
    def __init__(self, vertices: int, *, d_model: int = 256, heads: int = 4, layers: int = 2, feedforward: int = 512,
                 dropout: float = 0.1, bos: str = "learned", bos_hidden: tuple[int, int] = (1024, 4096)):
        super().__init__()
        if bos not in BOS_KINDS:
            raise ValueError(f"bos must be one of {BOS_KINDS}, got {bos!r}")
        self.vertices, self.d_model, self.bos_kind = vertices, d_model, bos
        self.pose_embedding = nn.Linear(FRAME_FEATURES, d_model)
        enc = nn.TransformerEncoderLayer(d_model, heads, feedforward, dropout, activation="relu", batch_first=True)
        self.pose_encoder = nn.TransformerEncoder(enc, layers, enable_nested_tensor=False)
        dec = nn.TransformerDecoderLayer(d_model, heads, feedforward, dropout, activation="relu", batch_first=True)
        self.garment_decoder = nn.TransformerDecoder(dec, layers)
        self.garment_in = nn.Linear(vertices * 3, d_model)
        self.garment_out = nn.Linear(d_model, vertices * 3)
        h1, h2 = bos_hidden
        self.bos = nn.Sequential(nn.Linear(FRAME_FEATURES, h1), nn.ReLU(), nn.Linear(h1, h2), nn.ReLU(),
                                 nn.Linear(h2, vertices * 3)) if bos == "learned" else None

    def bos_frame(self, poses: torch.Tensor) -> torch.Tensor:
        """The BOS garment frame [B, V*3] of pose sequences [B, T, 147]."""
        if self.bos is None:
            return poses.new_zeros(len(poses), self.vertices * 3)
        return self.bos(poses.mean(dim=1))

    def encode(self, poses: torch.Tensor) -> torch.Tensor:
        T = poses.shape[1]
        return self.pose_encoder(self.pose_embedding(poses) + sinusoidal_positions(T, self.d_model, poses.device)[None])

    def _decode(self, inputs: torch.Tensor, memory: torch.Tensor) -> torch.Tensor:
        """Outputs [B, n, V*3] for input frames [B, n, V*3] (BOS first), causally masked."""
        n = inputs.shape[1]
        h = self.garment_in(inputs) + sinusoidal_positions(n, self.d_model, inputs.device)[None]
        mask = nn.Transformer.generate_square_subsequent_mask(n, device=inputs.device)
        return self.garment_out(self.garment_decoder(h, memory, tgt_mask=mask, tgt_is_causal=True))

    def forward(self, poses: torch.Tensor, garment: torch.Tensor) -> torch.Tensor:
        """Teacher forcing: frames [B, T, V*3] predicted from the poses and the true previous frames.

        On CUDA its attention runs on PyTorch's plain (math) kernel (:func:`training_attention`):
        the memory-efficient kernel's backward can return NaN gradients from a finite loss
        (pytorch/pytorch#125674, #178251), the regressor's sudden NaN at Adam 1e-3."""
        with training_attention(poses.device):
            memory = self.encode(poses)
            inputs = torch.cat([self.bos_frame(poses)[:, None], garment[:, :-1]], dim=1)
            return self._decode(inputs, memory)

    @torch.no_grad()
    def generate(self, poses: torch.Tensor, graph: bool = False) -> torch.Tensor:
        """Greedy decoding: frames [B, T, V*3] from the poses alone.

        Every step decodes the whole buffer of T + 1 frames (BOS, then what is predicted so far)
        and keeps the output at the newest position: the causal mask makes it depend on the
        frames before it only, so it is what decoding the growing prefix gives (to float rounding),
        with the same shapes at every step. That lets ``graph=True`` on a CUDA device (the model in
        eval mode) capture the T steps once per input shape as one CUDA graph and replay it:
        without it, a sequence costs the host's launch overhead of every step's hundred kernels.
        """
        if graph and poses.is_cuda and not self.training:
            return self._graphed(poses)
        return self._generate_static(poses)

    def _generate_static(self, poses: torch.Tensor) -> torch.Tensor:
        B, T = poses.shape[:2]
        memory = self.encode(poses)
        first = self.bos_frame(poses)
        frames = first.new_zeros(B, T + 1, self.vertices * 3)
        frames[:, 0] = first
        for t in range(T):
            frames[:, t + 1] = self._decode(frames, memory)[:, t]
        return frames[:, 1:]

    def _graphed(self, poses: torch.Tensor) -> torch.Tensor:
        key = (tuple(poses.shape), poses.dtype, poses.device, torch.is_autocast_enabled())
        graphs = self.__dict__.setdefault("_graphs", {})  # not a submodule, not in the state dict
        if key not in graphs:
            static_in = poses.clone()
            side = torch.cuda.Stream(poses.device)
            side.wait_stream(torch.cuda.current_stream(poses.device))
            with torch.cuda.stream(side):  # warm-up outside the capture (cuBLAS handles, allocator)
                self._generate_static(static_in)
            torch.cuda.current_stream(poses.device).wait_stream(side)
            g = torch.cuda.CUDAGraph()
            with torch.cuda.graph(g):
                static_out = self._generate_static(static_in)
            graphs[key] = (g, static_in, static_out)
        g, static_in, static_out = graphs[key]
        static_in.copy_(poses)
        g.replay()
        return static_out.clone()
