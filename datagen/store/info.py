"""What a store holds: :func:`store_info` (a JSON-able summary) and :func:`format_store_info` (a
printable table): splits and their counts, sizes on disk against uncompressed, and the failures.

A store still being generated (not packed) is summarised from its staging area: staged and
missing samples, and the failures among the staged ones.

:func:`datagen.export.plots.plot_store_info` draws a complete store as PNG plots (matplotlib): samples per split, garment
vertex counts, failure reasons, and the distributions of the fit attribute α (per component) and of
the body shapes β (per component).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from datagen.errors import InputError
from datagen.store.layout import MARKER, STAGING, directory_bytes, parse_sample_dir_name, read_root_attributes
from schemas.dataset import ARRAYS, SPLIT_NAMES, STATIC_GROUPS, STORE_FORMAT


def store_info(path: str | Path) -> dict[str, Any]:
    """Summary of the store at ``path``.

    Returns:
        ``path``, ``complete``, ``schema_version``, ``drape_version``, ``code_version``, ``seed``, ``sample_count``,
        ``segment_length``; for a complete store ``splits`` (name -> samples, ok, failed, frames,
        sim_frames, vertex_rows, segments, garment_instances, bodies, motions), ``totals`` (the same
        over all samples), ``static`` (garment instances, bodies, motions, body vertices, fit features),
        ``sizes`` (group -> bytes on disk and uncompressed), ``garments`` (instances, shells, sewing
        patterns, settled; per type the template's mean move from the construction) and ``failures`` (one row per failure
        code that occurs: code, name, count, share, per split, median failure frame); for a store in
        progress ``staged``, ``missing``, ``static_staged`` and ``failures`` over the staged samples.
    """
    path = Path(path)
    attrs = read_root_attributes(path)
    if attrs is None or attrs.get("format") != STORE_FORMAT:
        raise InputError(f"{path} is not a drape dataset store (no zarr.json with format '{STORE_FORMAT}')")
    info: dict[str, Any] = {"path": str(path), "complete": attrs.get("complete") is True}
    for key in ("schema_version", "drape_version", "code_version", "seed", "sample_count", "segment_length"):
        info[key] = attrs.get(key)
    failure_names = list(attrs.get("failure_names", []))
    if not info["complete"]:
        return info | _staging_info(path, attrs, failure_names)

    from datagen.store.reader import open_store, version_problem

    outdated = version_problem(path, attrs.get("schema_version"))
    if outdated:
        return info | {"outdated": outdated}

    store = open_store(path, backend="zarr")
    idx = store.index
    T = np.diff(idx["frame_start"])
    T_sim = np.diff(idx["sim_frame_start"])
    split, failure = idx["split"], idx["failure"]
    seg_split = split[idx["segments"][:, 0]] if len(idx["segments"]) else np.zeros(0, int)

    def counts(mask: np.ndarray, seg_mask: np.ndarray) -> dict[str, int]:
        return {"samples": int(mask.sum()), "ok": int((mask & (failure == 0)).sum()),
                "failed": int((mask & (failure != 0)).sum()), "frames": int(T[mask].sum()),
                "sim_frames": int(T_sim[mask].sum()), "vertex_rows": int((T * idx["vertex_count"])[mask].sum()),
                "segments": int(seg_mask.sum()), "garment_instances": len(np.unique(idx["garment"][mask])),
                "bodies": len(np.unique(idx["body"][mask])), "motions": len(np.unique(idx["motion"][mask]))}

    info["splits"] = {name: counts(split == code, seg_split == code) for code, name in enumerate(SPLIT_NAMES)}
    info["totals"] = counts(np.ones(len(split), bool), np.ones(len(seg_split), bool))
    meta = json.loads((path / "zarr.json").read_text())
    consolidated = meta.get("consolidated_metadata", {}).get("metadata", {})

    def shape(p: str) -> list[int]:
        return consolidated.get(p, {}).get("shape", [0])

    info["static"] = {"garment_instances": shape("garments/type")[0], "bodies": shape("bodies/betas")[0],
                      "motions": shape("motions/label")[0], "body_vertices": shape("body/v_template")[0],
                      "fit_features": shape("fit/mean")[0]}
    sizes: dict[str, dict[str, int]] = {}
    for key, m in consolidated.items():
        if m.get("node_type") != "array":
            continue
        group = key.split("/")[0]
        raw = int(np.prod(m["shape"], dtype=np.int64)) * np.dtype(m["data_type"]).itemsize
        sizes.setdefault(group, {"on_disk": 0, "uncompressed": 0})["uncompressed"] += raw
    for group, size in sizes.items():
        size["on_disk"] = directory_bytes(path / group)
    info["sizes"] = dict(sorted(sizes.items(), key=lambda kv: -kv[1]["on_disk"]))
    info["size_on_disk"] = directory_bytes(path)
    frames = int(T.sum())
    per_frame = sum(sizes.get(g, {}).get("on_disk", 0) for g in ("vertex_frames", "frames"))
    info["bytes_per_garment_frame"] = per_frame / frames if frames else None
    info["fit"] = {"fitted": attrs.get("fit_attribute"), **(attrs.get("fit_diagnostics") or {})}
    info["garments"] = _garment_rows(store, list(attrs.get("garment_type_names", [])))
    from datagen.store.validation import file_problems

    info["damage"] = file_problems(path, attrs, meta, quick=True)[0]  # missing shard files (cheap)
    from datagen.store.integrity import metadata_problem

    consolidated = (meta.get("consolidated_metadata") or {}).get("metadata") or {}
    for name in ARRAYS:  # an array whose zarr.json is gone or disagrees with the consolidated copy (cheap)
        problem = metadata_problem(path, name, consolidated.get(name)) if name in consolidated else None
        if problem and not any(name in d for d in info["damage"]):
            info["damage"].append(f"{name}: {problem}")
    ff = idx["failure_frame"]
    info["failures"] = _failure_rows(failure, split, ff, failure_names)
    return info


def _garment_rows(store, type_names: list[str]) -> dict[str, Any] | None:
    """The garment instances by type: how many, shells or sewing patterns, how many settled at rest,
    and how far the template (the settled drape) lies from the construction: the mean vertical move
    and the mean distance per vertex (mm). None when a garments shard is damaged (reported apart)."""
    from datagen.store.integrity import DamagedStoreError

    try:
        gtype, settled = store.read("garments/type"), store.read("garments/settled")
        vs, ds = store.read("garments/vertex_start"), store.read("garments/design_start")
        rest, built = store.read("garments/rest_vertices"), store.read("garments/built_vertices")
    except DamagedStoreError:
        return None
    move = rest.astype(np.float64) - built
    rows: dict[str, dict] = {}
    for g in range(len(gtype)):
        name = type_names[gtype[g]] if 0 <= gtype[g] < len(type_names) else f"type {gtype[g]}"
        r = rows.setdefault(name, {"instances": 0, "pattern": bool(ds[g + 1] > ds[g]), "settled": 0, "dy": [],
                                   "distance": []})
        r["instances"] += 1
        r["settled"] += int(settled[g])
        if settled[g]:
            m = move[vs[g]:vs[g + 1]]
            r["dy"].append(float(m[:, 1].mean()))
            r["distance"].append(float(np.linalg.norm(m, axis=1).mean()))
    for r in rows.values():
        dy, dist = r.pop("dy"), r.pop("distance")
        r["template_dy_mm"] = 1000 * float(np.mean(dy)) if dy else None
        r["template_distance_mm"] = 1000 * float(np.mean(dist)) if dist else None
    pattern = int((np.diff(ds) > 0).sum())
    return {"instances": len(gtype), "pattern": pattern, "shell": len(gtype) - pattern,
            "settled": int(settled.sum()), "types": rows}


def _garment_lines(garments: dict | None) -> list[str]:
    if not garments:
        return []
    out = [f"garments: {garments['instances']} instances ({garments['shell']} shell, {garments['pattern']} sewing "
           f"pattern), {garments['settled']} settled at rest (their template); template - construction per type:"]
    for name, r in garments["types"].items():
        move = ("not settled" if r["template_dy_mm"] is None else
                f"vertical {r['template_dy_mm']:+.1f} mm, {r['template_distance_mm']:.1f} mm per vertex on average")
        out.append(f"  {name:<24}{r['instances']:>4} x, {r['settled']} settled: {move}")
    return out


def _failure_rows(failure: np.ndarray, split: np.ndarray, failure_frame: np.ndarray, names: list[str]) -> list[dict]:
    rows = []
    n = max(1, len(failure))
    for code in np.unique(failure):
        mask = failure == code
        frames = failure_frame[mask & (failure_frame >= 0)]
        rows.append({"code": int(code), "name": names[code] if 0 <= code < len(names) else f"code {code}",
                     "count": int(mask.sum()), "share": float(mask.sum() / n),
                     "per_split": {s: int((mask & (split == k)).sum()) for k, s in enumerate(SPLIT_NAMES)},
                     "median_failure_frame": float(np.median(frames)) if len(frames) else None})
    return rows


def _staging_info(path: Path, attrs: dict, failure_names: list[str]) -> dict[str, Any]:
    staging = path / STAGING
    failures, splits, frames = [], [], []
    if staging.is_dir():
        for entry in sorted(staging.iterdir()):
            if parse_sample_dir_name(entry.name) is None or not (entry / MARKER).is_file():
                continue
            try:
                m = json.loads((entry / MARKER).read_text())
            except (OSError, ValueError):
                continue
            failures.append(m["scalars"]["failure"])
            splits.append(m["scalars"]["split"])
            frames.append(m["scalars"]["failure_frame"])
    n = int(attrs.get("sample_count", 0))
    return {"staged": len(failures), "missing": n - len(failures),
            "static_staged": [g for g in STATIC_GROUPS if (staging / f"static-{g}" / MARKER).is_file()],
            "size_on_disk": directory_bytes(path),
            "failures": _failure_rows(np.asarray(failures, int), np.asarray(splits, int), np.asarray(frames, int),
                                      failure_names)}


def human_bytes(n: float) -> str:
    """``n`` bytes as B, KiB, MiB, GiB or TiB (one decimal above B)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return str(n)


