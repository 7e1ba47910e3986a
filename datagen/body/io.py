"""Reading and writing SMPL-format body files (``.npz`` and ``.pkl``).

Written files load in the ``smplx`` package (``smplx.SMPL(model_path=file.pkl)``) and pose to the
same vertices as drape. The reader takes drape's own files and real SMPL files as distributed by
their authors: Python-2 pickles (latin-1), a scipy-sparse ``J_regressor`` and ``chumpy`` arrays.
chumpy need not be installed: its arrays are read through a stand-in. Unpickling is restricted to
numpy, scipy.sparse and chumpy classes, so a body file cannot run arbitrary code.

File layout (SMPL's keys): ``v_template [V,3]``, ``shapedirs [V,3,S]``, ``posedirs [V,3,207]``,
``J_regressor [24,V]``, ``weights [V,24]``, ``kintree_table [2,24]``, ``f [F,3]``; drape adds
``drape_meta`` (a JSON string: source, licence, rest pose, build key, shape statistics).
"""

from __future__ import annotations

import io
import json
import logging
import os
import pickle
import uuid
import zipfile
from pathlib import Path

import numpy as np

from datagen.body.model import BodyModel
from datagen.body.skeleton import kintree_table, parents_from_kintree
from datagen.errors import InputError
from schemas.body_file import BODY_FILE_KEYS  # the schema is the single source of truth

logger = logging.getLogger(__name__)

REQUIRED_KEYS = tuple(BODY_FILE_KEYS)
BODY_FILE_FORMATS = (".npz", ".pkl")


class _ZerosOnLoad:
    """Pickles as a call to ``numpy.zeros``: an all-zero array costs a few bytes in a file and
    is a plain ndarray for whoever loads it (smplx included)."""

    def __init__(self, shape, dtype="float64"):
        self.shape, self.dtype = tuple(int(s) for s in shape), str(np.dtype(dtype))

    def __reduce__(self):
        return (np.zeros, (self.shape, self.dtype))


def _file_posedirs(model: BodyModel):
    V, J = model.vertex_count, model.joint_count
    if model.posedirs is None:
        return None, (V, 3, 9 * (J - 1))
    return model.posedirs.T.reshape(V, 3, -1), None


def save_body_file(model: BodyModel, path: str | Path) -> Path:
    """Write ``model`` as an SMPL file; the suffix picks the format (.npz or .pkl).

    The write goes to a temporary file that is renamed into place, so an existing file is never
    left half written.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in BODY_FILE_FORMATS:
        raise InputError(f"body file {path} must end in .npz or .pkl (got '{suffix}')")
    if not path.parent.exists():
        raise InputError(f"directory {path.parent} does not exist; create it first")
    posedirs, zero_shape = _file_posedirs(model)
    data = {
        "v_template": model.v_template.astype(np.float64),
        "shapedirs": model.shapedirs.astype(np.float64),
        "weights": model.weights.astype(np.float64),
        "kintree_table": kintree_table() if model.joint_count == 24 else np.stack(
            [np.where(model.parents < 0, 4294967295, model.parents), np.arange(model.joint_count)]
        ).astype(np.int64),
        "f": model.faces.astype(np.uint32),
        "bs_style": "lbs",
        "bs_type": "lrotmin",
        "drape_meta": json.dumps(model.meta, sort_keys=True),
    }
    # a name of this writer's own: two processes building the same cached body at once (the
    # workers of benchmarks/garment_cache.py did) each write whole and rename; the last rename wins
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex}.partial")
    try:
        if suffix == ".pkl":
            import scipy.sparse

            data["J_regressor"] = scipy.sparse.csc_matrix(model.J_regressor.astype(np.float64))
            data["posedirs"] = _ZerosOnLoad(zero_shape) if posedirs is None else posedirs.astype(np.float64)
            with tmp.open("wb") as fh:
                pickle.dump(data, fh, protocol=2)
        else:
            data["J_regressor"] = model.J_regressor.astype(np.float64)
            data["posedirs"] = np.zeros(zero_shape) if posedirs is None else posedirs.astype(np.float64)
            data["bs_style"] = np.array(data["bs_style"])
            data["bs_type"] = np.array(data["bs_type"])
            data["drape_meta"] = np.array(data["drape_meta"])
            with tmp.open("wb") as fh:
                np.savez_compressed(fh, **data)
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)  # nothing half written is left behind
        raise
    logger.info("wrote body model %s (%d vertices, %.1f MB)", path, model.vertex_count, path.stat().st_size / 1e6)
    return path


# ----------------------------------------------------------------------------- reading

class _ChumpyStandIn:
    """Takes the place of a chumpy ``Ch`` while unpickling a real SMPL file."""

    def __init__(self, *args, **kwargs):
        self._state = {}

    def __setstate__(self, state):
        self._state = state if isinstance(state, dict) else {"state": state}

    def to_array(self, key: str) -> np.ndarray:
        for name in ("x", "a"):
            if name in self._state and not isinstance(self._state[name], _ChumpyStandIn):
                return np.asarray(self._state[name])
        raise InputError(
            f"body file entry '{key}' is a chumpy expression that drape cannot evaluate without chumpy; "
            "convert the file once with chumpy installed (pip install chumpy) or export it from smplx"
        )


_ALLOWED_PICKLE_MODULES = ("numpy", "scipy.sparse", "copy_reg", "copyreg", "_codecs", "collections")


class _BodyUnpickler(pickle.Unpickler):
    def find_class(self, module, name):
        if module.startswith("chumpy"):
            return _ChumpyStandIn
        if module == "__builtin__" or module == "builtins":
            if name in ("object", "set", "frozenset", "slice", "complex", "bytearray", "list", "dict", "tuple"):
                return super().find_class("builtins", name)
        elif module.startswith(_ALLOWED_PICKLE_MODULES):
            return super().find_class(module, name)
        raise InputError(f"body file refers to '{module}.{name}', which is not part of an SMPL file; refusing to load it")


def _to_array(value, key: str) -> np.ndarray:
    if isinstance(value, _ChumpyStandIn):
        return value.to_array(key)
    if hasattr(value, "toarray"):
        return value.toarray()
    return np.asarray(value)


def read_body_arrays(path: str | Path) -> dict:
    """Raw key -> value mapping of a body file, with clear errors for what cannot be read."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"body file {path} does not exist; build one with `drape body build` or pass a path to an SMPL .pkl/.npz")
    head = path.read_bytes()[:4]
    try:
        if head.startswith(b"PK"):
            with np.load(path, allow_pickle=False) as npz:
                return {k: npz[k] for k in npz.files}
        if head[:1] == b"\x80" or head[:1] in (b"(", b"}"):
            with path.open("rb") as fh:
                return _BodyUnpickler(fh, encoding="latin1").load()
    except InputError:
        raise
    except (pickle.UnpicklingError, zipfile.BadZipFile, EOFError, ValueError, OSError, AttributeError, io.UnsupportedOperation) as exc:
        raise InputError(f"body file {path} could not be read ({type(exc).__name__}: {exc}); is it an SMPL .pkl or .npz?") from exc
    raise InputError(f"body file {path} is neither an npz archive nor a pickle; pass an SMPL .pkl or .npz file")


