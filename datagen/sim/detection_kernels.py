"""Warp kernels of the cloth-cloth contact detection: bounds for the BVHs, the vertex-triangle and
edge-edge pair queries with their sorted contact lists, the buffers' needed capacity and each
vertex's conservative move bound (Chen et al. 2024, §3.6), and the segment-triangle crossing test
that the crossing metric and the untangling share. Split from :mod:`datagen.sim.kernels` (the
solve); :mod:`datagen.sim.solver` arranges the launches, :mod:`datagen.sim.metrics` uses the face
bounds. Every array is an explicit argument; the kernels run unchanged on CPU and CUDA."""

from __future__ import annotations

import warp as wp

BIG = 1.0e9
"""The distance of a vertex with no cloth primitive near it (no move bound from contact)."""


@wp.func
def triangle_closest_bary(p: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> wp.vec3:
    """Barycentric weights of the point of triangle abc closest to p (Ericson, RTCD 5.1.5)."""
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = wp.dot(ab, ap)
    d2 = wp.dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return wp.vec3(1.0, 0.0, 0.0)
    bp = p - b
    d3 = wp.dot(ab, bp)
    d4 = wp.dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return wp.vec3(0.0, 1.0, 0.0)
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return wp.vec3(1.0 - v, v, 0.0)
    cp = p - c
    d5 = wp.dot(ab, cp)
    d6 = wp.dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return wp.vec3(0.0, 0.0, 1.0)
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return wp.vec3(1.0 - w, 0.0, w)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return wp.vec3(0.0, 1.0 - w, w)
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return wp.vec3(1.0 - v - w, v, w)


@wp.func
def are_neighbours(a: int, b: int, nbr_offsets: wp.array(dtype=wp.int32), nbr: wp.array(dtype=wp.int32)) -> bool:
    """True when a == b or a and b share a mesh edge (sorted neighbour lists)."""
    if a == b:
        return True
    for k in range(nbr_offsets[a], nbr_offsets[a + 1]):
        if nbr[k] == b:
            return True
    return False


@wp.kernel
def face_bounds(x: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32), lower: wp.array(dtype=wp.vec3),
                upper: wp.array(dtype=wp.vec3)):
    t = wp.tid()
    a = x[faces[t, 0]]
    b = x[faces[t, 1]]
    c = x[faces[t, 2]]
    lower[t] = wp.min(wp.min(a, b), c)
    upper[t] = wp.max(wp.max(a, b), c)


@wp.kernel
def edge_bounds(x: wp.array(dtype=wp.vec3), edges: wp.array2d(dtype=wp.int32), pad: float,
                lower: wp.array(dtype=wp.vec3), upper: wp.array(dtype=wp.vec3)):
    e = wp.tid()
    a = x[edges[e, 0]]
    b = x[edges[e, 1]]
    lower[e] = wp.min(a, b) - wp.vec3(pad)
    upper[e] = wp.max(a, b) + wp.vec3(pad)


