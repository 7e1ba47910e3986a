"""4-to-1 subdivision of a body model: every triangle split into four at its edge midpoints.

Paper 000 (§5.1) subdivides SMPL once (6,890 -> 27,554 vertices) so that each garment vertex
has a body vertex of its own nearby. The new vertex of edge (a, b) is ``(x_a + x_b) / 2`` for
every quantity that is linear in the vertices: the template, each shape direction, each pose
direction and the skinning weights (which therefore still sum to 1). The original vertices keep
their indices (0..V-1) and the midpoints follow (V..V+E-1), so ``V' = V + E``. The joint
regressor keeps its weights on the original vertices and gives the midpoints zero, which leaves
J(β) exactly as before.

Posing the subdivided model equals subdividing the posed mesh up to a second-order term in the
difference of the two end vertices' weights (LBS is not linear in the weights and the positions
together); :func:`subdivision_posing_error` measures it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from datagen.geometry.topology import unique_edges

if TYPE_CHECKING:  # the model calls this module (BodyModel.subdivided); this one builds its class
    from datagen.body.model import BodyModel


def subdivide_body(model: "BodyModel") -> "BodyModel":
    """The model subdivided once (see the module docstring)."""
    from trimesh.remesh import subdivide

    V = model.vertex_count
    S = model.shape_dim
    attrs = {
        "shapedirs": model.shapedirs.reshape(V, 3 * S),
        "weights": model.weights,
    }
    if model.posedirs is not None:
        P = model.posedirs.shape[0]
        attrs["posedirs"] = model.posedirs.reshape(P, V, 3).transpose(1, 2, 0).reshape(V, 3 * P)
    verts, faces, new = subdivide(model.v_template, model.faces, vertex_attributes=attrs)
    V2 = verts.shape[0]
    posedirs = None
    if model.posedirs is not None:
        P = model.posedirs.shape[0]
        posedirs = new["posedirs"].reshape(V2, 3, P).transpose(2, 0, 1).reshape(P, V2 * 3)
    J_regressor = np.zeros((model.joint_count, V2))
    J_regressor[:, :V] = model.J_regressor
    meta = dict(model.meta)
    meta["subdivision_level"] = int(meta.get("subdivision_level", 0)) + 1
    meta.pop("anny_vertex_index", None)
    return type(model)(
        v_template=verts,
        shapedirs=new["shapedirs"].reshape(V2, 3, S),
        posedirs=posedirs,
        J_regressor=J_regressor,
        weights=new["weights"],
        parents=model.parents.copy(),
        faces=np.asarray(faces, dtype=np.int64),
        meta=meta,
    )


def subdivision_edges(faces: np.ndarray) -> np.ndarray:
    """The edges [E, 2] (int32) whose midpoints :func:`subdivide_body` appends, in its order: vertex
    ``V + e`` of the subdivided model is the midpoint of edge ``e`` (trimesh's unique sorted edges)."""
    from trimesh import grouping
    from trimesh.geometry import faces_to_edges

    edges = np.sort(faces_to_edges(np.asarray(faces, dtype=np.int64)), axis=1)
    unique, _ = grouping.unique_rows(edges)
    return edges[unique].astype(np.int32)


def unique_edge_count(faces: np.ndarray) -> int:
    """Number of distinct undirected edges of a triangle mesh."""
    return len(unique_edges(faces))


def subdivision_posing_error(model: "BodyModel", betas: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Per-vertex distance [B, V'] between posing the subdivided model and subdividing the posed
    mesh (midpoints of the posed coarse vertices), in metres."""
    from trimesh.remesh import subdivide

    fine = model.subdivided()
    posed_fine, _ = fine.pose(betas, pose)
    posed_coarse, _ = model.pose(betas, pose)
    out = []
    for b in range(posed_coarse.shape[0]):
        ref, _ = subdivide(posed_coarse[b], model.faces)
        out.append(np.linalg.norm(posed_fine[b] - ref, axis=-1))
    return np.stack(out)