def _fit_lines(fit: dict) -> list[str]:
    if not fit.get("fitted"):
        return ["fit attribute: none (the config's fit_attribute is false; garments/alpha is NaN)"]
    out = [f"fit attribute: {fit.get('factors')} factors over {fit.get('features')} features from {fit.get('pairs')} "
           f"training pairs; {fit.get('saturated_features')} features at the noise floor"]
    if fit.get("alpha_seed_spread"):
        spread = ", ".join(f"α{k + 1} {v:.3g} (range {r:.3g})"
                           for k, (v, r) in enumerate(zip(fit["alpha_seed_spread"], fit.get("alpha_range", []),
                                                          strict=False)))
        out.append(f"  α's largest change across subsample seeds: {spread}")
    out += [f"  warning: {w}" for w in fit.get("warnings", [])]
    return out


def format_store_info(info: dict[str, Any]) -> str:
    """:func:`store_info` as a plain-text table."""
    state = "complete" if info["complete"] else ("NOT PACKED (generation in progress or interrupted: run the same `drape generate` command "
                                                 "again to finish it)")
    lines = [f"store {info['path']}: {state}",
             (f"schema {info['schema_version']}, drape {info['drape_version']} (code {info['code_version'] or 'not recorded'}), "
              f"seed {info['seed']}, "
              f"{info['sample_count']} samples, segments of {info['segment_length']} frames")]
    if info.get("outdated"):
        return "\n".join([*lines, info["outdated"]])
    if not info["complete"]:
        lines.append(f"staged {info['staged']} samples, missing {info['missing']}; static groups staged: "
                     f"{', '.join(info['static_staged']) or 'none'}; {human_bytes(info['size_on_disk'])} on disk")
    else:
        cols = ("samples", "ok", "failed", "frames", "sim_frames", "segments", "garment_instances", "bodies", "motions")
        heads = ("samples", "ok", "failed", "frames", "sim frames", "segments", "garments", "bodies", "motions")
        lines += ["", f"{'split':<8}" + "".join(f"{h:>11}" for h in heads)]
        for name, row in [*info["splits"].items(), ("total", info["totals"])]:
            lines.append(f"{name:<8}" + "".join(f"{row[c]:>11}" for c in cols))
        s = info["static"]
        lines += ["", (f"static: {s['garment_instances']} garment instances, {s['bodies']} bodies, "
                       f"{s['motions']} motions, body model of {s['body_vertices']} vertices, "
                       f"fit model of {s['fit_features']} features")]
        lines += ["", f"{'group':<15}{'on disk':>12}{'uncompressed':>14}{'ratio':>8}"]
        for group, sz in info["sizes"].items():
            ratio = sz["uncompressed"] / sz["on_disk"] if sz["on_disk"] else float("nan")
            lines.append(f"{group:<15}{human_bytes(sz['on_disk']):>12}{human_bytes(sz['uncompressed']):>14}{ratio:>8.2f}")
        lines.append(f"{'total':<15}{human_bytes(info['size_on_disk']):>12}"
                     f"{human_bytes(sum(v['uncompressed'] for v in info['sizes'].values())):>14}")
        if info.get("bytes_per_garment_frame"):
            lines.append(f"per stored garment-frame (vertex_frames + frames): {human_bytes(info['bytes_per_garment_frame'])}")
        lines += [""] + _garment_lines(info.get("garments"))
        lines += [""] + _fit_lines(info.get("fit") or {})
        if info.get("damage"):
            lines += ["", f"DAMAGED: {len(info['damage'])} problem(s); run `drape validate` for all of them:"]
            lines += [f"  {p}" for p in info["damage"][:5]]
    lines += ["", f"{'failure':<20}{'code':>5}{'count':>8}{'share':>8}" + "".join(f"{s:>7}" for s in SPLIT_NAMES)
              + f"{'median frame':>14}"]
    for row in info["failures"]:
        med = "-" if row["median_failure_frame"] is None else f"{row['median_failure_frame']:.0f}"
        lines.append(f"{row['name']:<20}{row['code']:>5}{row['count']:>8}{row['share']:>8.1%}"
                     + "".join(f"{row['per_split'][s]:>7}" for s in SPLIT_NAMES) + f"{med:>14}")
    if not info["failures"]:
        lines.append("(no samples)")
    return "\n".join(lines)
