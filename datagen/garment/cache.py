"""On-disk cache of built garments, keyed by everything a build depends on.

A garment is a pure function of its type, seed, edge length, the builder's version and the body
it is built on (its rest-pose vertices and faces), so a build is kept under
``$DRAPE_CACHE_DIR/garments`` and reused by later runs: a resumed ``drape generate``, a second
store over the same garments, or a machine that can simulate but not build (the GPU host has no
pymeshlab; carry the cache there). Files are written to a temporary name and renamed, so a killed
build never leaves a file that looks whole; a file that does not read back is rebuilt.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import uuid

import numpy as np

from datagen.body.cache import cache_root

log = logging.getLogger(__name__)


def garment_cache_key(kind: str, seed: int, body_model, betas, target_edge_length: float | None) -> str:
    """Hash of what the build reads: type, seed, edge length (the type's default resolved), builder
version, the type's material preset as it is now (a re-fitted preset is a new key: the cached
garment carries its material), shaped body."""
    from datagen.garment.types import BUILDER_VERSION, GARMENT_TYPES, default_edge_length
    from datagen.materials import material

    if target_edge_length is None and kind in GARMENT_TYPES:  # resolved: a changed default is a new key
        target_edge_length = default_edge_length(kind)
    betas = np.zeros(body_model.shape_dim) if betas is None else np.asarray(betas, dtype=np.float64).reshape(-1)
    preset = material(GARMENT_TYPES[kind].material).as_dict() if kind in GARMENT_TYPES else None
    h = hashlib.sha256(json.dumps([kind, int(seed), target_edge_length, BUILDER_VERSION, preset]).encode())
    h.update(np.ascontiguousarray(np.asarray(body_model.shaped(betas))[0], dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(body_model.faces, dtype=np.int64).tobytes())
    return h.hexdigest()[:20]


def cached_garment(kind: str, body_model, betas=None, *, seed: int = 0, target_edge_length: float | None = None):
    """:func:`~datagen.garment.types.make_garment` with the default style and material, from the
    cache when built before (bit-identical arrays), else built and cached."""
    from datagen.garment.mesh import load_garment
    from datagen.garment.types import make_garment

    path = cache_root() / "garments" / f"{kind}-{seed}-{garment_cache_key(kind, seed, body_model, betas, target_edge_length)}.npz"
    if path.is_file():
        try:
            return load_garment(path)
        except Exception as e:  # a damaged file (another tool, a full disk): build again
            log.warning("garment cache file %s does not read back (%s); rebuilding", path, e)
    g = make_garment(kind, body_model, betas, seed=seed, target_edge_length=target_edge_length)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp.npz")
        g.save(tmp)
        os.replace(tmp, path)
    except OSError as e:  # the cache is a convenience: a read-only or full cache disk does not stop the run
        log.warning("could not cache garment in %s: %s", path.parent, e)
    return g
