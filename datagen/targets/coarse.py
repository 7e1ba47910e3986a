"""The coarse target of paper 000: Laplacian smoothing of the simulated (detail) garment.

Paper 000 §5.1: "as in Refs. [VSGC20, PLPM20], we also apply the Laplacian smoothing operator
(with 0.12 diffusion coefficient and 40 iterations) to each generated clothing mesh". The result
``M_coarse`` splits the simulated garment into ``Δ_coarse = M_coarse - I M_b`` (eq. 5, learned by
the coarse generator) and ``Δ_detail = M_detail - M_coarse`` (eq. 9, learned by the detail one).

The smoothing is trimesh's :func:`trimesh.smoothing.filter_laplacian` (explicit diffusion,
``x <- x + λ (L x - x)``, uniform umbrella weights), run with ``lamb=0.12, iterations=40`` and
``volume_constraint=False``, on the operator :func:`laplacian_operator` builds. Two choices, both
from the cited refs and because a garment is an open surface:

- **Boundary** (``boundary="loop"``, the default): a vertex on an open boundary (hem, cuffs,
  neckline) is averaged over its boundary neighbours only, as TailorNet [PLPM20] smooths its
  coarse garments ("boundary vertices are smoothed only by neighbouring boundary vertices in
  order to prevent boundary shrinking"). With all neighbours (``boundary="free"``, exactly
  trimesh's :func:`~trimesh.smoothing.laplacian_calculation`) every opening would creep into the
  garment by centimetres over 40 iterations and that drift would land in ``Δ_detail``.
- **No volume constraint**: trimesh's constraint rescales the whole mesh about its centre of
  mass to restore the enclosed volume, which an open garment does not have.

The operator depends on the faces only, so it is built once per garment and applied to every
frame at once: the frames are the columns of one ``[V, 3 T]`` matrix, and each iteration is one
sparse product, exactly trimesh's update on each frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from datagen.errors import InputError
from datagen.geometry.topology import unique_edges

__all__ = ["SmoothingConfig", "coarse_from_detail", "laplacian_operator", "smooth_vertices"]

_BOUNDARY_MODES = ("loop", "free")


@dataclass(frozen=True, kw_only=True)
class SmoothingConfig:
    """Laplacian smoothing that makes the coarse target (paper 000 §5.1).

    Attributes:
        diffusion: λ, the explicit diffusion step (trimesh's ``lamb``); stable for λ <= 1.
        iterations: number of explicit steps.
        boundary: ``"loop"`` (boundary vertices follow their boundary neighbours only, TailorNet's
            rule) or ``"free"`` (all neighbours, trimesh's own operator).
    """

    diffusion: float = 0.12
    iterations: int = 40
    boundary: str = "loop"

    def __post_init__(self):
        if not (0.0 < self.diffusion <= 1.0):
            raise InputError(f"smoothing diffusion must be in (0, 1] for explicit steps, got {self.diffusion}")
        if int(self.iterations) != self.iterations or self.iterations < 0:
            raise InputError(f"smoothing iterations must be a non-negative integer, got {self.iterations}")
        if self.boundary not in _BOUNDARY_MODES:
            raise InputError(f"smoothing boundary must be one of {_BOUNDARY_MODES}, got {self.boundary!r}")


def laplacian_operator(faces: np.ndarray, vertex_count: int, *, boundary: str = "loop") -> sp.csr_matrix:
    """Row-stochastic umbrella operator L [V, V] (float64, CSR): ``(L x)_i`` is the mean of the
    neighbours of vertex i, so ``L x - x`` is the uniform Laplacian.

    ``boundary="free"`` gives trimesh's ``laplacian_calculation(mesh)`` (all edge neighbours);
    ``boundary="loop"`` replaces the row of every vertex on an open boundary (an edge used by one
    face) by the mean of its neighbours along boundary edges. A vertex with no edge keeps itself.

    Args:
        faces: triangles [F, 3] (int).
        vertex_count: V.
        boundary: ``"loop"`` or ``"free"``.
    """
    if boundary not in _BOUNDARY_MODES:
        raise InputError(f"boundary must be one of {_BOUNDARY_MODES}, got {boundary!r}")
    faces = np.asarray(faces, dtype=np.int64)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InputError(f"faces must be [F, 3], got {faces.shape}")
    if faces.size and (faces.min() < 0 or faces.max() >= vertex_count):
        raise InputError(f"faces index vertices outside 0..{vertex_count - 1}")
    V = int(vertex_count)
    edges, counts = unique_edges(faces, return_counts=True)
    adjacency = _symmetric(edges, V)
    if boundary == "loop":
        border = edges[counts == 1]
        on_border = np.zeros(V, dtype=bool)
        on_border[border.ravel()] = True
        keep = ~on_border
        interior = sp.diags(keep.astype(np.float64)) @ adjacency  # rows of boundary vertices zeroed
        adjacency = (interior + _symmetric(border, V)).tocsr()
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    lonely = degree == 0
    if lonely.any():
        adjacency = (adjacency + sp.diags(lonely.astype(np.float64))).tocsr()
        degree[lonely] = 1.0
    return (sp.diags(1.0 / degree) @ adjacency).tocsr()


def _symmetric(edges: np.ndarray, V: int) -> sp.csr_matrix:
    rows = np.concatenate([edges[:, 0], edges[:, 1]])
    cols = np.concatenate([edges[:, 1], edges[:, 0]])
    m = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(V, V))
    m.data[:] = 1.0  # duplicate edges count once, as in trimesh's boolean adjacency
    return m


def smooth_vertices(vertices: np.ndarray, operator: sp.spmatrix, *, diffusion: float = 0.12,
                    iterations: int = 40) -> np.ndarray:
    """Explicit Laplacian smoothing ``x <- x + λ (L x - x)``, ``iterations`` times, of every frame.

    Args:
        vertices: positions [V, 3] or [T, V, 3] (m).
        operator: L [V, V] from :func:`laplacian_operator`.
        diffusion: λ.
        iterations: number of steps.

    Returns:
        Smoothed positions (m), float64, the shape of ``vertices``.
    """
    x = np.asarray(vertices, dtype=np.float64)
    single = x.ndim == 2
    if single:
        x = x[None]
    if x.ndim != 3 or x.shape[2] != 3:
        raise InputError(f"vertices must be [V, 3] or [T, V, 3], got {np.shape(vertices)}")
    T, V, _ = x.shape
    if operator.shape != (V, V):
        raise InputError(f"operator is {operator.shape} but the mesh has {V} vertices")
    L = operator.tocsr()
    cols = np.array(x.transpose(1, 0, 2).reshape(V, 3 * T), order="C", copy=True)  # frames side by side; never
    # a view of the caller's array, which the in-place update below would overwrite
    for _ in range(int(iterations)):
        cols += diffusion * (L @ cols - cols)
    out = cols.reshape(V, T, 3).transpose(1, 0, 2)
    return out[0] if single else np.ascontiguousarray(out)


def coarse_from_detail(detail: np.ndarray, faces: np.ndarray, config: SmoothingConfig = SmoothingConfig(),
                       *, operator: sp.spmatrix | None = None) -> np.ndarray:
    """Paper 000's coarse garment M_coarse [T, V, 3] (m, float64) from the simulated one.

    Args:
        detail: simulated garment vertices [T, V, 3] (m).
        faces: garment triangles [F, 3].
        config: smoothing parameters (paper: λ = 0.12, 40 iterations).
        operator: a prebuilt :func:`laplacian_operator` for these faces (built here if None).
    """
    detail = np.asarray(detail)
    if detail.ndim != 3 or detail.shape[2] != 3:
        raise InputError(f"detail must be [T, V, 3], got {detail.shape}")
    if operator is None:
        operator = laplacian_operator(faces, detail.shape[1], boundary=config.boundary)
    return smooth_vertices(detail, operator, diffusion=config.diffusion, iterations=config.iterations)
