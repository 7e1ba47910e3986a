"""Triangle-mesh topology and vertex normals, on arrays (numpy and torch): the one home of a mesh's
unique edges, its vertex-face incidence and its area-weighted vertex normals.

Why not a library: trimesh poses one mesh at a time (``mean_vertex_normals`` on [V, 3]) and
torch_geometric's ``GenerateMeshNormals`` sums *unit* face normals (not area-weighted) of one
mesh; drape needs the area-weighted normals of many frames at once ([T, V, 3], paper 000's
``n_i``/``n^{b'}`` and PyTorch3D's ``verts_normals``). The vertex-face incidence is trimesh's
``index_sparse`` as a float CSR matrix, so the face-to-vertex sum of every frame is one sparse
product.

Conventions: ``faces`` [F, 3] index vertices 0 .. V - 1; an edge is a vertex pair ``(a, b)`` with
``a < b``; the normal of a face is ``(x_b - x_a) x (x_c - x_a)`` (twice its area times its unit
normal, outward for counter-clockwise winding). Naming follows :mod:`datagen.geometry.rotations`:
``name`` is torch, ``name_np`` numpy.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import torch

__all__ = ["unique_edges", "vertex_face_incidence", "vertex_normals", "vertex_normals_np"]


def unique_edges(faces: np.ndarray, *, return_inverse: bool = False, return_counts: bool = False):
    """The undirected edges of triangles ``faces`` [F, 3], each once: int64 [E, 2] with ``a < b``,
    sorted by (a, b) (the order of ``np.unique(np.sort(e, axis=1), axis=0)``).

    Args:
        faces: triangles [F, 3].
        return_inverse: also return the edge of every half-edge [3F] (int64), the half-edges in
            the order ``faces[:, [0, 1]]``, ``faces[:, [1, 2]]``, ``faces[:, [2, 0]]`` concatenated.
        return_counts: also return the number of faces around each edge [E] (1 on a boundary, 2
            inside a manifold mesh, more where it is non-manifold).

    Returns:
        ``edges``, or the tuple ``(edges, inverse?, counts?)`` of those asked for, in that order.

    The pairs are keyed as ``a * V + b`` and made unique in one dimension (several times faster
    than ``np.unique(..., axis=0)``, same result).
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    half = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    lo, hi = half.min(axis=1), half.max(axis=1)
    base = int(hi.max()) + 1 if len(hi) else 1
    keys, *rest = np.unique(lo * base + hi, return_inverse=True, return_counts=True)
    edges = np.stack([keys // base, keys % base], axis=1)
    out = (edges,) + ((rest[0].reshape(-1),) if return_inverse else ()) + ((rest[1],) if return_counts else ())
    return out if len(out) > 1 else edges


def vertex_face_incidence(faces: np.ndarray, vertex_count: int, dtype=np.float64) -> sp.csr_matrix:
    """Vertex-face incidence [V, F] (CSR, ``dtype``): entry (v, f) is 1 when vertex v is a corner of
    face f (trimesh's ``index_sparse``). ``incidence @ per_face`` sums a per-face quantity over
    each vertex's faces; its rows' column indices are each vertex's faces."""
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    F = len(f)
    return sp.csr_matrix((np.ones(3 * F, dtype=dtype), (f.reshape(-1), np.repeat(np.arange(F), 3))),
                         shape=(int(vertex_count), F))


def vertex_normals_np(vertices: np.ndarray, faces: np.ndarray, *, incidence: sp.spmatrix | None = None
                      ) -> np.ndarray:
    """Area-weighted unit vertex normals [..., V, 3] of a triangle mesh (numpy).

    The normal of vertex i is the normalised sum of ``(x_b - x_a) x (x_c - x_a)`` over its faces;
    a vertex in no face (or only in degenerate ones) gets zeros.

    Args:
        vertices: positions [..., V, 3] (m); leading dimensions are batches (frames). Computed in
            their float dtype (float32 stays float32; integers become float64).
        faces: triangles [F, 3].
        incidence: :func:`vertex_face_incidence` of ``faces`` when the caller keeps one.
    """
    v = np.asarray(vertices)
    if v.dtype.kind != "f":
        v = v.astype(np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    lead, V = v.shape[:-2], v.shape[-2]
    vt = np.ascontiguousarray(np.moveaxis(v.reshape((-1, V, 3)), 1, 0))  # [V, N, 3]: face gathers are blocks
    a = vt[f[:, 0]]
    e1, e2 = vt[f[:, 1]] - a, vt[f[:, 2]] - a
    fn = np.empty_like(a)  # [F, N, 3]
    fn[..., 0] = e1[..., 1] * e2[..., 2] - e1[..., 2] * e2[..., 1]
    fn[..., 1] = e1[..., 2] * e2[..., 0] - e1[..., 0] * e2[..., 2]
    fn[..., 2] = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
    inc = vertex_face_incidence(f, V, v.dtype) if incidence is None else incidence
    n = np.asarray(inc @ fn.reshape(len(f), -1), dtype=v.dtype).reshape(V, -1, 3)
    length = np.sqrt(np.einsum("vnc,vnc->vn", n, n))
    n /= np.where(length > 0, length, np.inf)[..., None]
    return np.moveaxis(n, 0, 1).reshape(lead + (V, 3))


def vertex_normals(vertices: torch.Tensor, faces: torch.Tensor) -> torch.Tensor:
    """Area-weighted unit vertex normals [..., V, 3] of a triangle mesh (torch, any device,
    differentiable): :func:`vertex_normals_np` for vertices [..., V, 3] and faces [F, 3] (long)."""
    lead, V = vertices.shape[:-2], vertices.shape[-2]
    x = vertices.reshape(-1, V, 3)
    tri = x[:, faces]  # [N, F, 3, 3]
    fn = torch.linalg.cross(tri[:, :, 1] - tri[:, :, 0], tri[:, :, 2] - tri[:, :, 0], dim=-1)
    n = x.new_zeros(x.shape)
    for k in range(3):
        n.index_add_(1, faces[:, k], fn)
    n = n / n.norm(dim=-1, keepdim=True).clamp_min(1e-30)
    return n.reshape(*lead, V, 3)
