"""Training targets and node features of paper 000 (coarse smoothing, indicator, anchors,
relative skinning features, joint distances, fit attribute), as pure functions on arrays.

- :mod:`datagen.targets.coarse`: the coarse target (Laplacian smoothing, §5.1).
- :mod:`datagen.targets.features`: indicator, anchor, normals, skinning features, joint distances
  (§4.1-4.4); :func:`sample_targets` for one sample.
- :mod:`datagen.targets.fit`: the fit attribute α by factor analysis (§4.1).

See ``docs/targets.md``.
"""

from datagen.targets.coarse import SmoothingConfig, coarse_from_detail, laplacian_operator, smooth_vertices
from datagen.targets.features import (
    TARGET_NAMES,
    garment_body_distances,
    garment_correspondence,
    garment_indicator,
    garment_skin_weights,
    joint_distances,
    pose_body_rows,
    relative_skinning,
    sample_targets,
    skinning_transforms,
    stored_targets,
    vertex_normals,
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

__all__ = [
    "TARGET_NAMES",
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
    "joint_distances",
    "laplacian_operator",
    "pose_body_rows",
    "relative_skinning",
    "sample_targets",
    "skinning_transforms",
    "smooth_vertices",
    "stored_targets",
    "vertex_normals",
]
