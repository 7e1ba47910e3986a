"""Check a packed store against :mod:`schemas.dataset`: :func:`validate` lists every problem.

Also home of the checks the writer runs on what it is handed (:class:`Dimensions`,
:func:`value_problems`), so that staging and validation apply one set of rules.
"""

from __future__ import annotations

import json
import logging
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from schemas.dataset import (
    ARRAYS,
    DATASET_SCHEMA_VERSION,
    FIXED_DIMENSIONS,
    ROOT_ATTRIBUTES,
    SPLIT_NAMES,
    STORE_FORMAT,
    ArraySpec,
)

logger = logging.getLogger(__name__)

MAX_PROBLEMS_PER_CHECK = 5
"""How many offending indices one check reports before summarising the rest."""


class Dimensions:
    """Binds the symbols of schema shapes (``"T"``, ``"G+1"``) to sizes and reports disagreements.

    Args:
        where: prefix of every problem (e.g. ``"sample 12"``).
        known: sizes already known (e.g. ``{"G": 3}`` from another group).
    """

    def __init__(self, where: str = "", known: dict[str, int] | None = None):
        self.where = where
        self.sizes: dict[str, int] = {**FIXED_DIMENSIONS, **(known or {})}
        self.source: dict[str, str] = {k: "the schema" for k in FIXED_DIMENSIONS}
        self.source |= {k: "the store" for k in known or {}}
        self.problems: list[str] = []

    def _say(self, text: str) -> None:
        self.problems.append(f"{self.where}: {text}" if self.where else text)

    def bind_shape(self, name: str, shape: tuple[int, ...], symbols: tuple) -> bool:
        """Bind ``symbols`` to ``shape`` (of array ``name``); False (and a problem) on any mismatch."""
        if len(shape) != len(symbols):
            self._say(f"'{name}' has {len(shape)} dimensions {tuple(shape)}; the schema says "
                      f"{len(symbols)}: [{', '.join(map(str, symbols))}]")
            return False
        ok = True
        for axis, (size, sym) in enumerate(zip(shape, symbols, strict=True)):
            ok &= self.bind(sym, int(size), name, axis)
        return ok

    def bind(self, sym: str | int, size: int, name: str, axis: int) -> bool:
        if isinstance(sym, int):
            if size != sym:
                self._say(f"'{name}' has size {size} on axis {axis}; the schema says {sym}")
                return False
            return True
        base, plus = (sym[:-2], 1) if sym.endswith("+1") else (sym, 0)
        value = size - plus
        if base in self.sizes:
            if self.sizes[base] != value:
                self._say(f"'{name}' has {base} = {value} (axis {axis}, size {size}) but {self.source[base]} "
                          f"gives {base} = {self.sizes[base]}")
                return False
            return True
        self.sizes[base] = value
        self.source[base] = f"'{name}'"
        return True


def _indices(mask: np.ndarray, offset: int = 0) -> str:
    if mask.ndim == 0:
        return "(the scalar)"
    idx = np.argwhere(mask)
    shown = ", ".join(str(tuple(int(v) + (offset if k == 0 else 0) for k, v in enumerate(row)))
                      if len(row) > 1 else str(int(row[0]) + offset) for row in idx[:MAX_PROBLEMS_PER_CHECK])
    more = f" and {len(idx) - MAX_PROBLEMS_PER_CHECK} more" if len(idx) > MAX_PROBLEMS_PER_CHECK else ""
    return f"[{shown}]{more}"


def _limits(spec: ArraySpec, upper: int | None) -> tuple[int | None, int | None]:
    """Smallest and largest valid value of an integer array (None: no limit)."""
    lo = spec.minimum if spec.minimum is not None else (0 if spec.unit in ("index", "code", "count", "bool", "row")
                                                        else None)
    hi = 1 if spec.unit == "bool" else (upper - 1 if upper is not None else None)
    return lo, hi


def _bad_mask(spec: ArraySpec, v: np.ndarray, upper: int | None, allow_nonfinite: bool = False) -> np.ndarray:
    if v.dtype.kind == "f":
        return np.zeros(v.shape, bool) if allow_nonfinite else ~np.isfinite(v)
    lo, hi = _limits(spec, upper)
    bad = np.zeros(v.shape, bool)
    if lo is not None:
        bad |= v < lo
    if hi is not None:
        bad |= v > hi
    return bad


