"""The fit attribute α of paper 000 §4.1: factor analysis of garment-body rest distances.

For each garment-body pair in the rest pose, ``d = ||M̄_g - I M̄_b||`` [N_g] is the distance of
every garment vertex to its indicator body vertex (:func:`~datagen.targets.correspondence.garment_body_distances`).
Garments have different vertex counts, so each ``d`` is cut to a common length N_g* by choosing
vertices evenly over the garment (:func:`even_subsample`, the paper's rule: reject vertices closer
than ``r = sqrt(A_g / (C N_g*))``, raising the integer C until N_g* remain). The vectors of the
training pairs form D (the paper's [N_g*, N_pair]; here stored as rows, [N_pair, N_g*], as
scikit-learn wants), and factor analysis with F = 3 factors, ``D - μ ≈ L A`` (eq. 3), gives each
pair its fit attribute α [3] = its factor scores.

Determinism and layout:

- The subsample visits vertices in the order of a permutation drawn from an explicit ``seed``
  (greedy rejection is order dependent), keeps the first N_g* accepted, and lists the kept
  vertices from the top of the garment down (height, then azimuth about the garment's vertical
  axis), so that entry k of ``d*`` means roughly the same place (the k-th height quantile) on
  every garment. Same vertices, faces, N_g* and seed give the same indices.
- The factor analysis is :class:`sklearn.decomposition.FactorAnalysis` with its SVD-based
  likelihood maximisation (the paper's "SVD-based likelihood optimisation"), ``svd_method="lapack"``
  (exact SVD: deterministic, and cheap at these sizes; ``"randomized"`` is the faster option
  for very large D and takes the explicit ``random_state``). Each factor's sign is fixed so that
  its loadings sum to >= 0 (a larger score means larger distances along the factor).
- Fitting takes the training pairs and nothing else (:func:`fit_attribute_model`); the fitted
  model is a set of plain arrays (``components`` [3, N_g*], ``mean`` [N_g*], ``noise_variance``
  [N_g*], ``subsample`` int64 [3] = (algorithm version, N_g*, seed)) and
  :func:`fit_attribute` applies it to any pair from those arrays alone.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from datagen.body.model import BodyModel
from datagen.errors import InputError

__all__ = [
    "FitAttributeModel",
    "FitPair",
    "SUBSAMPLE_VERSION",
    "even_subsample",
    "factor_scores",
    "fit_attribute",
    "fit_attribute_model",
    "fit_pair",
    "subsampled_distances",
]

SUBSAMPLE_VERSION = 1
"""Version of :func:`even_subsample`'s rule, stored with a fitted model."""

_MAX_RADIUS_STEPS = 100_000


# ----------------------------------------------------------------------------- pairs and subsampling

@dataclass(frozen=True, eq=False)
class FitPair:
    """One garment-body pair in the rest pose.

    Attributes:
        vertices: garment rest vertices [V, 3] (m).
        faces: garment triangles [F, 3].
        distances: d [V] (m): each garment vertex's distance to its indicator body vertex.
    """

    vertices: np.ndarray
    faces: np.ndarray
    distances: np.ndarray

    def __post_init__(self):
        v, f, d = np.asarray(self.vertices), np.asarray(self.faces), np.asarray(self.distances)
        if v.ndim != 2 or v.shape[1] != 3:
            raise InputError(f"fit pair vertices must be [V, 3], got {v.shape}")
        if f.ndim != 2 or f.shape[1] != 3:
            raise InputError(f"fit pair faces must be [F, 3], got {f.shape}")
        if d.shape != (v.shape[0],):
            raise InputError(f"fit pair distances must be [V={v.shape[0]}], got {d.shape}")
        if not np.isfinite(d).all():
            raise InputError("fit pair distances must be finite")

    @property
    def vertex_count(self) -> int:
        return int(np.asarray(self.vertices).shape[0])


def fit_pair(garment_rest: np.ndarray, faces: np.ndarray, subdivided_model: BodyModel, betas,
             indicator: np.ndarray | None = None) -> FitPair:
    """The :class:`FitPair` of a garment instance on its body (indicator computed if None)."""
    from datagen.targets.correspondence import garment_body_distances, garment_indicator

    if indicator is None:
        indicator = garment_indicator(garment_rest, subdivided_model, betas)
    body_rest = np.asarray(subdivided_model.shaped(np.asarray(betas, dtype=np.float64).reshape(1, -1)))[0]
    return FitPair(vertices=np.asarray(garment_rest, dtype=np.float64), faces=np.asarray(faces, dtype=np.int64),
                   distances=garment_body_distances(garment_rest, body_rest, indicator))


