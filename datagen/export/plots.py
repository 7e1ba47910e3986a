"""Plots of a whole dataset store (matplotlib): samples per split, garment vertex counts, failures,
the fit attribute and body shapes. A presentation of :func:`datagen.store.info.store_info`, so it
lives with the other exporters, above the store."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from datagen.errors import InputError, require
from datagen.store.layout import read_root_attributes
from schemas.dataset import SPLIT_NAMES, STORE_FORMAT

PLOT_FILES = ("splits.png", "vertex_counts.png", "failures.png", "alpha.png", "betas.png")
"""The files :func:`plot_store_info` writes."""

_SPLIT_COLOURS = {"train": "#4c72b0", "val": "#dd8452", "test": "#55a868"}


def plot_store_info(path: str | Path, out_dir: str | Path) -> list[Path]:
    """Write PNG plots of the complete store at ``path`` into ``out_dir`` (created if missing).

    - ``splits.png``: samples per split, ok and failed stacked;
    - ``vertex_counts.png``: histogram of the garment vertex count V of the samples, per split;
    - ``failures.png``: samples per failure reason (``ok`` included), stacked by split;
    - ``alpha.png``: histograms of the three components of the fit attribute α over the garment
      instances (``garments/alpha``), per split of the samples that use them;
    - ``betas.png``: the shape coefficients β of every body, per component (a dot per body,
      coloured by the split of its samples).

    Each file is written to a temporary name and renamed. Returns the paths written.

    Raises:
        InputError: ``path`` is not a complete store, or ``out_dir`` cannot be written.
    """
    from datagen.body.render import pyplot
    from datagen.files import atomic_output, check_output_dir

    require("matplotlib", "plotting a store", extra="render")
    path = Path(path)
    attrs = read_root_attributes(path)
    if attrs is None or attrs.get("format") != STORE_FORMAT:
        raise InputError(f"{path} is not a drape dataset store (no zarr.json with format '{STORE_FORMAT}')")
    if attrs.get("complete") is not True:
        raise InputError(f"store {path} is not complete (not packed yet): plots need a complete store")
    out_dir = check_output_dir(out_dir, "plot directory")
    from datagen.store.reader import open_store

    store = open_store(path, backend="zarr")
    idx = store.index
    split, failure, garment, body = idx["split"], idx["failure"], idx["garment"], idx["body"]
    names = store.names
    failure_names = list(names["failure_names"])
    plt = pyplot()
    written: list[Path] = []

    def save(fig, name: str) -> None:
        target = out_dir / name
        fig.tight_layout()
        with atomic_output(target) as tmp:
            fig.savefig(tmp, dpi=100, format="png")
        plt.close(fig)
        written.append(target)

    def split_of(rows: np.ndarray, of: np.ndarray, n: int) -> list[str]:
        """The split name of each of n instances (its first sample's split; 'unused' if none)."""
        out = ["unused"] * n
        for i in reversed(range(len(of))):  # the first sample writes last
            out[int(of[i])] = SPLIT_NAMES[int(rows[i])]
        return out

    # samples per split
    fig, ax = plt.subplots(figsize=(5, 3.2))
    ok = [int(((split == k) & (failure == 0)).sum()) for k in range(len(SPLIT_NAMES))]
    bad = [int(((split == k) & (failure != 0)).sum()) for k in range(len(SPLIT_NAMES))]
    ax.bar(SPLIT_NAMES, ok, color="#55a868", label="ok")
    ax.bar(SPLIT_NAMES, bad, bottom=ok, color="#c44e52", label="failed")
    for x, (a, b) in enumerate(zip(ok, bad, strict=True)):
        ax.text(x, a + b, str(a + b), ha="center", va="bottom", fontsize=8)
    ax.set_ylabel("samples")
    ax.set_title(f"{path.name}: {len(split)} samples per split", fontsize=9)
    ax.legend(fontsize=8, frameon=False)
    save(fig, "splits.png")

    # garment vertex counts
    fig, ax = plt.subplots(figsize=(5, 3.2))
    V = idx["vertex_count"]
    bins = np.histogram_bin_edges(V, bins=min(30, max(5, len(np.unique(V))))) if len(V) else 5
    ax.hist([V[split == k] for k in range(len(SPLIT_NAMES))], bins=bins, stacked=True, label=list(SPLIT_NAMES),
            color=[_SPLIT_COLOURS[s] for s in SPLIT_NAMES])
    ax.set_xlabel("garment vertices V per sample")
    ax.set_ylabel("samples")
    ax.set_title("garment vertex counts", fontsize=9)
    ax.legend(fontsize=8, frameon=False)
    save(fig, "vertex_counts.png")

    # failure reasons
    fig, ax = plt.subplots(figsize=(max(5, 1.1 * len(failure_names)), 3.2))
    codes = np.arange(max(len(failure_names), int(failure.max()) + 1 if len(failure) else 0))
    labels = [failure_names[c] if c < len(failure_names) else f"code {c}" for c in codes]
    bottom = np.zeros(len(codes))
    for k, s in enumerate(SPLIT_NAMES):
        counts = np.array([int(((failure == c) & (split == k)).sum()) for c in codes])
        ax.bar(labels, counts, bottom=bottom, color=_SPLIT_COLOURS[s], label=s)
        bottom += counts
    ax.set_ylabel("samples")
    ax.set_title("failure reasons (ok = not failed)", fontsize=9)
    ax.tick_params(axis="x", labelsize=8)
    ax.legend(fontsize=8, frameon=False)
    save(fig, "failures.png")

    # fit attribute alpha per component
    alpha = store.read("garments/alpha")
    g_split = split_of(split, garment, len(alpha))
    fig, axes = plt.subplots(1, alpha.shape[1], figsize=(3.2 * alpha.shape[1], 3.0), squeeze=False)
    for c in range(alpha.shape[1]):
        ax = axes[0, c]
        groups = [s for s in (*SPLIT_NAMES, "unused") if s in g_split]
        data = [alpha[[g for g in range(len(alpha)) if g_split[g] == s], c] for s in groups]
        ax.hist(data, bins=min(20, max(5, len(alpha))), stacked=True, label=groups,
                color=[_SPLIT_COLOURS.get(s, "#999999") for s in groups])
        ax.set_xlabel(f"α{c + 1}")
        ax.set_ylabel("garment instances" if c == 0 else "")
        if c == 0:
            ax.legend(fontsize=7, frameon=False)
    fig.suptitle(f"fit attribute α of {len(alpha)} garment instances", fontsize=9)
    save(fig, "alpha.png")

    # body shapes beta per component
    betas = store.betas()
    b_split = split_of(split, body, len(betas))
    fig, ax = plt.subplots(figsize=(max(5, 0.5 * betas.shape[1] + 2), 3.2))
    rng = np.random.default_rng(0)
    for s in (*SPLIT_NAMES, "unused"):
        rows = [b for b in range(len(betas)) if b_split[b] == s]
        if not rows:
            continue
        x = np.arange(betas.shape[1])[None] + rng.uniform(-0.15, 0.15, (len(rows), 1))
        ax.scatter(np.broadcast_to(x, (len(rows), betas.shape[1])), betas[rows], s=14,
                   color=_SPLIT_COLOURS.get(s, "#999999"), label=s)
    ax.axhline(0, color="0.7", linewidth=0.6)
    ax.set_xticks(np.arange(betas.shape[1]), [f"β{k + 1}" for k in range(betas.shape[1])], fontsize=8)
    ax.set_ylabel("value")
    ax.set_title(f"body shapes: β of {len(betas)} bodies", fontsize=9)
    ax.legend(fontsize=7, frameon=False)
    save(fig, "betas.png")
    return written