def value_problems(spec: ArraySpec, values: np.ndarray, *, name: str | None = None, upper: int | None = None,
                   allow_nonfinite: bool = False, offset: int = 0) -> list[str]:
    """What is wrong with ``values`` under ``spec``'s value rules: finite floats, codes and indices in
    range (``upper``: exclusive bound from the names list or dimension), counts >= 0, bools 0/1.
    ``offset`` is added to reported row indices (for blocks of a larger array)."""
    name = name or spec.path
    v = np.asarray(values)
    out = []
    if v.dtype.kind == "f":
        if not allow_nonfinite:
            bad = ~np.isfinite(v)
            if bad.any():
                kinds = "NaN" if np.isnan(v[bad]).all() else "inf" if np.isinf(v[bad]).all() else "NaN/inf"
                out.append(f"'{name}' has {int(bad.sum())} non-finite ({kinds}) value(s) at {_indices(bad, offset)}")
        return out
    lo, hi = _limits(spec, upper)
    if lo is not None:
        bad = v < lo
        if bad.any():
            out.append(f"'{name}' has {int(bad.sum())} value(s) below {lo} at {_indices(bad, offset)} "
                       f"(smallest {int(v.min())})")
    if hi is not None:
        bad = v > hi
        if bad.any():
            what = (f"{spec.codes} has {upper} names" if spec.codes else f"{spec.index_of} = {upper}" if spec.index_of
                    else "a bool is 0 or 1")
            out.append(f"'{name}' has {int(bad.sum())} value(s) above {hi} at {_indices(bad, offset)} "
                       f"(largest {int(v.max())}; {what})")
    return out


def pattern_problems(a: dict[str, np.ndarray], where: str) -> list[str]:
    """What is wrong with the pattern arrays of a garments group ``a`` (every array, offsets checked):
    a garment is a pattern garment (panels >= 0, a design record, finite corner coordinates) or a
    shell (-1, none, NaN) throughout; stitches local to their instance; each design record UTF-8
    JSON of an object."""
    out: list[str] = []
    vs, fs, ss, ds = (np.asarray(a[k]) for k in ("vertex_start", "face_start", "stitch_start", "design_start"))
    from datagen.store.layout import design_record

    for g in range(len(vs) - 1):
        panel, face_panel = a["panel"][vs[g]:vs[g + 1]], a["face_panel"][fs[g]:fs[g + 1]]
        try:
            record = design_record(a["design"], ds, g)
        except ValueError as exc:
            out.append(f"{where}: 'design' of instance {g} is not UTF-8 JSON of an object ({exc})")
            continue
        kinds = {"panel": bool(len(panel)) and bool((panel >= 0).all()),
                 "face_panel": bool(len(face_panel)) and bool((face_panel >= 0).all()), "design": record is not None}
        shell = {"panel": bool((panel == -1).all()), "face_panel": bool((face_panel == -1).all()),
                 "design": record is None}
        if not (all(kinds.values()) or all(shell.values()) and ss[g + 1] == ss[g]):
            out.append(f"{where}: instance {g} is neither a pattern garment (panel and face_panel >= 0, a design "
                       "record) nor a shell garment (panel and face_panel -1, no stitches, no design record)")
        st = a["stitches"][ss[g]:ss[g + 1]]
        V = int(vs[g + 1] - vs[g])
        if st.size and (st.min() < 0 or st.max() >= V):
            out.append(f"{where}: 'stitches' of instance {g} has vertex {int(st.min() if st.min() < 0 else st.max())}"
                       f"; indices must be local to the instance (0 .. {V - 1})")
        if len(out) > 10:
            break
    return out


# --------------------------------------------------------------------------------------------- validate