def _area(vertices: np.ndarray, faces: np.ndarray) -> float:
    tri = vertices[faces]
    return float(0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())


def _greedy(points: np.ndarray, order: np.ndarray, tree: cKDTree, radius: float) -> np.ndarray:
    """Visit ``order``; keep a vertex unless a kept one lies closer than ``radius``."""
    neighbours = tree.query_ball_point(points[order], radius, return_sorted=False)
    removed = np.zeros(len(points), dtype=bool)
    keep = []
    for i, near in zip(order, neighbours):
        if removed[i]:
            continue
        keep.append(i)
        removed[near] = True
    return np.asarray(keep, dtype=np.int64)


def even_subsample(vertices: np.ndarray, faces: np.ndarray, count: int, *, seed: int = 0) -> np.ndarray:
    """N_g* = ``count`` vertex indices spread evenly over a garment (paper 000 §4.1), int64 [count].

    Visits the vertices in a seeded random order and rejects every vertex closer than
    ``r = sqrt(A_g / (C count))`` to one already kept (A_g: the mesh area), for C = 1, 2, ...
    until at least ``count`` are kept; keeps the first ``count`` accepted and returns them from
    the top of the garment down (descending y, then azimuth about the vertical axis through the
    vertex centroid). Deterministic: same inputs, same indices.

    Args:
        vertices: rest vertices [V, 3] (m).
        faces: triangles [F, 3].
        count: N_g*, 1 <= count <= V.
        seed: seeds the visiting order.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    V = len(vertices)
    if not 1 <= int(count) <= V:
        raise InputError(f"cannot choose {count} of {V} garment vertices; N_g* must be at most the garment's "
                         f"vertex count (refit the fit model with a smaller subsample count, e.g. the smallest "
                         f"garment of the whole dataset)")
    count = int(count)
    order = np.random.default_rng(seed).permutation(V)
    if count == V:
        keep = order
    else:
        area = _area(vertices, faces)
        tree = cKDTree(vertices)
        for C in range(1, _MAX_RADIUS_STEPS + 1):
            keep = _greedy(vertices, order, tree, np.sqrt(area / (C * count)))
            if len(keep) >= count:
                break
        else:  # coincident vertices: no radius separates enough of them
            keep = order
        keep = keep[:count]
    p = vertices[keep]
    centre = vertices.mean(axis=0)
    azimuth = np.arctan2(p[:, 0] - centre[0], p[:, 2] - centre[2])
    return keep[np.lexsort((azimuth, -p[:, 1]))]


def subsampled_distances(pair: FitPair, count: int, seed: int) -> np.ndarray:
    """d* [count] (m): the pair's distances at :func:`even_subsample`'s vertices."""
    idx = even_subsample(pair.vertices, pair.faces, count, seed=seed)
    return np.asarray(pair.distances, dtype=np.float64)[idx]


# ----------------------------------------------------------------------------- factor analysis

def factor_scores(distances: np.ndarray, components: np.ndarray, mean: np.ndarray,
                  noise_variance: np.ndarray) -> np.ndarray:
    """Posterior mean of the factors (what ``FactorAnalysis.transform`` computes), from arrays.

    ``α = (x - μ) Ψ^-1 Lᵀ (I + L Ψ^-1 Lᵀ)^-1`` with L = ``components`` [F, N], Ψ = diag(noise_variance).

    Args:
        distances: d* [..., N] (m).
        components: loadings [F, N].
        mean: μ [N] (m).
        noise_variance: Ψ [N] (m²).

    Returns:
        α [..., F].
    """
    components = np.asarray(components, dtype=np.float64)
    w_psi = components / np.asarray(noise_variance, dtype=np.float64)
    cov_z = np.linalg.inv(np.eye(len(components)) + w_psi @ components.T)
    return ((np.asarray(distances, dtype=np.float64) - np.asarray(mean, dtype=np.float64)) @ w_psi.T) @ cov_z


@dataclass(frozen=True, eq=False)
class FitAttributeModel:
    """A fitted fit-attribute model: plain arrays (see :meth:`as_arrays`).

    Attributes:
        components: factor loadings L [F, N_g*] (m per unit factor).
        mean: μ [N_g*] (m).
        noise_variance: Ψ [N_g*] (m²).
        subsample: int64 [3]: (:data:`SUBSAMPLE_VERSION`, N_g*, subsample seed).
    """

    components: np.ndarray
    mean: np.ndarray
    noise_variance: np.ndarray
    subsample: np.ndarray

    def __post_init__(self):
        c = np.asarray(self.components)
        n = c.shape[1] if c.ndim == 2 else -1
        s = np.asarray(self.subsample)
        ok = (c.ndim == 2 and np.shape(self.mean) == (n,) and np.shape(self.noise_variance) == (n,)
              and s.shape == (3,) and np.issubdtype(s.dtype, np.integer) and int(s[1]) == n)
        if not ok:
            raise InputError(f"inconsistent fit model arrays: components {c.shape}, mean {np.shape(self.mean)}, "
                             f"noise_variance {np.shape(self.noise_variance)}, subsample {s.tolist()}")
        if int(s[0]) != SUBSAMPLE_VERSION:
            raise InputError(f"fit model uses subsample rule version {int(s[0])}; this drape knows "
                             f"{SUBSAMPLE_VERSION}: refit the model")

    @property
    def factor_count(self) -> int:
        return int(np.asarray(self.components).shape[0])

    @property
    def subsample_count(self) -> int:
        return int(self.subsample[1])

    @property
    def subsample_seed(self) -> int:
        return int(self.subsample[2])

    def as_arrays(self) -> dict[str, np.ndarray]:
        """``components`` [F, N] float64, ``mean`` [N], ``noise_variance`` [N], ``subsample`` int64 [3]."""
        return {"components": np.asarray(self.components, dtype=np.float64),
                "mean": np.asarray(self.mean, dtype=np.float64),
                "noise_variance": np.asarray(self.noise_variance, dtype=np.float64),
                "subsample": np.asarray(self.subsample, dtype=np.int64)}

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, np.ndarray]) -> FitAttributeModel:
        missing = {"components", "mean", "noise_variance", "subsample"} - set(arrays)
        if missing:
            raise InputError(f"fit model arrays lack {sorted(missing)}")
        return cls(components=np.asarray(arrays["components"], dtype=np.float64),
                   mean=np.asarray(arrays["mean"], dtype=np.float64),
                   noise_variance=np.asarray(arrays["noise_variance"], dtype=np.float64),
                   subsample=np.asarray(arrays["subsample"], dtype=np.int64))


def fit_attribute_model(train_pairs: Sequence[FitPair], *, factor_count: int = 3, subsample_count: int | None = None,
                        subsample_seed: int = 0, svd_method: str = "lapack", random_state: int = 0,
                        max_iter: int = 1000, tol: float = 1e-2) -> FitAttributeModel:
    """Fit paper 000's factor analysis (eq. 3) on the training split's garment-body pairs only.

    The caller passes the training pairs and nothing else; :func:`fit_attribute` then gives every
    pair (training, validation, test) its α.

    Args:
        train_pairs: the training split's :class:`FitPair` s.
        factor_count: F (paper: 3).
        subsample_count: N_g*; default the smallest training garment's vertex count. The paper
            takes the smallest garment of the whole dataset: pass that (a vertex count, no
            target leaks through it) when validation or test garments are smaller.
        subsample_seed: seeds :func:`even_subsample`'s visiting order.
        svd_method: scikit-learn's ``"lapack"`` (exact) or ``"randomized"``.
        random_state: seed for ``"randomized"``.
        max_iter, tol: scikit-learn's likelihood iteration limits.
    """
    from sklearn.decomposition import FactorAnalysis
    from threadpoolctl import threadpool_limits

    pairs = list(train_pairs)
    if len(pairs) <= factor_count:
        raise InputError(f"factor analysis with {factor_count} factors needs more than {factor_count} training "
                         f"pairs, got {len(pairs)}")
    if svd_method not in ("lapack", "randomized"):
        raise InputError(f"svd_method must be 'lapack' or 'randomized', got {svd_method!r}")
    count = min(p.vertex_count for p in pairs) if subsample_count is None else int(subsample_count)
    if count <= factor_count:
        raise InputError(f"N_g* = {count} must exceed the factor count {factor_count}")
    X = np.stack([subsampled_distances(p, count, subsample_seed) for p in pairs])  # [N_pair, N_g*]
    # The SVDs are small ([N_pair, N_g*]); threaded BLAS only adds synchronisation, which on a loaded
    # 2-core machine made each SVD ~200x slower (0.6 s instead of 3 ms for 300 x 64). One thread.
    with threadpool_limits(limits=1, user_api="blas"):
        fa = FactorAnalysis(n_components=factor_count, svd_method=svd_method, random_state=random_state,
                            max_iter=max_iter, tol=tol).fit(X)
    sign = np.where(fa.components_.sum(axis=1) < 0, -1.0, 1.0)
    return FitAttributeModel(components=fa.components_ * sign[:, None], mean=fa.mean_.copy(),
                             noise_variance=fa.noise_variance_.copy(),
                             subsample=np.array([SUBSAMPLE_VERSION, count, subsample_seed], dtype=np.int64))


def fit_attribute(model: FitAttributeModel | Mapping[str, np.ndarray], pair: FitPair) -> np.ndarray:
    """The fit attribute α [F] (float64) of one garment-body pair, from the model's arrays alone."""
    if not isinstance(model, FitAttributeModel):
        model = FitAttributeModel.from_arrays(model)
    d_star = subsampled_distances(pair, model.subsample_count, model.subsample_seed)
    return factor_scores(d_star, model.components, model.mean, model.noise_variance)


