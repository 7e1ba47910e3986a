"""Paper 000's detail-aware graph network (§4.2-4.4, §5.1), with the ablations of §5.3 as switches.

- :class:`GATBlock`: a graph-attention block with the self-reinforced stream [LSK20]: torch_geometric's
  ``GATConv`` (4 heads, concatenated) aggregates the neighbours, a linear map carries the node's own
  features; the two streams are concatenated (half the width each: §5.1's first block is 256 = 128
  self + 4 x 32 attention).
- :class:`CoarseNet` (W_coarse, eq. 5-6): one 256-wide block with Tanh, then a magnitude and a
  direction branch of three blocks [512, 512, 256] and fully connected layers [256, 128, 1] (ReLU,
  the last |x|: see :class:`Magnitude`) and [256, 128, 3] (Tanh, then normalised to unit
  length); Δ = |Δ| ⊙ δ (eq. 4).
- :class:`ParserNet` (W_parser): (α, β, θ) through fully connected layers [256, 512, 1024], ReLU.
- :class:`DetailNet` (W_detail, eq. 7-9): a 1024-wide block multiplied element-wise by the parser's
  encoding, then two branches of four blocks [256, 256, 128, 96] with edge-contraction pooling
  (torch_geometric's ``EdgePooling``, Diehl 2019, with a matching that runs on the GPU:
  :mod:`training.gnn.pooling`; about half the nodes) after the second block and unpooling before
  the fourth, and fully connected layers [128, 64, 1] / [128, 64, 3].

Glorot initialisation for the graph layers (``GATConv``'s own), Kaiming for the others (§5.3).

Ablations (:data:`ABLATIONS`, §5.3; capacities kept comparable by widening what remains):
``no_decomposition`` (one branch predicts Δ directly), ``output_limit`` (one branch, Tanh output
scaled by 5: a bounded Δ), ``no_parser`` (α, β, θ appended to every node instead), ``concat_parser``
(the encoding concatenated instead of multiplied), ``single_step`` (one network from the body graph
straight to the detailed garment), ``no_pooling``.
"""

from __future__ import annotations

import contextlib
import re

import torch
from torch import nn

from training.gnn.config import ABLATIONS

OUTPUT_LIMIT = 5.0
"""Scale of the bounded output of the ``output_limit`` ablation (in the target unit)."""


def _kaiming(layer: nn.Linear) -> nn.Linear:
    nn.init.kaiming_uniform_(layer.weight, nonlinearity="relu")
    nn.init.zeros_(layer.bias)
    return layer


def graph_loops(edge_index: torch.Tensor, num_nodes: int, static: bool) -> torch.Tensor:
    """The graph with one self-loop per node: :func:`with_self_loops`, or with ``static`` (a graph
    that has none, as a mesh's edges and a static pooling's output have) the loops appended, with
    no size that depends on the data."""
    if not static:
        return with_self_loops(edge_index, num_nodes)
    loop = torch.arange(num_nodes, device=edge_index.device)
    return torch.cat([edge_index, torch.stack([loop, loop])], dim=1)


def with_self_loops(edge_index: torch.Tensor, num_nodes: int) -> torch.Tensor:
    """``edge_index`` with its self-loops replaced by one per node, as ``GATConv`` makes it for
    itself by default: done once per graph and level instead of in every block (each time a mask,
    so on a GPU a wait for the device)."""
    from torch_geometric.utils import add_self_loops, remove_self_loops

    return add_self_loops(remove_self_loops(edge_index)[0], num_nodes=num_nodes)[0]


class GATBlock(nn.Module):
    """Graph attention plus the self-reinforced stream: ``[W x_i ‖ GAT(x)_i]``, ``out`` features.
    ``forward`` takes the graph with its self-loops (:func:`with_self_loops`)."""

    def __init__(self, in_channels: int, out_channels: int, heads: int = 4):
        from torch_geometric.nn import GATConv

        super().__init__()
        half = out_channels // 2
        if half % heads or out_channels % 2:
            raise ValueError(f"a GAT block of {out_channels} features needs half of them divisible by {heads} heads")
        self.self_stream = _kaiming(nn.Linear(in_channels, half))
        self.attention = GATConv(in_channels, half // heads, heads=heads, concat=True,  # Glorot inside
                                 add_self_loops=False)

    def forward(self, x: torch.Tensor, loops: torch.Tensor) -> torch.Tensor:
        return torch.cat([self.self_stream(x), self.attention(x, loops)], dim=-1)


