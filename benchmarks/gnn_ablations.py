"""Paper 000's Figure 10 and its table from drape's own runs: the validation error of the detailed
prediction per epoch for every ablation switch (one plot), and each run's final figures.

Each run is a ``drape train gnn`` run directory; its curve is ``val/detail_mm`` from the run's CSV
logs (every attempt, so resumed runs are whole). Where the run directory holds ``eval_test.json``
(``drape evaluate RUN --split test --json RUN/eval_test.json``), its errors join the table.

    python -m benchmarks gnn-ablations NAME=RUN [NAME=RUN ...] --out DIR

Writes ``DIR/figure10.png``, ``DIR/figure10.txt`` (the table) and ``DIR/figure10.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from training.loop import THROUGHPUT_KEY, read_metrics


def run_figures(run: Path) -> dict:
    """A run's curve and summary: ``curve`` {epoch: val detail mm}, best and final values, epochs,
    the median training rate, the ablation, and the test errors where evaluated."""
    curve = read_metrics(run, "val/detail_mm")
    coarse = read_metrics(run, "val/coarse_mm")
    # runs written before Lightning's ThroughputMonitor (commit 29fca84) logged "train/samples_per_s"
    rates = list((read_metrics(run, THROUGHPUT_KEY) or read_metrics(run, "train/samples_per_s")).values())
    meta = json.loads((run / "run.json").read_text())
    out = {"run": str(run), "ablation": meta["config"]["ablation"], "seed": meta["config"]["seed"],
           "curve": curve, "coarse_curve": coarse, "epochs": len(curve),
           "best": min(curve.values()) if curve else None,
           "best_epoch": min(curve, key=curve.get) if curve else None,  # counted from 0, as the logs count
           "final": curve[max(curve)] if curve else None,
           "samples_per_s": float(np.median(rates)) if rates else None}
    test = run / "eval_test.json"
    if test.is_file():
        e = json.loads(test.read_text())
        out["test"] = {"all": e["table"]["all"], "by_seen": {c: t["all"] for c, t in e.get("by_seen", {}).items()},
                       "inside_body_share": e.get("inside_body_share"), "parameters": e.get("parameters")}
    return out


def table(figures: dict[str, dict]) -> str:
    lines = ["validation error of the detailed prediction (mm), and the test split where evaluated",
             f"{'run':<22}{'epochs':>7}{'best':>8}{'at':>5}{'final':>8}{'frames/s':>10}"
             f"{'test coarse':>12}{'test detail':>12}{'unseen g+p':>11}{'inside %':>9}{'target→detail':>14}"
             f"{'on target':>10}"]
    for name, f in figures.items():
        t = f.get("test") or {}
        unseen = (t.get("by_seen") or {}).get("unseen garments and poses", {}).get("detail")
        cells = [f"{name:<22}{f['epochs']:>7}",
                 f"{f['best']:>8.2f}{f['best_epoch'] + 1:>5}{f['final']:>8.2f}" if f["best"] is not None else f"{'-':>21}",
                 f"{f['samples_per_s']:>10.1f}" if f["samples_per_s"] else f"{'-':>10}",
                 f"{t['all']['coarse']:>12.2f}{t['all']['detail']:>12.2f}" if t else f"{'-':>24}",
                 f"{unseen:>11.2f}" if unseen is not None else f"{'-':>11}",
                 f"{100 * t['inside_body_share']:>9.2f}" if t.get("inside_body_share") is not None else f"{'-':>9}",
                 # the detail step alone (on the coarse target, as trained), where the evaluation has it
                 f"{t['all']['truth_coarse_to_detail']:>14.2f}" if "truth_coarse_to_detail" in t.get("all", {})
                 else f"{'-':>14}",
                 f"{t['all']['truth_detail']:>10.2f}" if "truth_detail" in t.get("all", {}) else f"{'-':>10}"]
        lines.append("".join(cells))
    return "\n".join(lines)


def plot(figures: dict[str, dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.5), dpi=120)
    for name, f in figures.items():
        if f["curve"]:
            epochs = sorted(f["curve"])
            ax.plot([e + 1 for e in epochs], [f["curve"][e] for e in epochs], label=name,
                    lw=2.2 if f["ablation"] == "full" else 1.3)
    ax.set_xlabel("epoch")
    ax.set_ylabel("validation mean vertex error, detail (mm)")
    ax.set_title("paper 000 Figure 10 on drape's data")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="NAME=RUN_DIRECTORY")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    figures = {}
    for item in args.runs:
        name, sep, run = item.partition("=")
        if not sep:
            ap.error(f"{item!r} is not NAME=RUN_DIRECTORY")
        if not (Path(run) / "run.json").is_file():
            print(f"skipping {name}: {run} is not a run directory", file=sys.stderr)
            continue
        figures[name] = run_figures(Path(run))
    args.out.mkdir(parents=True, exist_ok=True)
    text = table(figures)
    print(text)
    (args.out / "figure10.txt").write_text(text + "\n")
    (args.out / "figure10.json").write_text(json.dumps(figures, indent=1, default=str))
    plot(figures, args.out / "figure10.png")
