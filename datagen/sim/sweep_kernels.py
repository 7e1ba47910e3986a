"""The sweep kernel of the vertex block descent (:func:`solve_colour`), several threads per vertex.

A vertex's Newton step sums forces and Hessians over the elements around it: its triangles
(membrane), its hinges (bending), its cloth-cloth contact lists and its body planes. One thread per
vertex walks that chain alone, about 30 elements and up to a few hundred contacts in a fold, and a
launch of one colour (40,000 vertices at 64 scenes) is then one wave of threads whose time the
longest chain sets. Here ``lanes`` consecutive threads of a warp share one vertex (as Newton's VBD
does for its elasticity): lane ``l`` takes the vertex's triangles, hinges, triangles' contact lists
and body planes ``l, l + lanes, ...`` and its own vertex-triangle contacts the same way, and the
lanes' sums are added by warp shuffles in a fixed butterfly (:func:`lane_sum`); lane 0 takes the
step. The order of every sum is fixed by the vertex's own adjacency and contact lists and the lane
count, so a run repeats bitwise and a scene does not depend on its batch.

On a CPU the solver launches one lane per vertex: lane 0 takes every element in the order of a plain
loop, the sums have one term, and the result is bitwise that of the one-thread kernel this replaced.
"""

from __future__ import annotations

import warp as wp

from datagen.sim.detection_kernels import triangle_closest_bary
from datagen.sim.kernels import (bending_force_hessian, body_plane_force_hessian, body_stick_slip,
                                 contact_force_hessian, friction_limit, friction_part, membrane_force_hessian, vec5)

WARP_SIZE = 32
"""Threads of a CUDA warp: the lanes of one vertex lie in one warp, and a launch is padded to whole warps
(every thread of a warp takes part in the shuffles)."""


@wp.func_native(
    """
#if defined(__CUDA_ARCH__)
    float r = v;
    for (int o = lanes >> 1; o > 0; o >>= 1)
        r += __shfl_xor_sync(0xffffffffu, r, o, lanes);
    return r;
#else
    return v;
#endif
"""
)
def lane_sum(v: float, lanes: int) -> float:
    """The sum of ``v`` over the ``lanes`` consecutive threads of a warp that share a vertex (a power
    of two up to 32; every lane gets the same bits: a butterfly of xor shuffles). On a CPU, ``v``."""
    ...


@wp.func
def lane_sum_vec3(v: wp.vec3, lanes: int) -> wp.vec3:
    return wp.vec3(lane_sum(v[0], lanes), lane_sum(v[1], lanes), lane_sum(v[2], lanes))


@wp.func
def lane_sum_mat33(m: wp.mat33, lanes: int) -> wp.mat33:
    return wp.mat33(lane_sum(m[0, 0], lanes), lane_sum(m[0, 1], lanes), lane_sum(m[0, 2], lanes),
                    lane_sum(m[1, 0], lanes), lane_sum(m[1, 1], lanes), lane_sum(m[1, 2], lanes),
                    lane_sum(m[2, 0], lanes), lane_sum(m[2, 1], lanes), lane_sum(m[2, 2], lanes))