def file_problems(path: Path, attrs: dict, meta: dict, quick: bool) -> tuple[list[str], set[str]]:
    """Every shard file that the layout implies is there, and (unless ``quick``) unchanged since pack
    (its checksum); returns the problems and the arrays with a missing file (a read would give zeros,
    so their values are not checked; a changed file is still read, to say more about it)."""
    from datagen.store.integrity import MISSING, shard_problem, shard_rows
    from datagen.store.layout import shard_keys

    consolidated = (meta.get("consolidated_metadata") or {}).get("metadata") or {}
    recorded = attrs.get("checksums") if isinstance(attrs.get("checksums"), dict) else {}
    remake = (f"the store is damaged: restore the file from a copy, or make the store again "
              f"(`drape info {path} --config > config.yaml && drape generate config.yaml --out NEW`)")
    out: list[str] = []
    damaged: set[str] = set()
    for name in ARRAYS:
        m = consolidated.get(name)
        if not m or m.get("node_type") != "array":
            continue
        shape, shard = shard_rows(m)

        def rows(key: str) -> str:
            i = int(key.split("/")[1])
            return f"rows {i * shard[0]} .. {min((i + 1) * shard[0], shape[0]) - 1}"

        bad = []
        for key in shard_keys(shape, shard):
            problem = shard_problem(path, name, key, recorded, digest=not quick)
            if problem:
                bad.append(f"'{name}': shard file {key} ({rows(key)}) {problem}")
                if problem == MISSING:
                    damaged.add(name)
        if bad:
            out += [f"{b}: {remake}" for b in bad[:MAX_PROBLEMS_PER_CHECK]]
            if len(bad) > MAX_PROBLEMS_PER_CHECK:
                out.append(f"'{name}': and {len(bad) - MAX_PROBLEMS_PER_CHECK} more damaged shard files")
    return out, damaged