NOISE_FLOOR = 1e-11
"""Noise variance (m²) at or below which a feature counts as saturated: scikit-learn clips Ψ at 1e-12."""

PAIR_MARGIN = 5
"""A fit with fewer than factors + this many training pairs is flagged as having too few pairs."""


def fit_diagnostics(train_pairs: Sequence[FitPair], all_pairs: Sequence[FitPair], model: FitAttributeModel, *,
                    seeds: Sequence[int] = (1, 2, 3), random_state: int = 0) -> dict:
    """How far a fitted model can be trusted: JSON data recorded in the store (``fit_diagnostics``).

    Returns:
        ``pairs``, ``factors``, ``features`` (N_g*); ``saturated_features`` (noise variance at
        scikit-learn's floor: the factors explain those features exactly, a sign of too few pairs);
        ``alpha_seed_spread`` [F]: the largest change of each α component over ``all_pairs`` when the
        model is fitted again with the subsample seed moved by each of ``seeds`` (each refitted
        factor's sign matched to the original's); ``warnings``: what a user should know, in words.
    """
    F, N = model.factor_count, model.subsample_count
    base = np.stack([fit_attribute(model, p) for p in all_pairs])
    spread = np.zeros(F)
    for k in seeds:
        other = fit_attribute_model(train_pairs, factor_count=F, subsample_count=N,
                                    subsample_seed=model.subsample_seed + int(k), random_state=random_state)
        alpha = np.stack([fit_attribute(other, p) for p in all_pairs])
        sign = np.where(np.sum(alpha * base, axis=0) < 0, -1.0, 1.0)
        spread = np.maximum(spread, np.abs(alpha * sign - base).max(axis=0))
    saturated = int(np.count_nonzero(np.asarray(model.noise_variance) <= NOISE_FLOOR))
    out = {"pairs": len(train_pairs), "factors": F, "features": N, "saturated_features": saturated,
           "alpha_seed_spread": [float(x) for x in spread], "alpha_range": [float(x) for x in np.ptp(base, axis=0)],
           "warnings": []}
    if len(train_pairs) < F + PAIR_MARGIN:
        out["warnings"].append(f"only {len(train_pairs)} training garment-body pairs for {F} factors (fewer than "
                               f"{F + PAIR_MARGIN}): the factor analysis is underdetermined")
    if saturated:
        out["warnings"].append(f"{saturated} of {N} features have noise variance at the floor ({NOISE_FLOOR:g} m²): "
                               "the model is saturated (it reproduces the training pairs exactly)")
    unstable = [i for i in range(F) if spread[i] > 0.1 * max(float(np.ptp(base[:, i])), 1e-12)]
    if unstable:
        out["warnings"].append("α is unstable across subsample seeds: component(s) "
                               + ", ".join(f"α{i + 1} moves by {spread[i]:.3g}" for i in unstable)
                               + " (more than 10 % of its range over the pairs)")
    return out
