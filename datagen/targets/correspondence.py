"""Garment-body correspondence of paper 000 (§4.1): what depends on a garment instance on its body
only, not on frames.

- the indicator I: each garment vertex's closest vertex of the *subdivided* body in the rest pose
  (shaped by β), :func:`garment_indicator`;
- the garment's skinning weights (its indicator vertex's), :func:`garment_skin_weights`;
- the rest-pose distances ``d = ||M̄_g - I M̄_b||`` the fit attribute is made of,
  :func:`garment_body_distances`.

:func:`garment_correspondence` gives all three. The per-frame features built on them are
:mod:`datagen.features` (derived from a store, torch).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from datagen.body.model import BodyModel
from datagen.errors import InputError

__all__ = ["betas_row", "garment_body_distances", "garment_correspondence", "garment_indicator",
           "garment_skin_weights", "rest_body"]


def betas_row(model: BodyModel, betas) -> np.ndarray:
    """β as a float64 row [S] with 1 .. ``model.shape_dim`` values, or an InputError."""
    b = np.asarray(betas, dtype=np.float64).reshape(-1)
    if b.size > model.shape_dim or b.size == 0:
        raise InputError(f"betas must have 1..{model.shape_dim} values, got {b.size}")
    return b


def rest_body(model: BodyModel, betas) -> np.ndarray:
    """The body's shaped rest vertices ``T + B_s(β)`` [V, 3] (m, float64)."""
    return np.asarray(model.shaped(betas_row(model, betas)[None]))[0]


def garment_indicator(garment_rest: np.ndarray, subdivided_model: BodyModel, betas) -> np.ndarray:
    """The indicator I of paper 000 §4.1 as indices: each garment vertex's closest vertex of the
    subdivided body in its rest pose (θ = 0, shaped by β), int32 [V].

    ``I`` in the paper is the one-hot matrix [N_g, N_b] with ``I[i, indicator[i]] = 1``.

    Args:
        garment_rest: garment rest vertices [V, 3] (m), placed on the body in its rest pose.
        subdivided_model: the subdivided body (``BodyModel.subdivided()``), built once by the caller.
        betas: body shape β [S] (or [1, S]).
    """
    g = np.asarray(garment_rest, dtype=np.float64)
    if g.ndim != 2 or g.shape[1] != 3:
        raise InputError(f"garment rest vertices must be [V, 3], got {g.shape}")
    _, idx = cKDTree(rest_body(subdivided_model, betas)).query(g)
    return idx.astype(np.int32)


def garment_skin_weights(indicator: np.ndarray, subdivided_model: BodyModel) -> np.ndarray:
    """Skinning weights of the garment vertices [V, J] (float32): each from its indicator body vertex."""
    return np.asarray(subdivided_model.weights)[np.asarray(indicator)].astype(np.float32)


def garment_body_distances(garment_rest: np.ndarray, body_rest: np.ndarray, indicator: np.ndarray) -> np.ndarray:
    """``d = ||M̄_g - I M̄_b||`` of paper 000 §4.1: rest-pose distance of every garment vertex to its
    indicator body vertex, [V] (m, float64).

    Args:
        garment_rest: garment rest vertices [V, 3] (m).
        body_rest: rest-pose (shaped) subdivided body vertices [N_b, 3] (m).
        indicator: [V] indices into ``body_rest``.
    """
    return np.linalg.norm(np.asarray(garment_rest, dtype=np.float64) - np.asarray(body_rest)[indicator], axis=-1)


def garment_correspondence(garment_rest: np.ndarray, subdivided_model: BodyModel, betas) -> dict[str, np.ndarray]:
    """What depends on the garment instance only (not on frames).

    Returns:
        ``indicator`` int32 [V] (index into the subdivided body's vertices),
        ``skin_weights`` float32 [V, 24] (from the indicator body vertex; rows sum to 1),
        ``body_distance`` float32 [V] (m, the §4.1 distance vector d the fit attribute is made of).
    """
    indicator = garment_indicator(garment_rest, subdivided_model, betas)
    body_rest = rest_body(subdivided_model, betas)
    return {
        "indicator": indicator,
        "skin_weights": garment_skin_weights(indicator, subdivided_model),
        "body_distance": garment_body_distances(garment_rest, body_rest, indicator).astype(np.float32),
    }
