"""What one garment instance on one body needs for paper 000's per-frame features, from the static
arrays a store keeps: the body model shaped by β (:func:`body_shape`), the rows of its subdivided
body (:func:`subdivided_rows`) and a garment's binding to it (:func:`bind_garment`).

The subdivided body (paper 000 §5.1) is the stored body plus one midpoint vertex per edge
(``body/subdivision_edges``): vertex ``B + e`` is the mean of its edge's two vertices in every
quantity linear in the vertices (template, shape directions, skinning weights), and its
triangles are ``body/subdivided_faces``; :func:`datagen.body.subdivide.subdivide_body` builds the
same model. Only the rows that a garment needs are ever made (:func:`bind_garment`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import torch

from datagen.errors import InputError

__all__ = ["BodyShape", "GarmentBinding", "bind_garment", "body_shape", "subdivided_rows"]

def _cached_tensors(owner, device, dtype, floats: tuple[str, ...], ints: tuple[str, ...]) -> dict[str, torch.Tensor]:
    """``owner``'s numpy fields as tensors on ``device`` (floats in ``dtype``, indices int64), made
    once per device and dtype and kept in ``owner._tensors``."""
    key = (str(device), dtype)
    if key not in owner._tensors:
        owner._tensors[key] = {**{n: torch.as_tensor(getattr(owner, n), dtype=dtype, device=device) for n in floats},
                               **{n: torch.as_tensor(getattr(owner, n), dtype=torch.int64, device=device)
                                  for n in ints}}
    return owner._tensors[key]


@dataclass(frozen=True, eq=False)
class BodyShape:
    """The stored body model shaped by one β (numpy, float64).

    Attributes:
        shaped: rest vertices ``T + B_s(β)`` [B, 3] (m).
        rest_joints: ``J(β)`` [J, 3] (m).
        weights: skinning weights [B, J].
        parents: parent of each joint (-1 for the root).
        faces: body triangles [Fb, 3].
        edges: subdivision edges [E, 2] (vertex B + e is their midpoint).
        subdivided_faces: triangles of the subdivided body [Fs, 3] (indices 0 .. B + E - 1).
    """

    shaped: np.ndarray
    rest_joints: np.ndarray
    weights: np.ndarray
    parents: tuple[int, ...]
    faces: np.ndarray
    edges: np.ndarray
    subdivided_faces: np.ndarray
    _tensors: dict = field(default_factory=dict, repr=False)

    @property
    def vertex_count(self) -> int:
        return len(self.shaped)

    @property
    def subdivided_vertex_count(self) -> int:
        return len(self.shaped) + len(self.edges)

    def tensors(self, device, dtype) -> dict[str, torch.Tensor]:
        """``shaped``, ``weights`` and ``rest_joints`` as tensors on ``device`` (made once per device and dtype)."""
        return _cached_tensors(self, device, dtype, ("shaped", "weights", "rest_joints"), ())


def body_shape(body: Mapping[str, np.ndarray], betas) -> BodyShape:
    """The body group of a store (``v_template``, ``shapedirs``, ``J_regressor``, ``weights``,
    ``parents``, ``faces``, ``subdivision_edges``, ``subdivided_faces``) shaped by ``betas`` [S]."""
    b = np.asarray(betas, dtype=np.float64).reshape(-1)
    shapedirs = np.asarray(body["shapedirs"], dtype=np.float64)
    if b.size > shapedirs.shape[2]:
        raise InputError(f"betas has {b.size} values but the body model has {shapedirs.shape[2]} shape directions")
    shaped = np.asarray(body["v_template"], dtype=np.float64) + shapedirs[:, :, :b.size] @ b
    parents = [int(p) for p in np.asarray(body["parents"]).reshape(-1)]
    parents[0] = -1
    return BodyShape(shaped=shaped, rest_joints=np.asarray(body["J_regressor"], dtype=np.float64) @ shaped,
                     weights=np.asarray(body["weights"], dtype=np.float64), parents=tuple(parents),
                     faces=np.asarray(body["faces"], dtype=np.int64),
                     edges=np.asarray(body["subdivision_edges"], dtype=np.int64),
                     subdivided_faces=np.asarray(body["subdivided_faces"], dtype=np.int64))


def subdivided_rows(shape: BodyShape, rows) -> tuple[np.ndarray, np.ndarray]:
    """Rest positions [R, 3] and skinning weights [R, J] of subdivided-body vertices ``rows``."""
    rows = np.asarray(rows, dtype=np.int64)
    B = shape.vertex_count
    if rows.size and (rows.min() < 0 or rows.max() >= shape.subdivided_vertex_count):
        raise InputError(f"subdivided body vertex indices must be in 0 .. {shape.subdivided_vertex_count - 1}, got "
                         f"{int(rows.min())} .. {int(rows.max())}")
    ends = np.where(rows[:, None] < B, rows[:, None], shape.edges[np.maximum(rows - B, 0)])  # [R, 2]
    return shape.shaped[ends].mean(axis=1), shape.weights[ends].mean(axis=1)


@dataclass(frozen=True, eq=False)
class GarmentBinding:
    """What one garment instance on one body needs to derive its features (numpy, float64).

    Attributes:
        body: the shaped body.
        rest: garment rest vertices [V, 3] (m).
        faces: garment triangles [F, 3].
        weights: skinning weights of each garment vertex (its indicator vertex's) [V, J].
        anchor_rest: rest position of each garment vertex's indicator vertex [V, 3] (m).
        ring_rest, ring_weights: the subdivided-body vertices of the triangles around the
            indicator vertices [R, 3], [R, J].
        ring_faces: those triangles, indices into the ring [Fr, 3].
        ring_at: each garment vertex's indicator vertex as a ring index [V].
    """

    body: BodyShape
    rest: np.ndarray
    faces: np.ndarray
    weights: np.ndarray
    anchor_rest: np.ndarray
    ring_rest: np.ndarray
    ring_weights: np.ndarray
    ring_faces: np.ndarray
    ring_at: np.ndarray
    _tensors: dict = field(default_factory=dict, repr=False)

    @property
    def vertex_count(self) -> int:
        return len(self.rest)

    def tensors(self, device, dtype) -> dict[str, torch.Tensor]:
        """The arrays as tensors on ``device`` (made once per device and dtype)."""
        return _cached_tensors(self, device, dtype, ("rest", "weights", "anchor_rest", "ring_rest", "ring_weights"),
                               ("faces", "ring_faces", "ring_at"))


def bind_garment(shape: BodyShape, rest_vertices: np.ndarray, faces: np.ndarray, indicator: np.ndarray
                 ) -> GarmentBinding:
    """The :class:`GarmentBinding` of a garment instance (rest mesh, indicator into the subdivided body)."""
    rest = np.asarray(rest_vertices, dtype=np.float64)
    indicator = np.asarray(indicator, dtype=np.int64)
    if rest.ndim != 2 or rest.shape[1] != 3 or indicator.shape != (len(rest),):
        raise InputError(f"a garment needs rest vertices [V, 3] and an indicator [V]; got {rest.shape} and "
                         f"{indicator.shape}")
    used = np.unique(indicator)
    touched = np.zeros(shape.subdivided_vertex_count, dtype=bool)
    touched[used] = True
    ring = shape.subdivided_faces[touched[shape.subdivided_faces].any(axis=1)]
    rows, local = np.unique(ring, return_inverse=True)
    ring_rest, ring_weights = subdivided_rows(shape, rows)
    at = np.searchsorted(rows, indicator)
    return GarmentBinding(body=shape, rest=rest, faces=np.asarray(faces, dtype=np.int64),
                          weights=ring_weights[at], anchor_rest=ring_rest[at], ring_rest=ring_rest,
                          ring_weights=ring_weights, ring_faces=local.reshape(-1, 3), ring_at=at)
