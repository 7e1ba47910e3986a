"""Body shapes: β sampling from a seed, the thin / regular / fat presets, and body measurements.

Paper 000 makes its bodies by varying SMPL's 2nd and 7th shape components. drape's shape space
is its own PCA (see :mod:`datagen.body.anny_builder`), so its presets are defined by what they
are rather than by component numbers: a body of 1.70 m with a BMI of 18.5 (thin), 23 (regular)
and 31 (fat), found by regressing β on height and BMI over the sampled adult population. Their
measured heights, masses and BMIs are stored in the model's metadata; ``drape body info``
prints them. In drape's shape space β1 is height (correlation 1.0 over the population) and β3
is mostly mass (-0.84): the presets move mainly along β3, as the paper's move along β2 and β7.
"""

from __future__ import annotations

import logging

import numpy as np

from datagen.body.model import BodyModel
from datagen.errors import InputError
from datagen.geometry.mass import BODY_DENSITY, measure  # noqa: F401 (here since drape's first body; the store's card measures too)

logger = logging.getLogger(__name__)

PRESET_TARGETS: dict[str, dict[str, float]] = {
    "thin": {"height_m": 1.70, "bmi": 18.5},
    "regular": {"height_m": 1.70, "bmi": 23.0},
    "fat": {"height_m": 1.70, "bmi": 31.0},
}
"""Target height [m] and BMI [kg/m^2] of each preset."""

PRESET_NAMES = tuple(PRESET_TARGETS)


def sample_betas(seed: int | np.random.Generator, count: int, shape_dim: int = 10, clip: float = 2.5) -> np.ndarray:
    """β [count, shape_dim] ~ N(0, I) truncated to ±``clip`` (redrawn, not clamped), from a seed."""
    if count < 1 or shape_dim < 1:
        raise InputError(f"count and shape_dim must be positive, got {count} and {shape_dim}")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    out = rng.standard_normal((count, shape_dim))
    bad = np.abs(out) > clip
    while bad.any():
        out[bad] = rng.standard_normal(int(bad.sum()))
        bad = np.abs(out) > clip
    return out


BETA_POPULATION_RANGE = 3.0
"""|β| beyond which a body leaves its shape space's population (β are standard deviations)."""


def preset_betas(model: BodyModel, name: str) -> np.ndarray:
    """β [shape_dim] of a named preset stored in the model's metadata."""
    presets = model.meta.get("presets", {})
    if name not in presets:
        known = ", ".join(sorted(presets)) or "none (this body file carries no presets; pass β instead)"
        raise InputError(f"unknown body preset '{name}'; known presets: {known}")
    return np.asarray(presets[name]["betas"], dtype=np.float64)


def resolve_betas(model: BodyModel, body: str | None = None, betas=None, seed: int | None = None) -> np.ndarray:
    """β [1, shape_dim] from a preset name, explicit values or a seed (exactly one of them)."""
    given = [x is not None for x in (body, betas, seed)]
    if sum(given) > 1:
        raise InputError("give only one of a body preset, β values or a seed")
    if body is not None:
        return preset_betas(model, body)[None]
    if betas is not None:
        b = np.asarray(betas, dtype=np.float64).reshape(1, -1)
        if b.shape[1] > model.shape_dim:
            raise InputError(f"{b.shape[1]} β values given; this body has {model.shape_dim}")
        if not np.isfinite(b).all():
            raise InputError(f"β values must be finite numbers, got {b.ravel().tolist()}")
        out = np.zeros((1, model.shape_dim))
        out[:, : b.shape[1]] = b
        far = np.abs(b[0]) > BETA_POPULATION_RANGE
        if far.any():
            logger.warning("warning: β%s = %s lie beyond ±%g, the range of the shape space's population (β is in "
                           "standard deviations): the body will not look like a person",
                           [int(k) for k in np.flatnonzero(far)], [float(x) for x in b[0][far]], BETA_POPULATION_RANGE)
        return out
    if seed is not None:
        return sample_betas(seed, 1, model.shape_dim)
    return np.zeros((1, model.shape_dim))


