"""On-disk cache of built body models, keyed by what they were built from.

The key is a hash of the builder's configuration, the Anny version and drape's builder version
(:meth:`AnnyBodyConfig.cache_key`); a rebuild happens only when one of those changes. The cache
root is ``$DRAPE_CACHE_DIR`` if set (read when called, not at import), else
``~/.cache/drape``. Files are written to a temporary name and renamed, so a killed build never
leaves a file that looks whole.
"""

from __future__ import annotations

import logging
import os
import time
from pathlib import Path

from datagen.body.anny_builder import AnnyBodyConfig, anny_version, build_body_from_anny
from datagen.body.io import load_body_file, save_body_file
from datagen.body.model import BodyModel

logger = logging.getLogger(__name__)


def cache_root() -> Path:
    return Path(os.environ.get("DRAPE_CACHE_DIR", Path.home() / ".cache" / "drape"))


def body_cache_path(config: AnnyBodyConfig, subdivision_level: int = 0) -> Path:
    key = config.cache_key(anny_version())
    name = "body.npz" if subdivision_level == 0 else f"body-subdiv{subdivision_level}.npz"
    return cache_root() / "body" / f"anny-{key}" / name


def default_body(config: AnnyBodyConfig = AnnyBodyConfig(), *, subdivision_level: int = 0, rebuild: bool = False) -> BodyModel:
    """The Anny-derived body for ``config``, from the cache when present, else built and cached.

    ``subdivision_level`` 1 gives the 4-to-1 subdivided model (built from the cached base).
    """
    path = body_cache_path(config, subdivision_level)
    if path.is_file() and not rebuild:
        t0 = time.perf_counter()
        model = load_body_file(path)
        logger.info("loaded cached body %s in %.2f s", path, time.perf_counter() - t0)
        return model
    if subdivision_level > 0:
        model = default_body(config, subdivision_level=subdivision_level - 1, rebuild=rebuild).subdivided()
    else:
        model = build_body_from_anny(config).model
    path.parent.mkdir(parents=True, exist_ok=True)
    save_body_file(model, path)
    # the model as every later run gets it, from the file: a build holds strided views where the
    # file gives contiguous arrays, and numpy sums in memory order, so the built model's shaped
    # bodies differed from the loaded one's in the last bits; garments built on them (their cache
    # keys, their meshes, the datasets made from them) then depended on whether the body cache was
    # warm (tiny from nothing: 4,740 garment vertices; with the body cached: 4,743)
    return load_body_file(path)