def validate(path: str | Path, *, check_values: bool = True, quick: bool = False) -> list[str]:
    """Every problem of the store at ``path`` against :mod:`schemas.dataset` (empty list: valid).

    Checks the store is complete, the root attributes, every shard file that the layout implies
    (present; unless ``quick``, unchanged since pack by its recorded checksum), every array's
    presence, dtype, shape and unit, the offsets (start at 0, never decrease, end at their table's length, agree with the
    garment vertex counts), codes and indices in range, finite values (``check_values``: reads all
    data block by block), segments, disjoint splits (no garment instance (type, seed), body or
    motion in two splits) and the fit model.
    """
    path = Path(path)
    problems: list[str] = []
    root_meta = path / "zarr.json"
    try:
        meta = json.loads(root_meta.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return [f"{path} is not a drape store: {root_meta} does not exist"]
    except (OSError, ValueError) as exc:
        return [f"{root_meta} is not readable JSON: {exc}"]
    attrs = meta.get("attributes", {}) if isinstance(meta, dict) else {}
    if attrs.get("format") != STORE_FORMAT:
        return [f"{path} is not a drape store: root attribute 'format' is {attrs.get('format')!r}, "
                f"not {STORE_FORMAT!r}"]
    if attrs.get("complete") is not True:
        problems.append("store is not marked complete (root attribute 'complete' is not true): its generation or "
                        "pack was interrupted; run the same `drape generate` command again (it resumes from the "
                        "staged samples and packs; `drape info STORE --config > config.yaml` recovers the config)")
    if attrs.get("schema_version") != DATASET_SCHEMA_VERSION:  # another layout: its arrays mean other things
        from datagen.store.reader import version_problem

        return [*problems, version_problem(path, attrs.get("schema_version"))]
    problems += _root_attribute_problems(attrs)
    if "consolidated_metadata" not in meta:
        problems.append("root zarr.json has no consolidated metadata (pack() writes it before marking the store "
                        "complete)")
    if any(p.startswith("store is not marked") for p in problems) and not (path / "index").exists():
        return problems
    damage, damaged = file_problems(path, attrs, meta, quick)
    problems += damage
    if quick:
        check_values = False

    import zarr

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            root = zarr.open_group(store=str(path), mode="r", use_consolidated=False)
        except Exception as exc:  # noqa: BLE001 (any zarr failure is a problem to report)
            return [*problems, f"zarr cannot open {path}: {exc}"]
    arrays: dict[str, Any] = {}
    dims = Dimensions()
    for spec in ARRAYS.values():
        arr = _open_array(root, spec, problems)
        if arr is None:
            continue
        if str(arr.dtype) != spec.dtype:
            problems.append(f"'{spec.path}' has dtype {arr.dtype}; the schema says {spec.dtype}")
            continue
        unit = arr.attrs.get("unit")
        if unit != spec.unit:
            problems.append(f"'{spec.path}' has unit attribute {unit!r}; the schema says {spec.unit!r}")
        if dims.bind_shape(spec.path, tuple(arr.shape), spec.shape) and spec.path not in damaged:
            arrays[spec.path] = arr
    problems += dims.problems
    n = dims.sizes
    if attrs.get("sample_count") is not None and n.get("n_samples") not in (None, attrs.get("sample_count")):
        problems.append(f"root attribute sample_count = {attrs.get('sample_count')} but the sample arrays have "
                        f"{n['n_samples']} rows")
    units = attrs.get("units")
    if isinstance(units, dict):
        for spec in ARRAYS.values():
            if units.get(spec.path) != spec.unit:
                problems.append(f"root attribute units['{spec.path}'] is {units.get(spec.path)!r}; the schema says "
                                f"{spec.unit!r}")
    if not any(p.startswith("fit/") for p in arrays):
        problems.append("the fit model (group fit/) is missing or unreadable")
    problems += _consolidated_problems(meta, path)
    checker = _Checker(arrays, attrs, n, problems)
    checker.offsets()
    checker.values(check_values)
    checker.subdivision()
    checker.samples()
    checker.patterns()
    if check_values:
        checker.motions()
    checker.segments()
    checker.splits()
    return problems


def _consolidated_problems(meta: dict, store: Path) -> list[str]:
    """Arrays whose consolidated metadata (what zarr readers use) disagrees with their own zarr.json."""
    consolidated = (meta.get("consolidated_metadata") or {}).get("metadata") or {}
    out = []
    for path in ARRAYS:
        c = consolidated.get(path)
        if c is None:
            if consolidated:
                out.append(f"consolidated metadata has no entry for '{path}'")
            continue
        try:
            actual = json.loads((store / path / "zarr.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):  # missing or unreadable arrays are reported elsewhere
            continue
        for key in ("shape", "data_type", "codecs"):
            if c.get(key) != actual.get(key):
                out.append(f"consolidated metadata of '{path}' has {key} {c.get(key)!s:.80} but its zarr.json has "
                           f"{actual.get(key)!s:.80}: run zarr.consolidate_metadata on the store (or pack it again)")
                break
    return out


def _root_attribute_problems(attrs: dict) -> list[str]:
    out = []
    types = {"int": int, "str": str, "bool": bool, "dict": dict}
    for key, spec in ROOT_ATTRIBUTES.items():
        if key not in attrs:
            out.append(f"root attribute '{key}' is missing ({spec.doc})")
            continue
        value = attrs[key]
        if spec.type == "list[str]":
            if not isinstance(value, list) or not all(isinstance(s, str) for s in value):
                out.append(f"root attribute '{key}' must be a list of strings, not {value!r:.60}")
            elif len(set(value)) != len(value):
                out.append(f"root attribute '{key}' has repeated names")
        elif not isinstance(value, types[spec.type]) or spec.type == "int" and isinstance(value, bool):
            out.append(f"root attribute '{key}' must be {spec.type}, not {type(value).__name__}")
    if attrs.get("split_names") not in (None, list(SPLIT_NAMES)):
        out.append(f"root attribute 'split_names' is {attrs.get('split_names')}; the schema fixes {list(SPLIT_NAMES)}")
    if isinstance(attrs.get("failure_names"), list) and attrs["failure_names"][:1] != ["ok"]:
        out.append("root attribute 'failure_names' must start with 'ok' (failure code 0)")
    return out


def _open_array(root, spec: ArraySpec, problems: list[str]):
    try:
        node = root[spec.path]
    except KeyError:
        problems.append(f"array '{spec.path}' is missing ({spec.doc})")
        return None
    except Exception as exc:  # noqa: BLE001
        problems.append(f"array '{spec.path}' cannot be opened: {exc}")
        return None
    if not hasattr(node, "dtype"):
        problems.append(f"'{spec.path}' is a group, not an array")
        return None
    return node


def _blocks(arr, rows: int | None = None) -> Iterator[tuple[int, np.ndarray]]:
    """(first row, block) over an array, one shard (or ``rows`` rows) at a time."""
    step = rows or int(arr.shards[0] if arr.shards else arr.chunks[0])
    for start in range(0, arr.shape[0], max(1, step)):
        yield start, arr[start:start + step]


class _Checker:
    def __init__(self, arrays: dict, attrs: dict, sizes: dict, problems: list[str]):
        self.a = arrays
        self.attrs = attrs
        self.n = sizes
        self.problems = problems
        self.cache: dict[str, np.ndarray] = {}

    def get(self, path: str) -> np.ndarray | None:
        if path not in self.a:
            return None
        if path not in self.cache:
            try:
                self.cache[path] = self.a[path][...]
            except Exception as exc:  # noqa: BLE001 (a damaged file: say so, check the rest)
                self.say(f"'{path}' cannot be read: {type(exc).__name__}: {exc}")
                self.cache[path] = None
        return self.cache[path]

    def say(self, text: str) -> None:
        self.problems.append(text)

    def _offsets(self, path: str, length: int | None, table: str) -> np.ndarray | None:
        off = self.get(path)
        if off is None:
            return None
        ok = True
        if len(off) == 0 or off[0] != 0:
            self.say(f"'{path}'[0] is {off[0] if len(off) else '(empty)'}; offsets must start at 0")
            ok = False
        dec = np.flatnonzero(np.diff(off) < 0)
        for k in dec[:MAX_PROBLEMS_PER_CHECK]:
            self.say(f"'{path}'[{k + 1}] = {off[k + 1]} < '{path}'[{k}] = {off[k]}: offsets must not decrease")
        if len(dec) > MAX_PROBLEMS_PER_CHECK:
            self.say(f"'{path}' decreases at {len(dec) - MAX_PROBLEMS_PER_CHECK} more places")
        ok &= len(dec) == 0
        if length is not None and len(off) and off[-1] != length:
            self.say(f"'{path}'[-1] = {off[-1]} but the {table} table has {length} rows")
            ok = False
        return off if ok else None

    def offsets(self) -> None:
        n = self.n
        self.frame_start = self._offsets("index/frame_start", n.get("n_frames"), "frame")
        self.sim_start = self._offsets("index/sim_frame_start", n.get("n_sim_frames"), "sim_frame")
        self.vrow_start = self._offsets("index/vertex_row_start", n.get("n_vertex_rows"), "vertex_frame")
        self.gv_start = self._offsets("garments/vertex_start", n.get("n_garment_vertices"), "garment_vertex")
        self.gf_start = self._offsets("garments/face_start", n.get("n_garment_faces"), "garment_face")
        self.gs_start = self._offsets("garments/stitch_start", n.get("n_stitches"), "garment_stitch")
        self.gd_start = self._offsets("garments/design_start", n.get("n_design_bytes"), "garment_design")

    def upper(self, spec: ArraySpec) -> int | None:
        if spec.codes:
            names = self.attrs.get(spec.codes)
            return len(names) if isinstance(names, list) else None
        if spec.index_of:
            return self.n.get(spec.index_of)
        return None

    def values(self, check_values: bool) -> None:
        """Codes, indices, counts and bools in range; floats finite (``check_values``), block by block."""
        failure = self.get("samples/failure")
        failed_rows = None
        if failure is not None and self.sim_start is not None and len(self.sim_start) == len(failure) + 1:
            failed_rows = np.repeat(failure != 0, np.diff(self.sim_start))
        for path, arr in self.a.items():
            spec = ARRAYS[path]
            is_float = spec.dtype.startswith("float")
            if spec.unit == "row" or path == "index/segments" or (is_float and not check_values):
                continue
            upper = self.upper(spec)
            if not is_float and _limits(spec, upper) == (None, None):
                continue
            try:
                self._check_blocks(path, arr, spec, upper, is_float, failed_rows)
            except Exception as exc:  # noqa: BLE001 (a damaged file: say so, check the rest)
                self.problems.append(f"'{path}' cannot be read: {type(exc).__name__}: {exc}")

    def _check_blocks(self, path, arr, spec, upper, is_float, failed_rows) -> None:
        reported = 0
        for start, block in _blocks(arr):
            if is_float and spec.finite == "fitted" and self.attrs.get("fit_attribute") is False:
                if not np.isnan(block).all():
                    self.say(f"'{path}' must be NaN everywhere: the store has no fit attribute "
                             "(root attribute fit_attribute is false)")
                return
            if is_float and spec.finite == "pattern":
                face_panel = self.get("garments/face_panel")
                if face_panel is None or len(face_panel) != arr.shape[0]:
                    return  # reported by the shape checks
                shell = face_panel[start:start + len(block)] < 0
                if not np.isnan(block[shell]).all():
                    self.say(f"'{path}' must be NaN on the rows of shell garments (garments/face_panel -1)")
                    return
                block = np.where(shell.reshape(-1, *([1] * (block.ndim - 1))), 0, block)
            if is_float and spec.finite == "ok_samples" and failed_rows is not None:
                skip = failed_rows[start:start + len(block)]
                if skip.any():  # a failed sample's metrics may be inf/nan
                    block = block.copy()
                    block[skip] = 0
            probs = value_problems(spec, block, upper=upper, offset=start)
            if probs:
                rows = np.flatnonzero(_bad_mask(spec, block, upper).reshape(len(block), -1).any(1))[:1] + start
                self.problems.extend(p + self._where(spec, rows) for p in probs)
                reported += 1
                if reported >= MAX_PROBLEMS_PER_CHECK:
                    return

    def subdivision(self) -> None:
        """The subdivided body's triangles and the garments' indicator index its B + E vertices."""
        B, E = self.n.get("B"), self.n.get("E")
        if B is None or E is None:
            return
        for path in ("body/subdivided_faces", "garments/indicator"):
            v = self.get(path)
            if v is not None and v.size and (v.min() < 0 or v.max() >= B + E):
                self.say(f"'{path}' has values {int(v.min())} .. {int(v.max())}; the subdivided body has B + E = "
                         f"{B + E} vertices")
        if self.attrs.get("fit_attribute") is not (self.n.get("D", 0) > 0):
            self.say(f"root attribute fit_attribute is {self.attrs.get('fit_attribute')!r} but fit/ has D = "
                     f"{self.n.get('D')} features (D = 0 means no fit attribute)")

    def _where(self, spec: ArraySpec, rows: np.ndarray) -> str:
        """' (sample i, frame t, vertex v)' for the first bad row of a per-sample table."""
        if len(rows) == 0:
            return ""
        r = int(rows[0])
        try:
            if spec.table == "vertex_frame" and self.vrow_start is not None and self.frame_start is not None:
                f = int(np.searchsorted(self.vrow_start, r, side="right") - 1)
                i = int(np.searchsorted(self.frame_start, f, side="right") - 1)
                return f" (first: sample {i}, frame {f - self.frame_start[i]}, vertex {r - self.vrow_start[f]})"
            if spec.table == "frame" and self.frame_start is not None:
                i = int(np.searchsorted(self.frame_start, r, side="right") - 1)
                return f" (first: sample {i}, frame {r - self.frame_start[i]})"
            if spec.table == "sim_frame" and self.sim_start is not None:
                i = int(np.searchsorted(self.sim_start, r, side="right") - 1)
                return f" (first: sample {i}, simulated frame {r - self.sim_start[i]})"
            if spec.table == "sample":
                return f" (first: sample {r})"
            if spec.table == "garment_vertex" and self.gv_start is not None:
                g = int(np.searchsorted(self.gv_start, r, side="right") - 1)
                return f" (first: garment instance {g}, vertex {r - self.gv_start[g]})"
        except (IndexError, ValueError):
            return ""
        return ""

    def samples(self) -> None:
        """Per-sample consistency: frame counts, vertex counts, failures, simulated frames."""
        fs, ss, vr, gv = self.frame_start, self.sim_start, self.vrow_start, self.gv_start
        failure = self.get("samples/failure")
        garment = self.get("samples/garment")
        if fs is None or failure is None or len(fs) != len(failure) + 1:
            return
        T = np.diff(fs)
        for i in np.flatnonzero((failure != 0) & (T != 0))[:MAX_PROBLEMS_PER_CHECK]:
            self.say(f"sample {i} failed (samples/failure = {failure[i]}) but has {T[i]} recorded frames; "
                     "a failed sample has none")
        for i in np.flatnonzero((failure == 0) & (T == 0))[:MAX_PROBLEMS_PER_CHECK]:
            self.say(f"sample {i} did not fail but has no recorded frames")
        if ss is not None and len(ss) == len(fs):
            T_sim = np.diff(ss)
            rec = self.get("samples/recorded_from")
            if rec is not None:
                for i in np.flatnonzero(rec + T > T_sim)[:MAX_PROBLEMS_PER_CHECK]:
                    self.say(f"sample {i}: recorded_from {rec[i]} + {T[i]} recorded frames > {T_sim[i]} "
                             "simulated frames")
            ff = self.get("samples/failure_frame")
            if ff is not None:
                for i in np.flatnonzero(ff >= T_sim)[:MAX_PROBLEMS_PER_CHECK]:
                    self.say(f"sample {i}: failure_frame {ff[i]} is past its {T_sim[i]} simulated frames")
                for i in np.flatnonzero((failure == 0) & (ff != -1))[:MAX_PROBLEMS_PER_CHECK]:
                    self.say(f"sample {i} did not fail but has failure_frame {ff[i]} (must be -1)")
        if vr is not None and gv is not None and garment is not None:
            G = len(gv) - 1
            ok = (garment >= 0) & (garment < G)
            V = np.zeros(len(garment), np.int64)
            V[ok] = np.diff(gv)[garment[ok]]
            per_frame = np.diff(vr)
            if len(per_frame) == len(np.repeat(V, T)):
                expected = np.repeat(V, T)
                bad = np.flatnonzero((per_frame != expected) & np.repeat(ok, T))
                for f in bad[:MAX_PROBLEMS_PER_CHECK]:
                    i = int(np.searchsorted(fs, f, side="right") - 1)
                    self.say(f"'index/vertex_row_start' gives frame row {f} (sample {i}, frame {f - fs[i]}) "
                             f"{per_frame[f]} vertex rows, but its garment instance {garment[i]} has {expected[f]} "
                             "vertices")
            else:
                self.say(f"'index/vertex_row_start' has {len(vr)} entries; index/frame_start says "
                         f"{len(T) and fs[-1]} frames (+1)")
        faces = self.get("garments/faces")
        if faces is not None and self.gf_start is not None and gv is not None and len(self.gf_start) == len(gv):
            Vg = np.repeat(np.diff(gv), np.diff(self.gf_start))
            bad = np.flatnonzero(((faces < 0) | (faces >= Vg[:, None])).any(1))
            for r in bad[:MAX_PROBLEMS_PER_CHECK]:
                g = int(np.searchsorted(self.gf_start, r, side="right") - 1)
                self.say(f"'garments/faces' row {r} (garment instance {g}, face {r - self.gf_start[g]}) has "
                         f"{faces[r].tolist()}: indices must be local to the instance (0 .. {Vg[r] - 1})")

    def patterns(self) -> None:
        """Every garment instance a pattern garment or a shell throughout; stitches local; design records
        UTF-8 JSON (:func:`datagen.store.checks.pattern_problems`)."""
        names = ("vertex_start", "face_start", "stitch_start", "design_start", "panel", "face_panel", "stitches",
                 "design")
        if any(x is None for x in (self.gv_start, self.gf_start, self.gs_start, self.gd_start)):
            return
        a = {k: self.get(f"garments/{k}") for k in names}
        if any(v is None for v in a.values()) or len(a["panel"]) != self.gv_start[-1] \
                or len(a["face_panel"]) != self.gf_start[-1]:
            return
        self.problems.extend(pattern_problems(a, "garments"))

    def motions(self) -> None:
        """Every passed sample's recorded poses and translations are its motion's (the first ``T`` of
        ``motions/pose``, ``motions/trans``): the motion generator reads the motion tables, the
        regressor the frames."""
        fs, failure, motion = self.frame_start, self.get("samples/failure"), self.get("samples/motion")
        if fs is None or failure is None or motion is None or len(fs) != len(failure) + 1:
            return
        for name in ("pose", "trans"):
            table, frames = self.get(f"motions/{name}"), self.get(f"frames/{name}")
            if table is None or frames is None:
                continue
            for i in np.flatnonzero(failure == 0):
                m, t0, t1 = int(motion[i]), int(fs[i]), int(fs[i + 1])
                if not 0 <= m < len(table) or t1 - t0 > table.shape[1]:
                    continue  # out-of-range motions and frame counts are reported by the checks above
                if not np.array_equal(frames[t0:t1], table[m, :t1 - t0]):
                    self.say(f"sample {i}: frames/{name} differs from motions/{name}[{m}] (its motion's recorded "
                             "frames); the motion generator and the regressor would read different poses")
                    if len(self.problems) > 50:
                        return

    def segments(self) -> None:
        seg = self.get("index/segments")
        fs, failure = self.frame_start, self.get("samples/failure")
        L = self.attrs.get("segment_length")
        if seg is None or fs is None or failure is None or not isinstance(L, int) or len(fs) != len(failure) + 1:
            return
        from datagen.store.layout import segment_table

        expected = segment_table(np.diff(fs), failure, L)
        if seg.shape == expected.shape and np.array_equal(seg, expected):
            return
        T = np.diff(fs)
        for k, (i, t0) in enumerate(seg[:100_000]):
            if not 0 <= i < len(T):
                self.say(f"'index/segments'[{k}] names sample {i}, which does not exist")
            elif failure[i] != 0:
                self.say(f"'index/segments'[{k}] names failed sample {i}")
            elif not 0 <= t0 or t0 + L > T[i]:
                self.say(f"'index/segments'[{k}] = ({i}, {t0}) runs past sample {i}'s {T[i]} frames "
                         f"(segment_length {L})")
            else:
                continue
            if len(self.problems) > 50:
                break
        self.say(f"'index/segments' has {len(seg)} rows; the non-overlapping segments of length {L} of the "
                 f"non-failed samples are {len(expected)} rows (first differing row "
                 f"{_first_difference(seg, expected)})")

    def splits(self) -> None:
        split = self.get("samples/split")
        if split is None:
            return
        keys: dict[str, np.ndarray] = {}
        garment, gtype, gseed = self.get("samples/garment"), self.get("garments/type"), self.get("garments/seed")
        if garment is not None and gtype is not None and gseed is not None:
            ok = (garment >= 0) & (garment < len(gtype))
            g = np.where(ok, garment, 0)
            keys["garment instance (type, seed)"] = np.where(ok[:, None], np.stack([gtype[g], gseed[g]], 1), -1)
        for what in ("body", "motion"):
            v = self.get(f"samples/{what}")
            if v is not None:
                keys[what] = v[:, None]
        names = self.attrs.get("split_names") or list(SPLIT_NAMES)
        config = self.attrs.get("config") if isinstance(self.attrs.get("config"), dict) else {}
        # the config says what splits must not share (paper 001 splits by motion only)
        disjoint = set(config.get("split_disjoint", ("garments", "bodies", "motions")))
        kinds = {"garment instance (type, seed)": "garments", "body": "bodies", "motion": "motions"}
        keys = {what: key for what, key in keys.items() if kinds[what] in disjoint}
        for what, key in keys.items():
            first: dict[tuple, tuple[int, int]] = {}
            shared = 0
            for i, (s, k) in enumerate(zip(split.tolist(), map(tuple, key.tolist()), strict=True)):
                if k in first and first[k][0] != s:
                    shared += 1
                    if shared <= MAX_PROBLEMS_PER_CHECK:
                        s0, i0 = first[k]
                        label = k if len(k) > 1 else k[0]
                        self.say(f"splits overlap: {what} {label} is in {_name(names, s0)} (sample {i0}) and "
                                 f"{_name(names, s)} (sample {i})")
                else:
                    first.setdefault(k, (s, i))
            if shared > MAX_PROBLEMS_PER_CHECK:
                self.say(f"splits overlap: {shared - MAX_PROBLEMS_PER_CHECK} more samples share a {what} across splits")


def _name(names: list, code: int) -> str:
    return names[code] if 0 <= code < len(names) else f"split {code}"


def _first_difference(a: np.ndarray, b: np.ndarray) -> int:
    n = min(len(a), len(b))
    diff = np.flatnonzero((a[:n] != b[:n]).any(1)) if n else np.array([], int)
    return int(diff[0]) if len(diff) else n
