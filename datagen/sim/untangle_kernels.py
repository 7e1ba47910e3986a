"""Warp kernels that undo crossings of the cloth with itself: intersection contour minimisation
(Volino and Magnenat-Thalmann 2006, "Resolving surface collisions through intersection contour
minimization").

The contacts keep cloth from crossing itself, but once an edge has passed through a triangle (the
end-of-substep projection out of the body can carry a vertex through another layer; a fast body
can squeeze two layers through each other), a contact only holds each side where it now is: the
crossing stays for good. Where two pieces of cloth cross, they meet along a curve, the
intersection contour, and moving them so that this curve gets shorter pulls them apart until it
vanishes. For an edge E (vertices e0, e1) through a triangle of normal N, each triangle i next to
the edge (normal N_i) carries the contour away from the crossing along R_i = N x N_i, oriented
into that triangle; moving the edge along

    G = sum_i  R_i - 2 (E . R_i) / (E . N) N

(and the triangle against it) shortens the contour (Volino's local gradient; the first term moves
the crossing along the contour, the second slides it along the edge). The solver moves every
vertex of a crossing a small step along the average of its unit gradients before each substep
(``SolverConfig.untangle_step``). The contacts stay on (see that setting for why).

Every array is an explicit argument; the kernels run unchanged on CPU and CUDA.
"""

from __future__ import annotations

import warp as wp

from datagen.sim.detection_kernels import segment_triangle_parameter

PUSH_SCALE = wp.constant(1.0e6)
"""Unit gradients are summed per vertex as integers of 1/PUSH_SCALE: integer atomic sums do not
depend on the order in which threads add them, so a run on CUDA stays bitwise repeatable (float
atomics would not)."""


@wp.func
def contour_gradient(xa: wp.vec3, xb: wp.vec3, n_tri: wp.vec3, has0: int, o0: wp.vec3, has1: int,
                     o1: wp.vec3) -> wp.vec3:
    """Volino's local gradient G for edge (xa, xb) through a triangle of unit normal ``n_tri``: the
    direction to move the edge (the triangle moves against it) that shortens the contour. ``o0``
    and ``o1`` are the corners opposite the edge in its one or two triangles (``has0``/``has1``)."""
    e = xb - xa
    en = wp.dot(e, n_tri)
    g = wp.vec3(0.0)
    if wp.abs(en) < 1.0e-12:
        return g
    ee = wp.dot(e, e)
    for side in range(2):
        o = o0
        has = has0
        if side == 1:
            o = o1
            has = has1
        if has != 0:
            d = o - xa
            w = d - e * (wp.dot(d, e) / ee)  # in the triangle, away from the edge
            ni = wp.cross(e, d)
            r = wp.cross(n_tri, ni)
            rl = wp.length(r)
            if rl > 1.0e-12:
                r = r / rl
                if wp.dot(r, w) < 0.0:
                    r = -r
                g = g + r - n_tri * (2.0 * wp.dot(e, r) / en)
    return g


@wp.kernel
def contour_gradients(face_bvh: wp.uint64, x: wp.array(dtype=wp.vec3), scene: wp.array(dtype=wp.int32),
                      faces: wp.array2d(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32),
                      frozen: wp.array(dtype=wp.int32), only_marked: int, marked: wp.array(dtype=wp.int32),
                      push: wp.array2d(dtype=wp.int32), hits: wp.array(dtype=wp.int32),
                      order: wp.array(dtype=wp.int32)):
    """For every edge of the cloth (``edges`` [E, 4]: its two vertices and the corners opposite it,
    -1 on a border) that crosses a triangle of its own scene: add the unit contour gradient to the
    edge's two vertices' ``push`` and subtract it from the triangle's three (``push`` [N, 3] in
    integer units of 1/:data:`PUSH_SCALE`), and count the crossing at all five (``hits``; a vertex
    with hits > 0 is tangled).

    With ``only_marked`` 0 every edge is queried and ``marked[e]`` says whether edge e crossed
    anything; with 1 only the marked edges are queried (the later iterations of one untangling:
    a quiet batch pays one tree query per substep, not one per iteration). Thread t takes edge
    ``order[t]`` (``SolverVBD.edge_order``; the pushes and counts are integer sums, so the order
    changes nothing but speed)."""
    e = order[wp.tid()]
    if only_marked != 0:
        if marked[e] == 0:
            return
    a = edges[e, 0]
    b = edges[e, 1]
    s = scene[a]
    if frozen[s] != 0:
        return
    xa = x[a]
    xb = x[b]
    qry = wp.bvh_query_aabb(face_bvh, wp.min(xa, xb), wp.max(xa, xb), wp.bvh_get_group_root(face_bvh, s))
    t = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    found = int(0)  # noqa: UP018, RUF046
    while wp.bvh_query_next(qry, t):
        i = faces[t, 0]
        j = faces[t, 1]
        k = faces[t, 2]
        if i == a or i == b or j == a or j == b or k == a or k == b:
            continue
        if segment_triangle_parameter(xa, xb, x[i], x[j], x[k]) < 0.0:
            continue
        n = wp.cross(x[j] - x[i], x[k] - x[i])
        nl = wp.length(n)
        if nl < 1.0e-20:
            continue
        c0 = edges[e, 2]
        c1 = edges[e, 3]
        o0 = xa
        o1 = xa
        if c0 >= 0:
            o0 = x[c0]
        if c1 >= 0:
            o1 = x[c1]
        g = contour_gradient(xa, xb, n / nl, int(c0 >= 0), o0, int(c1 >= 0), o1)
        gl = wp.length(g)
        if gl < 1.0e-9:
            continue
        g = g / gl
        for d in range(3):
            q = int(wp.round(g[d] * PUSH_SCALE))
            wp.atomic_add(push, a, d, q)
            wp.atomic_add(push, b, d, q)
            wp.atomic_add(push, i, d, -q)
            wp.atomic_add(push, j, d, -q)
            wp.atomic_add(push, k, d, -q)
        wp.atomic_add(hits, a, 1)
        wp.atomic_add(hits, b, 1)
        wp.atomic_add(hits, i, 1)
        wp.atomic_add(hits, j, 1)
        wp.atomic_add(hits, k, 1)
        found = 1
    if only_marked == 0:
        marked[e] = found


@wp.kernel
def apply_untangle(push: wp.array2d(dtype=wp.int32), hits: wp.array(dtype=wp.int32),
                   active: wp.array(dtype=wp.int32), step: float, x: wp.array(dtype=wp.vec3)):
    """Moves every tangled vertex by ``step`` times the mean of its unit contour gradients (at
    most ``step``)."""
    i = wp.tid()
    c = hits[i]
    if c == 0 or active[i] == 0:
        return
    g = wp.vec3(float(push[i, 0]), float(push[i, 1]), float(push[i, 2]))
    x[i] = x[i] + g * (step / (float(c) * PUSH_SCALE))
