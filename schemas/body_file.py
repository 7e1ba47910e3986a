"""Schema of SMPL-format body files (version 1): the keys, shapes, dtypes and units that
``datagen.body.io`` writes and requires. V = vertices, F = faces, J = joints (24), S = shape
components, P = 9 (J - 1) pose-blend-shape features."""

from __future__ import annotations

BODY_FILE_SCHEMA_VERSION = 1

BODY_FILE_KEYS: dict[str, dict[str, str]] = {
    "v_template": {"shape": "[V, 3]", "dtype": "float64", "unit": "m", "doc": "rest-pose (T-pose) template"},
    "shapedirs": {"shape": "[V, 3, S]", "dtype": "float64", "unit": "m per unit β", "doc": "shape blend-shape directions"},
    "posedirs": {"shape": "[V, 3, P]", "dtype": "float64", "unit": "m", "doc": "pose blend-shape directions (zero: none)"},
    "J_regressor": {"shape": "[J, V]", "dtype": "float64", "unit": "1", "doc": "joint regressor, rows sum to 1 (dense or scipy.sparse)"},
    "weights": {"shape": "[V, J]", "dtype": "float64", "unit": "1", "doc": "skinning weights, rows sum to 1"},
    "kintree_table": {"shape": "[2, J]", "dtype": "int64", "unit": "index", "doc": "parents (root: 2**32 - 1) and joint ids"},
    "f": {"shape": "[F, 3]", "dtype": "uint32", "unit": "index", "doc": "triangles"},
}
"""Required keys (SMPL's own layout)."""

OPTIONAL_KEYS: dict[str, str] = {
    "drape_meta": "JSON string: source, licence, rest pose, build config, presets, measured errors",
    "bs_style": "'lbs' (as SMPL files)",
    "bs_type": "'lrotmin' (as SMPL files)",
}
