"""Checks of what is staged into a dataset store, against :mod:`schemas.dataset`: one sample
(:func:`check_sample`) or one static group (:func:`check_static`), cast to the schema's dtypes.

Every problem is collected and raised as one :class:`~datagen.errors.InputError` that names each
array or scalar that is missing, unknown, of the wrong dtype or shape, not finite or out of range.
Nothing here writes; :class:`datagen.store.writer.StoreWriter` stages what these return.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from datagen.errors import InputError
from datagen.geometry.positions import encode_positions
from datagen.store.layout import specs_of_group
from datagen.store.validation import Dimensions, pattern_problems, value_problems
from schemas.dataset import ARRAYS, NAME_LISTS, SPLIT_NAMES, STATIC_GROUPS, ArraySpec

__all__ = ["RANGED", "SAMPLE_ARRAYS", "SAMPLE_SCALARS", "check_sample", "check_static", "raise_problems"]

SAMPLE_ARRAYS: dict[str, ArraySpec] = {a.name: a for a in ARRAYS.values()
                                       if a.written_by == "stage_sample" and a.sample_shape != ()}
"""Per-sample arrays handed to :meth:`StoreWriter.stage_sample` (vertex-frame, frame, simulation-frame)."""

SAMPLE_SCALARS: dict[str, ArraySpec] = {a.name: a for a in ARRAYS.values()
                                        if a.written_by == "stage_sample" and a.sample_shape == ()}
"""Per-sample scalars handed to :meth:`StoreWriter.stage_sample`."""

FRAME_ARRAYS = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.table in ("vertex_frame", "frame"))
SIM_ARRAYS = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.table == "sim_frame")
RANGED = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.codes)  # code arrays whose range pack checks
QUANTISED = tuple(n for n, a in SAMPLE_ARRAYS.items() if a.quantum is not None)



def _cast(spec: ArraySpec, value: Any, name: str, where: str, problems: list[str]) -> np.ndarray | None:
    """``value`` as an array of ``spec.dtype``, refusing other kinds (float for int, ...) and out-of-range ints."""
    try:
        arr = np.asarray(value)
    except Exception as exc:  # noqa: BLE001 (anything that is not array-like)
        problems.append(f"{where}: '{name}' is not an array ({exc})")
        return None
    target = np.dtype(spec.dtype)
    kind = arr.dtype.kind
    if spec.quantum is not None:  # positions handed in metres, quantised once the root joints are known
        if kind != "f":
            problems.append(f"{where}: '{name}' has dtype {arr.dtype}; give float positions in metres (the store "
                            f"keeps them as {spec.dtype} steps of {spec.quantum} m)")
            return None
        return arr.astype(np.float64, copy=False)
    if target.kind == "f":
        if kind != "f":
            problems.append(f"{where}: '{name}' has dtype {arr.dtype}; the schema says {spec.dtype} (give floats)")
            return None
        return arr.astype(target, copy=False)
    if not (kind in "iu" or kind == "b" and spec.unit == "bool"):
        problems.append(f"{where}: '{name}' has dtype {arr.dtype}; the schema says {spec.dtype} (give integers)")
        return None
    if arr.size and kind in "iu":
        info = np.iinfo(target)
        lo, hi = int(arr.min()), int(arr.max())
        if lo < info.min or hi > info.max:
            problems.append(f"{where}: '{name}' has values {lo} .. {hi} that do not fit {spec.dtype}")
            return None
    return arr.astype(target, copy=False)


def raise_problems(problems: list[str], hint: str) -> None:
    """Raise one InputError listing ``problems`` (the first ten) and ``hint``, if there are any."""
    if problems:
        shown = "; ".join(problems[:10]) + (f"; and {len(problems) - 10} more" if len(problems) > 10 else "")
        raise InputError(f"{shown}. {hint}")


def check_sample(index: int, arrays: Mapping[str, Any], scalars: Mapping[str, Any], *, sample_count: int,
                 failure_names: list[str] | tuple[str, ...], garment_vertex_counts: np.ndarray | None = None,
                 ) -> tuple[dict[str, np.ndarray], dict[str, int | float], dict]:
    """Check one sample against the schema and cast it to the schema's dtypes.

    Returns:
        (arrays, scalars, dims): arrays as stored (no frame arrays for a failed sample; positions
        quantised), scalars as Python numbers, and the bound sizes ``{"T", "V", "T_sim"}`` (V None
        when unknown).

    Raises:
        InputError: naming every array or scalar that is missing, unknown, of the wrong dtype or
            shape, not finite or out of range.
    """
    where = f"sample {index}"
    problems: list[str] = []
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < sample_count:
        raise InputError(f"sample index {index!r} is not an integer in 0 .. {sample_count - 1} (the store holds "
                         f"{sample_count} samples)")
    unknown = sorted(set(scalars) - set(SAMPLE_SCALARS))
    if unknown:
        problems.append(f"{where}: unknown scalar(s) {unknown}; scalars are {sorted(SAMPLE_SCALARS)}")
    missing = sorted(set(SAMPLE_SCALARS) - set(scalars))
    if missing:
        problems.append(f"{where}: missing scalar(s) {missing}")
    out_scalars: dict[str, int | float] = {}
    for name in [n for n in SAMPLE_SCALARS if n in scalars]:
        spec = SAMPLE_SCALARS[name]
        value = _cast(spec, scalars[name], name, where, problems)
        if value is None:
            continue
        if value.shape != ():
            problems.append(f"{where}: scalar '{name}' has shape {value.shape}; give one number")
            continue
        upper = len(SPLIT_NAMES) if name == "split" else len(failure_names) if name == "failure" else None
        problems += [f"{where}: {p}" for p in value_problems(spec, value, name=name, upper=upper)]
        out_scalars[name] = value.item()
    if "seconds" in out_scalars and out_scalars["seconds"] < 0:
        problems.append(f"{where}: 'seconds' is negative ({out_scalars['seconds']})")
    raise_problems(problems, "Fix the sample's scalars and stage it again.")

    failed = out_scalars["failure"] != 0
    unknown = sorted(set(arrays) - set(SAMPLE_ARRAYS))
    if unknown:
        hint = " (per-sample scalars go in `scalars`)" if set(unknown) & set(SAMPLE_SCALARS) else ""
        problems.append(f"{where}: unknown array(s) {unknown}{hint}; arrays are {sorted(SAMPLE_ARRAYS)}")
    required = SIM_ARRAYS if failed else SIM_ARRAYS + FRAME_ARRAYS
    missing = sorted(set(required) - set(arrays))
    if missing:
        problems.append(f"{where}: missing array(s) {missing}" + ("" if failed else " (a sample with failure = 0 "
                                                                                   "needs every frame array)"))
    dims = Dimensions(where)
    out: dict[str, np.ndarray] = {}
    for name in [n for n in SAMPLE_ARRAYS if n in arrays]:
        spec = SAMPLE_ARRAYS[name]
        arr = _cast(spec, arrays[name], name, where, problems)
        if arr is None or not dims.bind_shape(name, arr.shape, spec.sample_shape):
            continue
        allow = failed and spec.finite == "ok_samples"
        problems += [f"{where}: {p}" for p in value_problems(spec, arr, name=name, allow_nonfinite=allow)]
        out[name] = arr
    problems += dims.problems
    raise_problems(problems, "Fix the sample's arrays to the shapes and dtypes of schemas/dataset.py and stage it again.")

    T = dims.sizes.get("T", 0)
    T_sim = dims.sizes["T_sim"]
    V = dims.sizes.get("V")
    if failed and T:
        problems.append(f"{where} failed (failure = {out_scalars['failure']}) but has {T} recorded frames; a failed "
                        "sample has none: drop its frame arrays (or give them with T = 0)")
    if not failed and T == 0:
        problems.append(f"{where} has failure = 0 but no recorded frames; record at least one frame or give the "
                        "failure code")
    if out_scalars["recorded_from"] + T > T_sim:
        problems.append(f"{where}: recorded_from {out_scalars['recorded_from']} + {T} recorded frames is more than "
                        f"its {T_sim} simulated frames")
    ff = out_scalars["failure_frame"]
    if not failed and ff != -1:
        problems.append(f"{where}: failure_frame is {ff} but failure = 0; use -1")
    if ff >= T_sim:
        problems.append(f"{where}: failure_frame {ff} is past its {T_sim} simulated frames")
    if garment_vertex_counts is not None:
        g = out_scalars["garment"]
        if g >= len(garment_vertex_counts):
            problems.append(f"{where}: garment {g} does not exist (the staged garments/ tables hold "
                            f"{len(garment_vertex_counts)} instances)")
        elif V is not None and T and V != garment_vertex_counts[g]:
            problems.append(f"{where}: its arrays have V = {V} vertices but garment instance {g} has "
                            f"{garment_vertex_counts[g]}")
    raise_problems(problems, "Fix the sample and stage it again.")
    if failed:
        out = {n: a for n, a in out.items() if n in SIM_ARRAYS}
    else:
        for name in QUANTISED:
            out[name] = encode_positions(out[name], out["joints"][:, 0], SAMPLE_ARRAYS[name].quantum)
    return out, out_scalars, {"T": T, "V": V if T else None, "T_sim": T_sim}


def check_static(group: str, arrays: Mapping[str, Any], names: Mapping[str, Any] | None = None
                 ) -> tuple[dict[str, np.ndarray], dict[str, list[str]], dict[str, int]]:
    """Check one static group (``body``, ``bodies``, ``motions``, ``garments``, ``fit``) and its code
    name lists against the schema; returns the cast arrays, the name lists and the bound sizes."""
    if group not in STATIC_GROUPS:
        raise InputError(f"unknown static group {group!r}; static groups are {list(STATIC_GROUPS)}")
    where = f"static group '{group}'"
    specs = {s.name: s for s in specs_of_group(group)}
    problems: list[str] = []
    unknown, missing = sorted(set(arrays) - set(specs)), sorted(set(specs) - set(arrays))
    if unknown:
        problems.append(f"{where}: unknown array(s) {unknown}; its arrays are {sorted(specs)}")
    if missing:
        problems.append(f"{where}: missing array(s) {missing}")
    wanted = {k for k, a in NAME_LISTS.items() if a.staged_with == group}
    names = dict(names or {})
    if set(names) != wanted:
        problems.append(f"{where}: give names={{...}} with exactly the code name lists {sorted(wanted) or '(none)'}"
                        f"; got {sorted(names) or '(none)'}")
    out_names: dict[str, list[str]] = {}
    for key in wanted & set(names):
        value = names[key]
        if not isinstance(value, (list, tuple)) or not all(isinstance(s, str) for s in value):
            problems.append(f"{where}: names['{key}'] must be a list of strings")
        elif len(set(value)) != len(value):
            problems.append(f"{where}: names['{key}'] repeats a name")
        else:
            out_names[key] = list(value)
    dims = Dimensions(where)
    out: dict[str, np.ndarray] = {}
    for name in [n for n in specs if n in arrays]:
        arr = _cast(specs[name], arrays[name], name, where, problems)
        if arr is not None and dims.bind_shape(name, arr.shape, specs[name].shape):
            out[name] = arr
    problems += dims.problems
    raise_problems(problems, "Fix the static arrays to schemas/dataset.py and stage them again.")
    for name, arr in out.items():
        spec = specs[name]
        upper = len(out_names[spec.codes]) if spec.codes in out_names else dims.sizes.get(spec.index_of or "")
        if spec.finite == "fitted" and np.isnan(arr).all():  # no fit attribute in this store
            continue
        if spec.finite == "pattern" and "face_panel" in out:  # NaN on shell garments' rows, finite on patterns'
            pattern = out["face_panel"] >= 0
            if not np.isnan(arr[~pattern]).all():
                problems.append(f"{where}: '{name}' must be NaN on the rows of shell garments (face_panel -1)")
            arr = arr[pattern]
        if spec.unit != "row":
            problems += [f"{where}: {p}" for p in value_problems(spec, arr, name=name, upper=upper)]
    if group == "garments":
        for key, rows in (("vertex_start", "n_garment_vertices"), ("face_start", "n_garment_faces"),
                          ("stitch_start", "n_stitches"), ("design_start", "n_design_bytes")):
            off = out[key]
            if off[0] != 0 or np.any(np.diff(off) < 0) or off[-1] != dims.sizes[rows]:
                problems.append(f"{where}: '{key}' must start at 0, never decrease and end at {dims.sizes[rows]} "
                                f"(the rows of its table); it is {off[:3].tolist()} ... {off[-1]}")
        if not problems:
            Vg = np.repeat(np.diff(out["vertex_start"]), np.diff(out["face_start"]))
            bad = np.flatnonzero(((out["faces"] < 0) | (out["faces"] >= Vg[:, None])).any(1))
            if len(bad):
                g = int(np.searchsorted(out["face_start"], bad[0], side="right") - 1)
                problems.append(f"{where}: 'faces' row {bad[0]} (instance {g}) has {out['faces'][bad[0]].tolist()}; "
                                f"indices must be local to the instance (0 .. {Vg[bad[0]] - 1})")
            problems += pattern_problems(out, where)
    if group == "body" and out["parents"][0] != -1:
        problems.append(f"{where}: 'parents'[0] must be -1 (the root)")
    raise_problems(problems, "Fix the static arrays and stage them again.")
    return out, out_names, {k: v for k, v in dims.sizes.items()}

