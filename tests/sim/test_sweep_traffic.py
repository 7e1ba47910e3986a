"""``benchmarks/sweep_traffic.py`` counts a sweep launch's loads from the topology: checked against
counts taken another way (which triangles and edge stencils hold the vertex) on a small grid."""

from __future__ import annotations

import numpy as np

from datagen.sim.model import ClothModelBuilder
from tests.sim.meshes import grid

OWN = 4 + 12 + 4 + 12 + 4 + 4 + 4 + 12 + 4 + 12  # active, x, mass, y, vt_count, damping, radius, centre, bound, x_prev
"""Bytes the kernel loads of a vertex's own arrays."""


def _host():
    v, f = grid(6, 6, 0.02)
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name="cotton")
    b.add_body(v[:3] - [0.0, 1.0, 0.0], np.array([[0, 1, 2]]))
    m = b.finalize("cpu")
    return m.host, m.body_part_count


def test_one_vertex_requested_bytes_match_its_triangles_and_stencils():
    from benchmarks.sweep_traffic import colour_traffic

    h, parts = _host()
    faces, edges = np.asarray(h.faces), np.asarray(h.edges)
    i = 14  # an interior vertex of the 6 x 6 grid
    tris = int(np.any(faces == i, axis=1).sum())
    in_stencil = np.any(edges[:, :4] == i, axis=1)
    hinges = int((in_stencil & (edges[:, 2] >= 0) & (edges[:, 3] >= 0)).sum())
    as_endpoint = int(np.any(edges[:, :2] == i, axis=1).sum())
    assert tris == 6 and as_endpoint == 6  # the grid's interior valence
    expected = (4 + OWN + 2 * 8 + parts * 4 + 12  # colour entry, own arrays, offsets, body flags, the store
                + tris * (2 * (8 + 12) + 4 + 3 * 12 * 2 + 16 + 20 + 4)  # v2f and faces twice, tv_count, corners, shape
                + int(in_stencil.sum()) * (8 + 16)  # v2e and edges
                + hinges * (4 * 12 * 2 + 4 + 4)  # the stencil's x and x_prev, bend_k, rest_angle
                + as_endpoint * 4)  # ee_count of the edges it ends
    assert colour_traffic(h, np.array([i]), parts).requested == expected


def test_a_colour_of_every_vertex_touches_every_position_sector():
    from benchmarks.sweep_traffic import SECTOR, colour_traffic

    h, parts = _host()
    n = len(h.rest_positions)
    t = colour_traffic(h, np.arange(n), parts)
    assert len(t.sectors["x"]) == -(-n * 12 // SECTOR)
    assert len(t.sectors["x_out"]) == -(-n * 12 // SECTOR)
    assert t.unique() <= t.requested + SECTOR * len(t.sectors)