def _mlp(sizes: list[int], activation: type[nn.Module], last: nn.Module | None) -> nn.Sequential:
    """torch_geometric's ``MLP`` over ``sizes`` (``activation`` between the layers, none after the
    last, no normalisation), Kaiming-initialised, then ``last`` (an output activation) if given."""
    from torch_geometric.nn import MLP

    with torch.random.fork_rng(devices=[]):  # built without drawing: the draws follow, layer by layer
        mlp = MLP(sizes, act=activation(), norm=None, plain_last=True)
    for lin in mlp.lins:
        # the default draw and then Kaiming's, layer after layer, as torch's Linear layers drew them
        # before: a seed gives the weights it gave before the switch to this MLP
        lin.reset_parameters()
        _kaiming(lin)
    return nn.Sequential(mlp, *([last] if last is not None else []))


LEGACY_MLP_KEY = re.compile(r"^(.*\.(?:head|net))\.(\d+)\.(weight|bias)$")
"""A weight of the fully connected layers as runs before torch_geometric's ``MLP`` stored them
(``head.2.weight``: the second linear layer of an ``nn.Sequential`` that interleaved activations)."""


def upgrade_state_dict(state: dict) -> dict:
    """A state dict of :class:`DetailAwareGNN` from a checkpoint of either layout, in the current one
    (``head.2.weight`` -> ``head.0.lins.1.weight``)."""
    out = {}
    for key, value in state.items():
        m = LEGACY_MLP_KEY.match(key)
        out[f"{m[1]}.0.lins.{int(m[2]) // 2}.{m[3]}" if m else key] = value
    return out


class _Branch(nn.Module):
    """GAT blocks then fully connected layers; optional edge-contraction pooling around the middle."""

    def __init__(self, in_channels: int, widths: list[int], head: list[int], activation: type[nn.Module],
                 last: nn.Module | None, *, pool_after: int | None = None):
        super().__init__()
        self.blocks = nn.ModuleList()
        c = in_channels
        for w in widths:
            self.blocks.append(GATBlock(c, w))
            c = w
        self.act = activation()
        self.pool_after = pool_after
        if pool_after is not None:
            from training.gnn.pooling import FastEdgePooling

            self.pool = FastEdgePooling(widths[pool_after])
        self.head = _mlp([c, *head], activation, last)

    def forward(self, x: torch.Tensor, edge_index: torch.Tensor, batch: torch.Tensor,
                loops: torch.Tensor) -> torch.Tensor:
        """``loops``: ``edge_index`` with its self-loops (:func:`with_self_loops`)."""
        info = None
        e, e_loops = edge_index, loops
        for k, block in enumerate(self.blocks):
            if info is not None and k == len(self.blocks) - 1:  # unpool before the last block
                x, e, batch = self.pool.unpool(x, info)
                e_loops, info = loops, None
            x = self.act(block(x, e_loops))
            if self.pool_after is not None and k == self.pool_after:
                x, e, batch, info = self.pool(x, e, batch)
                e_loops = graph_loops(e, x.size(0), self.pool.static)
        if info is not None:
            x, e, batch = self.pool.unpool(x, info)
        return self.head(x)


ONE_BRANCH_SCALE = 1.5
"""Width of the one-branch ablations' branch over a decomposed branch's: 1.5 gives 0.98x the full
model's parameters (twice the width, as before 2026-11-25, gave 1.45x)."""


