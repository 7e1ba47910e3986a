"""What a store's samples are a function of: the dataset config (without the settings that only
say how the work is spread) and the code and libraries that make the data.

A store records both when it is created; resuming it with another config or with other code is
refused, so a store never mixes samples simulated by two versions of the simulator (a garment
builder or solver change between a killed run and its resumption would otherwise go unnoticed:
``drape_version`` alone does not change with every commit).
"""

from __future__ import annotations

import hashlib
import importlib.metadata
from functools import cache
from pathlib import Path

EXECUTION_ONLY = (("simulation", "batch_size"),)
"""Config fields that say how scenes are grouped for the device, not what is simulated (a scene's
result does not depend on its batch: ``tests/sim/test_physics.py``): a store can be resumed with a
different value, e.g. a smaller batch after a device ran out of memory."""

DATA_PACKAGES = ("geometry", "body", "garment", "motion", "sim", "targets", "generate", "store")
"""The subpackages of ``datagen`` whose source makes or lays out the data."""

DATA_MODULES = ("materials.py", "params.py")
"""The modules at the top of ``datagen`` whose source the data depends on (material presets, the
style-parameter draws)."""

DATA_LIBRARIES = ("warp-lang", "anny", "numpy", "scipy", "torch", "pymeshlab", "trimesh", "scikit-learn")
"""Libraries whose versions the data depends on (kernels, the body model, meshing, the fit model)."""


def identity_config(config: dict) -> dict:
    """The config without :data:`EXECUTION_ONLY` fields: what a store's identity holds."""
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in config.items()}
    for section, key in EXECUTION_ONLY:
        if isinstance(out.get(section), dict):
            out[section].pop(key, None)
    return out


@cache
def code_version() -> str:
    """A 16-hex-digit digest of the source of :data:`DATA_PACKAGES` and :data:`DATA_MODULES`, the store schema and the
    versions of :data:`DATA_LIBRARIES` (those installed)."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    files = sorted(p for pkg in DATA_PACKAGES for p in (root / pkg).rglob("*.py"))
    files += [root / name for name in DATA_MODULES]
    files += sorted((root.parent / "schemas").glob("*.py"))
    for p in files:
        h.update(str(p.relative_to(root.parent)).encode())
        h.update(p.read_bytes())
    for lib in DATA_LIBRARIES:
        try:
            version = importlib.metadata.version(lib)
        except importlib.metadata.PackageNotFoundError:
            version = "-"
        h.update(f"{lib}=={version}".encode())
    return h.hexdigest()[:16]