@wp.func
def segment_triangle_parameter(p: wp.vec3, q: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> float:
    """Where segment pq crosses triangle abc, as the parameter along pq in [0, 1]; -1 if it does
    not (both ends on one side, or the point outside the triangle)."""
    n = wp.cross(b - a, c - a)
    dp = wp.dot(p - a, n)
    dq = wp.dot(q - a, n)
    if dp * dq > 0.0 or dp == dq:
        return -1.0
    t = dp / (dp - dq)
    r = p + (q - p) * t
    c0 = wp.dot(wp.cross(b - a, r - a), n)
    c1 = wp.dot(wp.cross(c - b, r - b), n)
    c2 = wp.dot(wp.cross(a - c, r - c), n)
    if (c0 >= 0.0 and c1 >= 0.0 and c2 >= 0.0) or (c0 <= 0.0 and c1 <= 0.0 and c2 <= 0.0):
        return t
    return -1.0


@wp.kernel
def detect_vertex_triangle(face_bvh: wp.uint64, x: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3),
                           scene: wp.array(dtype=wp.int32), faces: wp.array2d(dtype=wp.int32),
                           nbr_offsets: wp.array(dtype=wp.int32), nbr: wp.array(dtype=wp.int32),
                           query: float, contact_radius: float, active: wp.array(dtype=wp.int32),
                           vt_count: wp.array(dtype=wp.int32), vt_tri: wp.array2d(dtype=wp.int32),
                           tv_count: wp.array(dtype=wp.int32), tv_vert: wp.array2d(dtype=wp.int32),
                           min_dist: wp.array(dtype=float), order: wp.array(dtype=wp.int32)):
    """Vertex-triangle pairs of the cloth closer than ``contact_radius`` (stored both ways), and
    every vertex's distance to the nearest triangle within ``query`` that is not next to it.

    A triangle next to the vertex (one of its corners is a neighbour) is a contact only when it
    was farther than 1.5x the contact radius in the rest shape (so flat cloth never pushes on
    itself), and does not bound the vertex's move (that would cap every vertex's speed at a
    fraction of an edge length per substep). Thread t takes vertex ``order[t]`` (the lists are
    sorted afterwards and the distances are minima, so the order changes nothing but speed)."""
    i = order[wp.tid()]
    p = x[i]
    lo = p - wp.vec3(query)
    hi = p + wp.vec3(query)
    qry = wp.bvh_query_aabb(face_bvh, lo, hi, wp.bvh_get_group_root(face_bvh, scene[i]))
    t = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    n = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    cap = vt_tri.shape[1]
    cap_t = tv_vert.shape[1]
    while wp.bvh_query_next(qry, t):
        a = faces[t, 0]
        b = faces[t, 1]
        c = faces[t, 2]
        if a == i or b == i or c == i:
            continue
        w = triangle_closest_bary(x[i], x[a], x[b], x[c])
        d = wp.length(x[i] - (x[a] * w[0] + x[b] * w[1] + x[c] * w[2]))
        if d > query:
            continue
        near = are_neighbours(i, a, nbr_offsets, nbr) or are_neighbours(i, b, nbr_offsets, nbr) or are_neighbours(
            i, c, nbr_offsets, nbr)
        if near:
            if d >= contact_radius:
                continue
            wr = triangle_closest_bary(rest[i], rest[a], rest[b], rest[c])
            if wp.length(rest[i] - (rest[a] * wr[0] + rest[b] * wr[1] + rest[c] * wr[2])) < 1.5 * contact_radius:
                continue
        else:
            wp.atomic_min(min_dist, i, d)
            wp.atomic_min(min_dist, a, d)
            wp.atomic_min(min_dist, b, d)
            wp.atomic_min(min_dist, c, d)
        if d < contact_radius:
            if n < cap:
                vt_tri[i, n] = t
            n += 1
            k = wp.atomic_add(tv_count, t, 1)
            if k < cap_t:
                tv_vert[t, k] = i
    vt_count[i] = n


