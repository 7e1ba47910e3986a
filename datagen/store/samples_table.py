"""The per-sample table of a store: one row per sample (scene) with what it is made of and how its
simulation went, computed from the store alone. :func:`sample_table` gives it as a pyarrow
``Table`` (its columns and units are :data:`COLUMNS`); :func:`write_tables` writes it as Parquet, one
file per split under ``STORE/table/`` (``pandas.read_parquet("STORE/table")`` reads them all), which
the dataset card links (:mod:`datagen.store.card`); ``drape info STORE --samples`` prints it.

The design parameters of a pattern garment are the ``parameters`` of its design record (JSON text);
a shell garment has only its type and seed. A body is measured on its rest mesh (the stored body
model shaped by its β, no pose): height, mass (volume at 985 kg/m³) and BMI
(:func:`datagen.geometry.mass.measure`). Strain is ``metric_stretch_max`` (largest principal stretch
minus one over the garment's triangles) and penetration ``metric_penetration_depth`` and
``metric_penetration_count`` over the sample's recorded frames (a failed sample: over the simulated
frames up to the one that failed, non-finite values left out).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from schemas.dataset import SPLIT_NAMES

if TYPE_CHECKING:
    import pyarrow as pa

    from datagen.store.reader import DatasetStore

TABLE_DIR = "table"
"""Directory (in the store's root) of the per-sample table: ``{split}.parquet`` per split with samples."""

COLUMNS: dict[str, tuple[str, str]] = {
    "sample": ("index", "sample id (row of samples/)"),
    "split": ("name", "train, val or test"),
    "garment": ("index", "garment instance (row of garments/)"),
    "garment_family": ("name", "garment type: a shell type, or pattern:PROGRAM / pattern:file"),
    "garment_seed": ("1", "style seed (a pattern program's design seed); (family, seed) is the design"),
    "garment_vertices": ("count", "vertices V of the garment instance"),
    "design_parameters": ("JSON", "a pattern garment's design parameters (its design record's 'parameters'); "
                                  "empty for a shell"),
    "material": ("name", "cloth material"),
    "body": ("index", "body (row of bodies/betas)"),
    "body_name": ("name", "the config's name of the body (a preset or seed:N)"),
    "betas": ("1", "shape coefficients β of the body"),
    "height": ("m", "body height on its rest mesh (vertical extent)"),
    "mass": ("kg", "body mass: rest-mesh volume at 985 kg/m³"),
    "bmi": ("kg/m²", "body mass index, mass / height²"),
    "motion": ("index", "motion (row of motions/)"),
    "motion_label": ("name", "motion label"),
    "motion_seed": ("1", "seed the motion was made with"),
    "frames": ("count", "recorded frames T (0: the scene failed)"),
    "simulated_frames": ("count", "simulated frames T_sim, settle and lead-in included"),
    "passed": ("bool", "true when the scene passed every gate (failure 'ok')"),
    "failure": ("name", "the gate that stopped the scene ('ok' if none)"),
    "failure_frame": ("index", "simulated frame where the scene failed, -1 if it passed"),
    "strain_max": ("1", "largest metric_stretch_max (principal stretch - 1) over the frames"),
    "strain_p99": ("1", "99th percentile of metric_stretch_max over the frames"),
    "penetration_depth_max": ("m", "deepest garment vertex inside the body over the frames"),
    "penetration_count_max": ("count", "most garment vertices inside the body in one frame"),
    "self_intersections_max": ("count", "most cloth edge-triangle crossings in one frame"),
    "seconds": ("s", "simulation wall time spent on the scene"),
}
"""Columns of the per-sample table: name -> (unit, meaning)."""


def body_measurements(store: DatasetStore) -> list[dict[str, float]]:
    """Height [m], mass [kg] and BMI of every body of ``store``, on its rest mesh."""
    from datagen.features import body_shape
    from datagen.geometry.mass import measure

    body = store.body_model()
    return [measure(body_shape(body, b).shaped, body["faces"]) for b in store.betas()]


def _metric_rows(store: DatasetStore) -> dict[str, np.ndarray]:
    """The sim-frame metrics of every sample's frames that count: the recorded ones of a passed sample,
    those up to the failure of a failed one. Returns per-metric arrays and ``owner`` (sample per row)."""
    idx = store.index
    ss, fs = idx["sim_frame_start"], idx["frame_start"]
    keep = np.zeros(int(ss[-1]), bool)
    owner = np.repeat(np.arange(len(ss) - 1), np.diff(ss))
    for i in range(len(ss) - 1):
        T = int(fs[i + 1] - fs[i])
        if T:
            a = int(ss[i] + idx["recorded_from"][i])
            keep[a:a + T] = True
        else:
            f = int(idx["failure_frame"][i])
            keep[ss[i]:ss[i] + (f + 1 if f >= 0 else ss[i + 1] - ss[i])] = True
    names = ("metric_stretch_max", "metric_penetration_depth", "metric_penetration_count", "metric_self_intersections")
    out = {n: store.read(f"sim_frames/{n}")[keep] for n in names}
    out["owner"] = owner[keep]
    return out


def _per_sample(values: np.ndarray, owner: np.ndarray, n: int, how) -> np.ndarray:
    out = np.full(n, np.nan)
    finite = np.isfinite(values)
    order = np.argsort(owner[finite], kind="stable")
    v, o = values[finite][order], owner[finite][order]
    cuts = np.searchsorted(o, np.arange(n + 1))
    for i in range(n):
        if cuts[i + 1] > cuts[i]:
            out[i] = how(v[cuts[i]:cuts[i + 1]])
    return out


def sample_table(store: DatasetStore, measurements: list[dict[str, float]] | None = None) -> pa.Table:
    """The per-sample table of ``store`` (columns :data:`COLUMNS`, in that order; the schema's metadata
    carries each column's unit and meaning). ``measurements``: :func:`body_measurements`, if made already."""
    import pyarrow as pa

    idx = store.index
    n = store.sample_count
    names = store.names
    garments = store.group("garments")
    motions = {k: store.read(f"motions/{k}") for k in ("label", "seed")}
    betas = store.betas()
    measurements = body_measurements(store) if measurements is None else measurements
    g, b, m = idx["garment"], idx["body"], idx["motion"]
    designs = []
    for k in range(len(garments["type"])):
        raw = bytes(garments["design"][garments["design_start"][k]:garments["design_start"][k + 1]])
        designs.append(json.dumps(json.loads(raw)["parameters"], sort_keys=True) if raw else "")
    metrics = _metric_rows(store)
    own = metrics["owner"]
    T = np.diff(idx["frame_start"])
    columns = {
        "sample": np.arange(n, dtype=np.int64),
        "split": [SPLIT_NAMES[s] for s in idx["split"]],
        "garment": g.astype(np.int64),
        "garment_family": [names["garment_type_names"][garments["type"][k]] for k in g],
        "garment_seed": garments["seed"][g].astype(np.int64),
        "garment_vertices": np.diff(garments["vertex_start"])[g].astype(np.int64),
        "design_parameters": [designs[k] for k in g],
        "material": [names["material_names"][garments["material"][k]] for k in g],
        "body": b.astype(np.int64),
        "body_name": [names["body_names"][k] for k in b],
        "betas": pa.array([betas[k].tolist() for k in b], type=pa.list_(pa.field("element", pa.float32()))),
        "height": [measurements[k]["height_m"] for k in b],
        "mass": [measurements[k]["mass_kg"] for k in b],
        "bmi": [measurements[k]["bmi"] for k in b],
        "motion": m.astype(np.int64),
        "motion_label": [names["label_names"][motions["label"][k]] if motions["label"][k] >= 0 else "unlabelled"
                         for k in m],
        "motion_seed": motions["seed"][m].astype(np.int64),
        "frames": T.astype(np.int64),
        "simulated_frames": np.diff(idx["sim_frame_start"]).astype(np.int64),
        "passed": idx["failure"] == 0,
        "failure": [names["failure_names"][f] for f in idx["failure"]],
        "failure_frame": idx["failure_frame"].astype(np.int64),
        "strain_max": _per_sample(metrics["metric_stretch_max"], own, n, np.max),
        "strain_p99": _per_sample(metrics["metric_stretch_max"], own, n, lambda v: np.percentile(v, 99)),
        "penetration_depth_max": _per_sample(metrics["metric_penetration_depth"], own, n, np.max),
        "penetration_count_max": _per_sample(metrics["metric_penetration_count"].astype(np.float64), own, n,
                                             np.max),
        "self_intersections_max": _per_sample(metrics["metric_self_intersections"].astype(np.float64), own, n,
                                              np.max),
        "seconds": idx["seconds"].astype(np.float64),
    }
    for key in ("penetration_count_max", "self_intersections_max"):  # counts: -1 where no frame was finite
        columns[key] = np.nan_to_num(columns[key], nan=-1).astype(np.int64)
    fields = [pa.field(k, pa.array(v).type if not isinstance(v, pa.Array) else v.type,
                       metadata={"unit": COLUMNS[k][0], "doc": COLUMNS[k][1]}) for k, v in columns.items()]
    return pa.table(list(columns.values()), schema=pa.schema(fields, metadata={"drape": "per-sample table"}))


def write_tables(table: pa.Table, directory: Path) -> list[Path]:
    """Write ``table`` as ``{split}.parquet`` per split that has samples into ``directory`` (each to a
    temporary name, then renamed); returns the files written."""
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    from datagen.store.layout import unique_temporary

    directory.mkdir(parents=True, exist_ok=True)
    out = []
    for split in SPLIT_NAMES:
        part = table.filter(pc.equal(table["split"], split))
        target = directory / f"{split}.parquet"
        if not len(part):
            target.unlink(missing_ok=True)
            continue
        tmp = unique_temporary(directory, target.name)
        pq.write_table(part, tmp)
        tmp.replace(target)
        out.append(target)
    return out


def read_tables(directory: Path) -> pa.Table | None:
    """The per-sample table written by :func:`write_tables` (splits in order), or None without one."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    parts = [pq.read_table(directory / f"{s}.parquet") for s in SPLIT_NAMES if (directory / f"{s}.parquet").is_file()]
    return pa.concat_tables(parts).sort_by("sample") if parts else None


def format_table(table: pa.Table) -> str:
    """The per-sample table as plain text (one line per sample; β and design parameters left out)."""
    shown = [c for c in COLUMNS if c not in ("betas", "design_parameters")]
    rows = [[_cell(v) for v in table[c].to_pylist()] for c in shown]
    widths = [max(len(c), *(len(x) for x in col)) if col else len(c) for c, col in zip(shown, rows, strict=True)]
    lines = ["  ".join(c.rjust(w) for c, w in zip(shown, widths, strict=True))]
    for r in range(table.num_rows):
        lines.append("  ".join(rows[k][r].rjust(widths[k]) for k in range(len(shown))))
    return "\n".join(lines)


def _cell(v) -> str:
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "-" if v != v else f"{v:.4g}"
    return str(v)
