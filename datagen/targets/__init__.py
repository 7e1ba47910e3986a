"""Training targets of paper 000 (coarse smoothing, garment-body correspondence, what a store keeps
per frame, fit attribute), as pure functions on arrays.

- :mod:`datagen.targets.coarse`: the coarse target (Laplacian smoothing, §5.1).
- :mod:`datagen.targets.correspondence`: indicator, skinning weights, rest distances (§4.1).
- :mod:`datagen.targets.stored`: the per-frame arrays a store keeps (coarse, joints); the node
  features built from them are :mod:`datagen.features`.
- :mod:`datagen.targets.fit`: the fit attribute α by factor analysis (§4.1).

See ``docs/targets.md``.
"""

from datagen.targets.coarse import SmoothingConfig, coarse_from_detail, laplacian_operator, smooth_vertices
from datagen.targets.correspondence import (
    garment_body_distances,
    garment_correspondence,
    garment_indicator,
    garment_skin_weights,
)
from datagen.targets.fit import (
    FitAttributeModel,
    FitPair,
    even_subsample,
    factor_scores,
    fit_attribute,
    fit_attribute_model,
    fit_diagnostics,
    fit_pair,
    subsampled_distances,
)
from datagen.targets.stored import skinning_transforms, stored_targets

__all__ = [
    "FitAttributeModel",
    "FitPair",
    "SmoothingConfig",
    "coarse_from_detail",
    "even_subsample",
    "factor_scores",
    "fit_attribute",
    "fit_attribute_model",
    "fit_diagnostics",
    "fit_pair",
    "garment_body_distances",
    "garment_correspondence",
    "garment_indicator",
    "garment_skin_weights",
    "laplacian_operator",
    "skinning_transforms",
    "smooth_vertices",
    "stored_targets",
]