def load_body_file(path: str | Path) -> BodyModel:
    """Load drape's or SMPL's body file into a :class:`BodyModel` (float64)."""
    path = Path(path)
    raw = read_body_arrays(path)
    if not isinstance(raw, dict):
        raise InputError(f"body file {path} holds a {type(raw).__name__}, not the dict of arrays an SMPL file holds")
    missing = [k for k in REQUIRED_KEYS if k not in raw]
    if missing:
        raise InputError(f"body file {path} lacks {', '.join(missing)}; an SMPL file has {', '.join(REQUIRED_KEYS)}")
    arr = {k: _to_array(raw[k], k) for k in REQUIRED_KEYS}
    v_template = arr["v_template"].astype(np.float64)
    V = v_template.shape[0] if v_template.ndim == 2 else -1
    if v_template.ndim != 2 or v_template.shape[1] != 3:
        raise InputError(f"body file {path}: v_template must be [V, 3], got {v_template.shape}")
    shapedirs = arr["shapedirs"].astype(np.float64)
    if shapedirs.ndim != 3 or shapedirs.shape[:2] != (V, 3):
        raise InputError(f"body file {path}: shapedirs must be [V={V}, 3, S], got {shapedirs.shape}")
    posedirs_file = arr["posedirs"].astype(np.float64)
    if posedirs_file.shape[:2] != (V, 3):
        raise InputError(f"body file {path}: posedirs must be [V={V}, 3, P], got {posedirs_file.shape}")
    posedirs = None if not np.any(posedirs_file) else posedirs_file.reshape(-1, posedirs_file.shape[-1]).T.copy()
    parents = parents_from_kintree(arr["kintree_table"])
    meta = {}
    if "drape_meta" in raw:
        try:
            meta = json.loads(str(_to_array(raw["drape_meta"], "drape_meta")))
        except json.JSONDecodeError:
            logger.warning("body file %s has an unreadable drape_meta entry; ignoring it", path)
    else:
        meta = {"source": f"SMPL-format file {path.name}", "licence": "as distributed by the file's authors"}
    values = {k: arr[k] for k in ("v_template", "shapedirs", "J_regressor", "weights")}
    for key, value in values.items():
        if not np.all(np.isfinite(value)):
            raise InputError(f"body file {path}: {key} has non-finite values")
    return BodyModel(
        v_template=v_template,
        shapedirs=shapedirs,
        posedirs=posedirs,
        J_regressor=arr["J_regressor"].astype(np.float64),
        weights=arr["weights"].astype(np.float64),
        parents=parents,
        faces=arr["f"].astype(np.int64),
        meta=meta,
    )