class Magnitude(nn.Module):
    """The magnitude's last activation: |x|. Non-negative as ReLU (§5.1) is, with gradient ±1 everywhere.

    §5.1's ReLU: the head's hidden features come out of ReLUs, positive and alike from node to
    node, so its output has about one sign over the whole graph; where that sign turned negative
    (at the start, or while the direction was still random and the MSE asked for |Δ| = 0) the ReLU
    gave 0 with zero gradient at every node, for good (W_detail in every run on `medium`, 2026-11-26).
    Softplus, used instead until 2026-11-27, only moved the trap: early on the MSE pulls the
    magnitude down, Adam's steps (as large for a small gradient as for a big one) carry the
    pre-activation far below zero, and there Softplus's gradient (≈ its value) falls under Adam's
    ε, so the step stops learning just as well (W_detail in five of six decomposed runs on `medium`
    on 4 x H200, docs/bench/gnn_medium_h200x4_20261127; on four grid garments with hard targets in
    six seeds of six, tests/training/test_gnn.py). |x| has no flat tail to fall into: a magnitude
    driven through 0 comes back with the same gradient."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x.abs()


class _Output(nn.Module):
    """Δ from node features: magnitude x unit direction (eq. 4), or one branch for the ablations.
    The magnitude's last activation is :class:`Magnitude` (|x|) where §5.1 has ReLU."""

    side_stream = None
    """A CUDA stream for the direction branch, set while a prediction is captured as a CUDA graph
    (:meth:`DetailAwareGNN.set_side_stream`): the two branches are independent, so the graph runs
    them side by side. A single frame's kernels are too small to fill the GPU, and one after
    another their launches, not their arithmetic, take the time."""

    def __init__(self, in_channels: int, widths: list[int], head: list[int], *, mode: str,
                 pool_after: int | None = None):
        super().__init__()
        self.mode = mode
        if mode == "decomposed":
            self.magnitude = _Branch(in_channels, widths, [*head, 1], nn.ReLU, Magnitude(), pool_after=pool_after)
            self.direction = _Branch(in_channels, widths, [*head, 3], nn.Tanh, nn.Tanh(), pool_after=pool_after)
        else:  # one branch, wider by ONE_BRANCH_SCALE: about the two branches' parameters
            wide = [8 * int(round(w * ONE_BRANCH_SCALE / 8)) for w in widths]  # GAT: 4 heads on each half
            last = nn.Tanh() if mode == "limited" else None
            self.direct = _Branch(in_channels, wide, [*[int(round(h * ONE_BRANCH_SCALE)) for h in head], 3], nn.ReLU,
                                  last, pool_after=pool_after)

    def forward(self, x, edge_index, batch, loops) -> torch.Tensor:
        if self.mode == "decomposed":
            side = self.side_stream
            main = None if side is None else torch.cuda.current_stream()
            if side is not None:
                side.wait_stream(main)
            with torch.cuda.stream(side) if side is not None else contextlib.nullcontext():
                d = nn.functional.normalize(self.direction(x, edge_index, batch, loops), dim=-1)
            m = self.magnitude(x, edge_index, batch, loops)
            if side is not None:
                main.wait_stream(side)
                if not torch.cuda.is_current_stream_capturing():  # eagerly (the warm-up): keep d's memory
                    d.record_stream(main)                          # from the side stream until main is done
            return m * d
        out = self.direct(x, edge_index, batch, loops)
        return OUTPUT_LIMIT * out if self.mode == "limited" else out


def _mode(ablation: str) -> str:
    return {"no_decomposition": "direct", "output_limit": "limited"}.get(ablation, "decomposed")


class CoarseNet(nn.Module):
    """W_coarse: body graph features [n^{b'}, p^{b'}, α₁] (R^7) -> Δ_coarse [N, 3]."""

    def __init__(self, in_channels: int = 7, ablation: str = "full"):
        super().__init__()
        self.first = GATBlock(in_channels, 256)
        self.out = _Output(256, [512, 512, 256], [256, 128], mode=_mode(ablation))

    static = False

    def forward(self, x, edge_index, batch) -> torch.Tensor:
        loops = graph_loops(edge_index, x.size(0), self.static)
        return self.out(torch.tanh(self.first(x, loops)), edge_index, batch, loops)


class ParserNet(nn.Module):
    """W_parser: multi-source attributes (α, β, θ) -> a detail-aware encoding [B, 1024]."""

    def __init__(self, in_features: int, width: int = 1024):
        super().__init__()
        self.net = _mlp([in_features, 256, 512, width], nn.ReLU, nn.ReLU())

    def forward(self, attributes: torch.Tensor) -> torch.Tensor:
        return self.net(attributes)