@wp.kernel
def detect_edge_edge(edge_bvh: wp.uint64, x: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3),
                     scene: wp.array(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32),
                     nbr_offsets: wp.array(dtype=wp.int32), nbr: wp.array(dtype=wp.int32), query: float,
                     contact_radius: float, frozen: wp.array(dtype=wp.int32), ee_count: wp.array(dtype=wp.int32),
                     ee_edge: wp.array2d(dtype=wp.int32), min_dist: wp.array(dtype=float),
                     order: wp.array(dtype=wp.int32)):
    """Edge-edge pairs of the cloth closer than ``contact_radius``, stored in both edges' lists
    (``ee_count`` must start at zero; the rows are sorted afterwards); edges next to each other are
    treated as in :func:`detect_vertex_triangle`.

    Each pair is measured once, by the thread of its lower edge: the search box of either edge,
    grown by ``query``, finds the other, so the higher edge's thread skips it. Scenes that are
    ``frozen`` (failed, no longer simulated) are not searched. Thread t takes edge ``order[t]``.
    """
    e = order[wp.tid()]
    a = edges[e, 0]
    b = edges[e, 1]
    if frozen[scene[a]] != 0:
        return
    pa = x[a]
    pb = x[b]
    lo = wp.min(pa, pb) - wp.vec3(query)
    hi = wp.max(pa, pb) + wp.vec3(query)
    qry = wp.bvh_query_aabb(edge_bvh, lo, hi, wp.bvh_get_group_root(edge_bvh, scene[a]))
    f = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    cap = ee_edge.shape[1]
    while wp.bvh_query_next(qry, f):
        if f <= e:
            continue
        c = edges[f, 0]
        d = edges[f, 1]
        if a == c or a == d or b == c or b == d:
            continue
        st = wp.closest_point_edge_edge(pa, pb, x[c], x[d], 1.0e-12)
        dist = st[2]
        if dist > query:
            continue
        near = are_neighbours(a, c, nbr_offsets, nbr) or are_neighbours(a, d, nbr_offsets, nbr) or are_neighbours(
            b, c, nbr_offsets, nbr) or are_neighbours(b, d, nbr_offsets, nbr)
        if near:
            if dist >= contact_radius:
                continue
            sr = wp.closest_point_edge_edge(rest[a], rest[b], rest[c], rest[d], 1.0e-12)
            if sr[2] < 1.5 * contact_radius:
                continue
        else:
            wp.atomic_min(min_dist, a, dist)
            wp.atomic_min(min_dist, b, dist)
            wp.atomic_min(min_dist, c, dist)
            wp.atomic_min(min_dist, d, dist)
        if dist < contact_radius:
            k = wp.atomic_add(ee_count, e, 1)
            if k < cap:
                ee_edge[e, k] = f
            k = wp.atomic_add(ee_count, f, 1)
            if k < cap:
                ee_edge[f, k] = e


@wp.kernel
def sort_lists(count: wp.array(dtype=wp.int32), items: wp.array2d(dtype=wp.int32)):
    """Sort each row's first ``count`` entries (insertion sort: rows are short), so contact sums
    do not depend on the order in which threads appended."""
    r = wp.tid()
    n = wp.min(count[r], items.shape[1])
    for k in range(1, n):
        key = items[r, k]
        j = k - 1
        while j >= 0 and items[r, j] > key:
            items[r, j + 1] = items[r, j]
            j -= 1
        items[r, j + 1] = key


@wp.kernel
def finish_bounds(min_dist: wp.array(dtype=float), fraction: float, floor: float, bound: wp.array(dtype=float)):
    """A vertex with a non-neighbouring cloth primitive within the search distance moves at most
    ``fraction`` of that distance this substep (then no two such primitives can meet). Distances
    below ``floor`` count as ``floor``: primitives that already touch (or crossed) are the contact
    forces' business, and a bound of zero would freeze the vertex for good."""
    i = wp.tid()
    bound[i] = fraction * wp.max(min_dist[i], floor)


@wp.kernel
def count_needed(count: wp.array(dtype=wp.int32), needed: wp.array(dtype=wp.int32), slot: int):
    """The largest list length asked for (to grow the contact buffers when it exceeds them)."""
    i = wp.tid()
    wp.atomic_max(needed, slot, count[i])


BLOCK = 256
"""Threads per block of warp's launches (its default), the block size a register cap is set for."""


def register_capped(kernel, blocks_per_sm: int):
    """A copy of ``kernel`` compiled with CUDA's ``__launch_bounds__(256, blocks_per_sm)``: at most
    65,536 / (256 x ``blocks_per_sm``) registers a thread, so an SM of an sm_90 card keeps that many
    blocks in flight (what does not fit spills to the stack). The same code, so the same results
    (on the CPU the bound is ignored); ``SolverConfig.register_caps`` chooses these copies.
    ``benchmarks/kernel_registers.py`` prints what each one compiles to."""
    return wp.kernel(kernel.func, name=f"{kernel.key}_capped", launch_bounds=(BLOCK, int(blocks_per_sm)))


# the detection's two queries are bound by the threads in flight (600,000 edge threads at 64
# scenes): uncapped they take 94 and 72 registers (512 and 768 threads an SM)
detect_vertex_triangle_capped = register_capped(detect_vertex_triangle, 4)  # 64 registers, 1,024 threads
detect_edge_edge_capped = register_capped(detect_edge_edge, 3)  # at most 85 registers (80 used), 768 threads
