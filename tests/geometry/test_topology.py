"""The mesh-topology helper: unique edges, vertex-face incidence, area-weighted vertex normals."""

from __future__ import annotations

import numpy as np
import torch
import trimesh

from datagen.geometry.topology import unique_edges, vertex_face_incidence, vertex_normals, vertex_normals_np


def _plain_edges(faces):
    f = np.asarray(faces, dtype=np.int64)
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0, return_inverse=True, return_counts=True)


def test_unique_edges_equal_numpys_row_unique_with_counts():
    mesh = trimesh.creation.icosphere(2)
    open_half = mesh.faces[mesh.triangles_center[:, 2] > 0.1]  # a cap: boundary edges have one face
    for faces in (mesh.faces, open_half, np.array([[0, 1, 2], [2, 1, 3], [1, 0, 4], [0, 1, 5]])):
        ref, ref_inverse, ref_counts = _plain_edges(faces)
        edges, counts = unique_edges(faces, return_counts=True)
        np.testing.assert_array_equal(edges, ref)
        np.testing.assert_array_equal(counts, ref_counts)
        _, inverse, counts = unique_edges(faces, return_inverse=True, return_counts=True)
        np.testing.assert_array_equal(inverse, ref_inverse.reshape(-1))
        np.testing.assert_array_equal(counts, ref_counts)
        np.testing.assert_array_equal(unique_edges(faces), ref)
        assert edges.dtype == np.int64 and (edges[:, 0] < edges[:, 1]).all()
    assert len(unique_edges(mesh.faces)) == len(mesh.edges_unique)  # Euler: E = 3F/2 on a closed mesh
    _, counts = unique_edges(np.array([[0, 1, 2], [2, 1, 3], [1, 0, 4], [0, 1, 5]]), return_counts=True)
    assert counts.max() == 3  # edge (0, 1) is non-manifold


def test_vertex_face_incidence_lists_each_vertexs_faces():
    faces = np.array([[0, 1, 2], [2, 1, 3]])
    inc = vertex_face_incidence(faces, 5)
    assert inc.shape == (5, 2)
    assert [sorted(inc[v].indices.tolist()) for v in range(5)] == [[0], [0, 1], [0, 1], [1], []]


def test_vertex_normals_equal_a_plain_loop_in_numpy_and_torch():
    mesh = trimesh.creation.icosphere(1)
    rng = np.random.default_rng(1)
    v = mesh.vertices[None] * (1 + 0.1 * rng.random((2, len(mesh.vertices), 1)))
    ours = vertex_normals_np(v, mesh.faces)
    ours_t = vertex_normals(torch.as_tensor(v), torch.as_tensor(mesh.faces, dtype=torch.long)).numpy()
    for t in range(2):
        ref = np.zeros_like(v[t])
        for a, b, c in mesh.faces:
            n = np.cross(v[t, b] - v[t, a], v[t, c] - v[t, a])
            for i in (a, b, c):
                ref[i] += n
        ref /= np.linalg.norm(ref, axis=1, keepdims=True)
        np.testing.assert_allclose(ours[t], ref, atol=1e-12)
        np.testing.assert_allclose(ours_t[t], ref, atol=1e-12)
    assert (np.einsum("ij,ij->i", ours[0], mesh.vertices) > 0).all()  # outward
    # one frame [V, 3] and float32 keep their shape and dtype; a vertex in no face gets zeros
    one = vertex_normals_np(np.vstack([v[0], [[9.0, 9, 9]]]).astype(np.float32), mesh.faces)
    assert one.shape == (len(mesh.vertices) + 1, 3) and one.dtype == np.float32
    np.testing.assert_allclose(one[:-1], ours[0], atol=1e-6)
    assert not one[-1].any()