@wp.kernel
def solve_colour(
    colour_verts: wp.array(dtype=wp.int32),
    x: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    x_det: wp.array(dtype=wp.vec3),
    inertia_target: wp.array(dtype=wp.vec3),
    mass: wp.array(dtype=float),
    active: wp.array(dtype=wp.int32),
    bound: wp.array(dtype=float),
    damping: wp.array(dtype=float),
    friction: wp.array(dtype=float),
    faces: wp.array2d(dtype=wp.int32),
    dm_inv: wp.array(dtype=wp.mat22),
    tri_area: wp.array(dtype=float),
    tri_stiff: wp.array(dtype=vec5),
    tri_lock: wp.array(dtype=wp.vec2),
    edges: wp.array2d(dtype=wp.int32),
    rest_angle: wp.array(dtype=float),
    bend_k: wp.array(dtype=float),
    v2f_offsets: wp.array(dtype=wp.int32),
    v2f: wp.array2d(dtype=wp.int32),
    v2e_offsets: wp.array(dtype=wp.int32),
    v2e: wp.array2d(dtype=wp.int32),
    body_has: wp.array2d(dtype=wp.int32),
    body_point: wp.array2d(dtype=wp.vec3),
    body_normal: wp.array2d(dtype=wp.vec3),
    body_disp: wp.array2d(dtype=wp.vec3),
    body_radius: wp.array(dtype=float),
    body_lambda: wp.array2d(dtype=float),
    body_k: float,
    vt_count: wp.array(dtype=wp.int32),
    vt_tri: wp.array2d(dtype=wp.int32),
    tv_count: wp.array(dtype=wp.int32),
    tv_vert: wp.array2d(dtype=wp.int32),
    ee_count: wp.array(dtype=wp.int32),
    ee_edge: wp.array2d(dtype=wp.int32),
    self_radius: float,
    self_k: float,
    self_friction: float,
    eps_u: float,
    h: float,
    vertex_area: wp.array(dtype=float),
    body_friction: int,
    friction_pressure: float,
    friction_used: wp.array(dtype=float),
    lanes: int,
    x_out: wp.array(dtype=wp.vec3),
):
    """One Newton step on the local energy of every vertex of one colour (writes ``x_out``), then
    Coulomb friction with the body on that step (:func:`~datagen.sim.kernels.body_stick_slip`).
    Thread t is lane t % ``lanes`` of the colour's vertex t // ``lanes``; the launch may be padded
    past the last vertex (to whole warps), and no thread leaves before the shuffles."""
    tid = wp.tid()
    slot = tid // lanes
    lane = tid - slot * lanes
    valid = slot < colour_verts.shape[0]
    i = int(0)
    if valid:
        i = colour_verts[slot]
    live = valid and active[i] != 0
    xi = x[i]
    m_h2 = mass[i] / (h * h)
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
    if live and lane == 0:
        force = (inertia_target[i] - xi) * m_h2
        hess = wp.identity(n=3, dtype=float) * m_h2
    first_face = v2f_offsets[i + 1]  # a vertex that is not live adds nothing
    first_edge = v2e_offsets[i + 1]
    own_contacts = int(0)
    parts = int(0)
    if live:
        first_face = v2f_offsets[i] + lane
        first_edge = v2e_offsets[i] + lane
        own_contacts = wp.min(vt_count[i], vt_tri.shape[1])
        parts = body_has.shape[1]
    kd = damping[i]
    # membrane
    for k in range(first_face, v2f_offsets[i + 1], lanes):
        fm, hm = membrane_force_hessian(i, v2f[k, 1], v2f[k, 0], x, x_prev, faces, dm_inv, tri_area, tri_stiff,
                                        tri_lock, kd, h)
        force += fm
        hess += hm
    hel = hess  # inertia, membrane and bending: the stiffness friction acts against
    # bending (every edge stencil the vertex belongs to) and edge-edge contacts
    for k in range(first_edge, v2e_offsets[i + 1], lanes):
        e = v2e[k, 0]
        local = v2e[k, 1]
        if edges[e, 2] >= 0 and edges[e, 3] >= 0:
            fb, hb = bending_force_hessian(i, local, e, x, x_prev, edges, rest_angle, bend_k, kd, h)
            force += fb
            hess += hb
            hel += hb
        if local < 2:
            a = edges[e, 0]
            b = edges[e, 1]
            for kk in range(wp.min(ee_count[e], ee_edge.shape[1])):
                f = ee_edge[e, kk]
                c = edges[f, 0]
                d = edges[f, 1]
                st = wp.closest_point_edge_edge(x[a], x[b], x[c], x[d], 1.0e-12)
                es = st[0]
                et = st[1]
                pa = x[a] * (1.0 - es) + x[b] * es
                pb = x[c] * (1.0 - et) + x[d] * et
                dist = wp.length(pa - pb)
                if dist < self_radius and dist > 1.0e-9:
                    n = (pa - pb) / dist
                    we = 1.0 - es
                    if local == 1:
                        we = es
                    rel = ((x[a] - x_prev[a]) * (1.0 - es) + (x[b] - x_prev[b]) * es) - (
                        (x[c] - x_prev[c]) * (1.0 - et) + (x[d] - x_prev[d]) * et)
                    fc, hc = contact_force_hessian(rel, n, self_radius - dist, self_k, self_friction, eps_u, we)
                    force += fc
                    hess += hc
    # vertex-triangle contacts with i as the vertex
    for kk in range(lane, own_contacts, lanes):
        t = vt_tri[i, kk]
        a = faces[t, 0]
        b = faces[t, 1]
        c = faces[t, 2]
        w = triangle_closest_bary(xi, x[a], x[b], x[c])
        p = x[a] * w[0] + x[b] * w[1] + x[c] * w[2]
        dist = wp.length(xi - p)
        if dist < self_radius and dist > 1.0e-9:
            n = (xi - p) / dist
            rel = (xi - x_prev[i]) - ((x[a] - x_prev[a]) * w[0] + (x[b] - x_prev[b]) * w[1] + (x[c] - x_prev[c]) * w[2])
            fc, hc = contact_force_hessian(rel, n, self_radius - dist, self_k, self_friction, eps_u, 1.0)
            force += fc
            hess += hc
    # vertex-triangle contacts with i as a corner of the triangle
    for k in range(first_face, v2f_offsets[i + 1], lanes):
        t = v2f[k, 0]
        local = v2f[k, 1]
        a = faces[t, 0]
        b = faces[t, 1]
        c = faces[t, 2]
        for kk in range(wp.min(tv_count[t], tv_vert.shape[1])):
            j = tv_vert[t, kk]
            w = triangle_closest_bary(x[j], x[a], x[b], x[c])
            p = x[a] * w[0] + x[b] * w[1] + x[c] * w[2]
            dist = wp.length(x[j] - p)
            if dist < self_radius and dist > 1.0e-9:
                n = (p - x[j]) / dist
                rel = ((x[a] - x_prev[a]) * w[0] + (x[b] - x_prev[b]) * w[1] + (x[c] - x_prev[c]) * w[2]) - (
                    x[j] - x_prev[j])
                fc, hc = contact_force_hessian(rel, n, self_radius - dist, self_k, self_friction, eps_u, w[local])
                force += fc
                hess += hc
    # the body: one plane per part (the penalty along its normal; friction with the part that
    # presses hardest projects the step afterwards)
    r = body_radius[i]
    for p in range(lane, parts, lanes):
        if body_has[i, p] == 1:
            fc, hc = body_plane_force_hessian(xi, body_point[i, p], body_normal[i, p], r, body_k)
            force += fc
            hess += hc
    # the lanes' sums (every thread of the warp takes part)
    force = lane_sum_vec3(force, lanes)
    hess = lane_sum_mat33(hess, lanes)
    hel = lane_sum_mat33(hel, lanes)
    if lane != 0 or not valid:
        return
    if not live or wp.abs(wp.determinant(hess)) < 1.0e-20:
        x_out[i] = xi
        return
    dx = wp.inverse(hess) * force
    new = xi + dx
    best = int(-1)
    if body_friction != 0:
        best = friction_part(i, body_has, body_normal, body_lambda)
    if best >= 0:
        limit = friction_limit(i, best, body_lambda, friction, vertex_area, friction_pressure, friction_used)
        new = body_stick_slip(new, x_prev[i], hel, body_normal[i, best], body_disp[i, best], limit)
    move = new - x_det[i]
    L = wp.length(move)
    if L > bound[i]:
        new = x_det[i] + move * (bound[i] / L)
    x_out[i] = new