class DetailNet(nn.Module):
    """W_detail: garment graph features [n, p, x] (R^30), infused with W_parser's encoding -> Δ_detail."""

    def __init__(self, in_channels: int, attribute_features: int, ablation: str = "full", width: int = 1024,
                 branch_scale: float = 1.0):
        super().__init__()
        self.ablation = ablation
        node_in = in_channels + (attribute_features if ablation in ("no_parser", "single_step") else 0)
        self.first = GATBlock(node_in, width)
        self.parser = ParserNet(attribute_features, width) if ablation not in ("no_parser", "single_step") else None
        branch_in = 2 * width if ablation == "concat_parser" else width
        pool = None if ablation == "no_pooling" else 1
        widths = [8 * int(round(w * branch_scale / 8)) for w in (256, 256, 128, 96)]  # GAT: 4 heads on each half
        self.out = _Output(branch_in, widths, [int(round(128 * branch_scale)), int(round(64 * branch_scale))],
                           mode=_mode(ablation), pool_after=pool)

    static = False

    def forward(self, x, edge_index, batch, attributes) -> torch.Tensor:
        per_node = attributes[batch]
        loops = graph_loops(edge_index, x.size(0), self.static)
        if self.parser is None:
            h = torch.tanh(self.first(torch.cat([x, per_node], dim=-1), loops))
        else:
            h = torch.tanh(self.first(x, loops))
            code = self.parser(attributes)[batch]
            h = torch.cat([h, code], dim=-1) if self.ablation == "concat_parser" else h * code  # eq. 7
        return self.out(h, edge_index, batch, loops)


SINGLE_STEP_SCALE = 2.3
"""How much wider ``single_step``'s branches are than the detail step's: 2.3 gives 2.72 M parameters against the
full model's 2.76 M (1.0 gave 0.89 M)."""


class DetailAwareGNN(nn.Module):
    """Both steps of paper 000: Δ_coarse from the body graph, Δ_detail from the garment graph.

    ``single_step`` replaces them with one DetailNet from the body graph's features (and the
    attributes) straight to ``detail - anchor``.
    """

    def __init__(self, *, coarse_features: int = 7, detail_features: int = 30, attribute_features: int = 85,
                 ablation: str = "full"):
        super().__init__()
        if ablation not in ABLATIONS:
            raise ValueError(f"unknown ablation {ablation!r}; ablations are {list(ABLATIONS)}")
        self.ablation = ablation
        if ablation == "single_step":
            self.coarse = None
            # wider branches, so that the one network has about the two steps' parameters (§5.3 compares
            # architectures, not sizes)
            self.detail = DetailNet(coarse_features, attribute_features, ablation, branch_scale=SINGLE_STEP_SCALE)
        else:
            self.coarse = CoarseNet(coarse_features, ablation if ablation in ("no_decomposition", "output_limit")
                                    else "full")
            self.detail = DetailNet(detail_features, attribute_features, ablation)

    def set_static_shapes(self, static: bool = True) -> DetailAwareGNN:
        """Switch every pooling to its static form (:class:`~training.gnn.pooling.FastEdgePooling`)
        and the graphs' self-loops to appending: the same outputs, with no tensor whose size depends
        on the data, so inference can be captured as a CUDA graph. The input graph must have no
        self-loops (a mesh's edges have none)."""
        from training.gnn.pooling import FastEdgePooling

        for m in self.modules():
            if isinstance(m, (FastEdgePooling, CoarseNet, DetailNet)):
                m.static = static
        return self

    def set_side_stream(self, stream) -> DetailAwareGNN:
        """Run each step's direction branch on ``stream`` (a ``torch.cuda.Stream``; None: on the
        current stream), beside its magnitude branch. Meant for capturing a CUDA graph
        (:meth:`~training.gnn.module.GNNModule.captured_predictor`), where the graph keeps the
        two streams' order and memory; eagerly (the capture's warm-up) the direction's output is
        kept for the main stream with ``record_stream``."""
        for m in self.modules():
            if isinstance(m, _Output):
                m.side_stream = stream
        return self

    def forward_coarse(self, x, edge_index, batch) -> torch.Tensor:
        return self.coarse(x, edge_index, batch)

    def forward_detail(self, x, edge_index, batch, attributes) -> torch.Tensor:
        return self.detail(x, edge_index, batch, attributes)
