"""The derived arrays of a stored sample: paper 000's per-frame node features, from what the store keeps.

A dataset store keeps what was simulated and what cannot be recomputed cheaply (garment positions,
the coarse target, pose, translation, joints, labels, metrics) and the static data that the rest is
a function of: the body model with its subdivision recipe, each body's β, each garment instance's
rest mesh and indicator. This module is the one home of that function. The store's reader, the
exporters and the trainers call it; nothing else recomputes these arrays.

=================  =============  ================================================================
name               shape          definition (paper 000)
=================  =============  ================================================================
``joints``         [T, J, 3] m    posed joints, translation included (SMPL's forward kinematics)
``anchor``         [T, V, 3] m    ``I M_b`` (eq. 5): the posed subdivided body vertex each garment
                                  vertex is attached to (indicator I, §4.1)
``anchor_normal``  [T, V, 3]      unit vertex normal of the posed subdivided body there (n^{b'}, §4.3)
``anchor_skin``    [T, V, 3] m    relative skinning feature of that body vertex (p^{b'}, §4.3):
                                  ``Σ_s w_s G_s(θ) G_s(θ*)^-1 p̄`` = ``anchor - trans`` (no pose
                                  blend shapes)
``skin``           [T, V, 3] m    relative skinning feature of the garment vertex (p_i, §4.4): the
                                  same blend of transforms applied to the garment's rest vertex
``coarse_normal``  [T, V, 3]      unit vertex normal of the coarse garment (n_i, §4.4)
``joint_distance`` [T, V, J] m    coarse garment vertex to posed joint distances (x_i, §4.4)
``body_vertices``  [T, B, 3] m    the posed body (SMPL LBS, no pose blend shapes)
=================  =============  ================================================================

The subdivided body (paper 000 §5.1) is the stored body plus one midpoint vertex per edge
(``body/subdivision_edges``): vertex ``B + e`` is the mean of its edge's two vertices in every
quantity linear in the vertices (template, shape directions, skinning weights), and its
triangles are ``body/subdivided_faces``; :func:`datagen.body.subdivide.subdivide_body` builds the
same model. Only the rows that a garment needs are ever made (:func:`bind_garment`).

One implementation in torch serves both worlds: :func:`derive` takes numpy arrays (computed in
float64 on the CPU, returned as float32 numpy) or torch tensors (computed in the tensors' dtype on
their device, returned as tensors), batched over the frames of one sample.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import torch

from datagen.errors import InputError
from datagen.geometry.rotations import axis_angle_to_matrix
from datagen.geometry.skinning import blend_skinning, rigid_transforms
from schemas.dataset import DERIVED

__all__ = [
    "DERIVED",
    "BodyShape",
    "GarmentBinding",
    "bind_garment",
    "body_shape",
    "derive",
    "joint_distances",
    "subdivided_rows",
    "vertex_normals",
]

# ----------------------------------------------------------------------------- static parts


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


# ----------------------------------------------------------------------------- per frame


def _face_normal_sums(vertices: torch.Tensor, faces: torch.Tensor, vertex_count: int) -> torch.Tensor:
    """Σ over incident faces of the face cross product (2 x area x unit normal): [T, V, 3]."""
    tri = vertices[:, faces]  # [T, F, 3, 3]
    fn = torch.linalg.cross(tri[:, :, 1] - tri[:, :, 0], tri[:, :, 2] - tri[:, :, 0], dim=-1)
    out = vertices.new_zeros((vertices.shape[0], vertex_count, 3))
    for k in range(3):
        out.index_add_(1, faces[:, k], fn)
    return out


def _unit(v: torch.Tensor) -> torch.Tensor:
    return v / v.norm(dim=-1, keepdim=True).clamp_min(1e-30)


def vertex_normals(vertices: torch.Tensor, faces: torch.Tensor) -> torch.Tensor:
    """Area-weighted unit vertex normals [T, V, 3] of a triangle mesh [T, V, 3] (torch; zeros for a
    vertex without faces): the normalised sum of ``(x_b - x_a) x (x_c - x_a)`` over its faces."""
    return _unit(_face_normal_sums(vertices, faces, vertices.shape[1]))


def joint_distances(points: torch.Tensor, joints: torch.Tensor) -> torch.Tensor:
    """Distances [..., V, J] from points [..., V, 3] to joints [..., J, 3] (x_i of paper 000 §4.4)."""
    return torch.linalg.vector_norm(points[..., :, None, :] - joints[..., None, :, :], dim=-1)


def _apply(blended: torch.Tensor, points: torch.Tensor) -> torch.Tensor:
    return (blended[..., 0] * points[..., 0:1] + blended[..., 1] * points[..., 1:2]
            + blended[..., 2] * points[..., 2:3] + blended[..., 3])


def derive(binding: GarmentBinding, names: Sequence[str], *, pose=None, trans=None, coarse=None, joints=None
           ) -> dict:
    """The derived arrays ``names`` (see :data:`DERIVED` and the module docstring) of one sample's frames.

    Args:
        binding: the garment instance on its body (:func:`bind_garment`).
        names: which arrays to compute.
        pose: θ [T, J, 3] axis-angle (rad); needed by every name except ``coarse_normal``.
        trans: root translation [T, 3] (m).
        coarse: coarse garment positions [T, V, 3] (m).
        joints: posed joints [T, J, 3] (m), as stored; computed from pose and trans when None.

    Returns:
        name -> array: numpy float32 when the inputs are numpy (computed in float64), tensors of
        the inputs' float dtype on their device otherwise.
    """
    unknown = [n for n in names if n not in DERIVED]
    if unknown:
        raise InputError(f"unknown derived array(s) {unknown}; derived arrays are {list(DERIVED)}")
    given = {"pose": pose, "trans": trans, "coarse": coarse}
    need = {k for n in names for k in DERIVED[n] if k != "joints"} | (
        {"pose", "trans"} if "joint_distance" in names and joints is None else set())
    missing = sorted(k for k in need if given[k] is None)
    if missing:
        raise InputError(f"deriving {list(names)} needs {missing}")
    tensors = [x for x in (pose, trans, coarse, joints) if isinstance(x, torch.Tensor)]
    numpy_out = not tensors
    if numpy_out:
        device, dtype = torch.device("cpu"), torch.float64
    else:
        device = tensors[0].device
        dtype = next((t.dtype for t in tensors if t.is_floating_point()), torch.float32)
    as_t = lambda x: None if x is None else torch.as_tensor(x, dtype=dtype, device=device)  # noqa: E731
    pose, trans, coarse, joints = as_t(pose), as_t(trans), as_t(coarse), as_t(joints)
    g = binding.tensors(device, dtype)
    out: dict[str, torch.Tensor] = {}
    if pose is not None and need & {"pose"}:
        T = pose.shape[0]
        J = len(binding.body.parents)
        if pose.shape != (T, J, 3):
            raise InputError(f"pose must be [T, {J}, 3] axis-angle, got {tuple(pose.shape)}")
        if trans is not None and trans.shape != (T, 3):
            raise InputError(f"trans must be [T={T}, 3], got {tuple(trans.shape)}")
        body = binding.body.tensors(device, dtype)
        posed_joints, rel = rigid_transforms(axis_angle_to_matrix(pose), body["rest_joints"].expand(T, -1, -1),
                                             list(binding.body.parents))
        if joints is None and trans is not None:
            joints = posed_joints + trans[:, None]
        if "joints" in names:
            out["joints"] = posed_joints + trans[:, None]
        if {"anchor", "anchor_skin", "skin"} & set(names):
            blended = (g["weights"] @ rel[:, :, :3, :].reshape(T, J, 12)).reshape(T, -1, 3, 4)
            if {"anchor", "anchor_skin"} & set(names):
                anchor_skin = _apply(blended, g["anchor_rest"])
                if "anchor_skin" in names:
                    out["anchor_skin"] = anchor_skin
                if "anchor" in names:
                    out["anchor"] = anchor_skin + trans[:, None]
            if "skin" in names:
                out["skin"] = _apply(blended, g["rest"])
        if "anchor_normal" in names:
            ring = blend_skinning(g["ring_rest"].expand(T, -1, -1), g["ring_weights"], rel)
            out["anchor_normal"] = _unit(_face_normal_sums(ring, g["ring_faces"], ring.shape[1])[:, g["ring_at"]])
        if "body_vertices" in names:
            out["body_vertices"] = blend_skinning(body["shaped"].expand(T, -1, -1), body["weights"], rel) + trans[:, None]
    if coarse is not None:
        V = binding.vertex_count
        if coarse.ndim != 3 or coarse.shape[1:] != (V, 3):
            raise InputError(f"coarse must be [T, V={V}, 3], got {tuple(coarse.shape)}")
        if "coarse_normal" in names:
            out["coarse_normal"] = vertex_normals(coarse, g["faces"])
        if "joint_distance" in names:
            out["joint_distance"] = joint_distances(coarse, joints)
    out = {n: out[n] for n in names}
    if numpy_out:
        return {n: v.numpy().astype(np.float32) for n, v in out.items()}
    return out
