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
from datagen.sim.kernel_groups import BodyContact, Bending, Membrane, SelfContact, Substep, Vertices
from datagen.sim.kernels import (bending_force_hessian, body_plane_force_hessian, body_stick_slip, bounded_move,
                                 contact_force_hessian, friction_limit, friction_part, membrane_force_hessian)

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
    verts: Vertices,
    membrane: Membrane,
    bending: Bending,
    body: BodyContact,
    contact: SelfContact,
    sub: Substep,
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
    live = valid and verts.active[i] != 0
    xi = x[i]
    m_h2 = verts.mass[i] / (sub.h * sub.h)
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
    if live and lane == 0:
        force = (sub.inertia_target[i] - xi) * m_h2
        hess = wp.identity(n=3, dtype=float) * m_h2
    first_face = membrane.v2f_offsets[i + 1]  # a vertex that is not live adds nothing
    first_edge = bending.v2e_offsets[i + 1]
    own_contacts = int(0)
    parts = int(0)
    if live:
        first_face = membrane.v2f_offsets[i] + lane
        first_edge = bending.v2e_offsets[i] + lane
        own_contacts = wp.min(contact.vt_count[i], contact.vt_tri.shape[1])
        parts = body.has.shape[1]
    kd = verts.damping[i]
    # membrane
    for k in range(first_face, membrane.v2f_offsets[i + 1], lanes):
        fm, hm = membrane_force_hessian(i, membrane.v2f[k, 1], membrane.v2f[k, 0], x, sub.x_prev, membrane.faces,
                                        membrane.dm_inv, membrane.area, membrane.stiffness, membrane.lock, kd, sub.h)
        force += fm
        hess += hm
    hel = hess  # inertia, membrane and bending: the stiffness friction acts against
    # bending (every edge stencil the vertex belongs to) and edge-edge contacts
    for k in range(first_edge, bending.v2e_offsets[i + 1], lanes):
        e = bending.v2e[k, 0]
        local = bending.v2e[k, 1]
        if bending.edges[e, 2] >= 0 and bending.edges[e, 3] >= 0:
            fb, hb = bending_force_hessian(i, local, e, x, sub.x_prev, bending.edges, bending.rest_angle,
                                           bending.stiffness, kd, sub.h)
            force += fb
            hess += hb
            hel += hb
        if local < 2:
            a = bending.edges[e, 0]
            b = bending.edges[e, 1]
            for kk in range(wp.min(contact.ee_count[e], contact.ee_edge.shape[1])):
                f = contact.ee_edge[e, kk]
                c = bending.edges[f, 0]
                d = bending.edges[f, 1]
                st = wp.closest_point_edge_edge(x[a], x[b], x[c], x[d], 1.0e-12)
                es = st[0]
                et = st[1]
                pa = x[a] * (1.0 - es) + x[b] * es
                pb = x[c] * (1.0 - et) + x[d] * et
                dist = wp.length(pa - pb)
                if dist < contact.radius and dist > 1.0e-9:
                    n = (pa - pb) / dist
                    we = 1.0 - es
                    if local == 1:
                        we = es
                    rel = ((x[a] - sub.x_prev[a]) * (1.0 - es) + (x[b] - sub.x_prev[b]) * es) - (
                        (x[c] - sub.x_prev[c]) * (1.0 - et) + (x[d] - sub.x_prev[d]) * et)
                    fc, hc = contact_force_hessian(rel, n, contact.radius - dist, contact.stiffness, contact.friction,
                                                   sub.eps_u, we)
                    force += fc
                    hess += hc
    # vertex-triangle contacts with i as the vertex
    for kk in range(lane, own_contacts, lanes):
        t = contact.vt_tri[i, kk]
        a = membrane.faces[t, 0]
        b = membrane.faces[t, 1]
        c = membrane.faces[t, 2]
        w = triangle_closest_bary(xi, x[a], x[b], x[c])
        p = x[a] * w[0] + x[b] * w[1] + x[c] * w[2]
        dist = wp.length(xi - p)
        if dist < contact.radius and dist > 1.0e-9:
            n = (xi - p) / dist
            rel = (xi - sub.x_prev[i]) - ((x[a] - sub.x_prev[a]) * w[0] + (x[b] - sub.x_prev[b]) * w[1]
                                          + (x[c] - sub.x_prev[c]) * w[2])
            fc, hc = contact_force_hessian(rel, n, contact.radius - dist, contact.stiffness, contact.friction,
                                           sub.eps_u, 1.0)
            force += fc
            hess += hc
    # vertex-triangle contacts with i as a corner of the triangle
    for k in range(first_face, membrane.v2f_offsets[i + 1], lanes):
        t = membrane.v2f[k, 0]
        local = membrane.v2f[k, 1]
        a = membrane.faces[t, 0]
        b = membrane.faces[t, 1]
        c = membrane.faces[t, 2]
        for kk in range(wp.min(contact.tv_count[t], contact.tv_vert.shape[1])):
            j = contact.tv_vert[t, kk]
            w = triangle_closest_bary(x[j], x[a], x[b], x[c])
            p = x[a] * w[0] + x[b] * w[1] + x[c] * w[2]
            dist = wp.length(x[j] - p)
            if dist < contact.radius and dist > 1.0e-9:
                n = (p - x[j]) / dist
                rel = ((x[a] - sub.x_prev[a]) * w[0] + (x[b] - sub.x_prev[b]) * w[1]
                       + (x[c] - sub.x_prev[c]) * w[2]) - (x[j] - sub.x_prev[j])
                fc, hc = contact_force_hessian(rel, n, contact.radius - dist, contact.stiffness, contact.friction,
                                               sub.eps_u, w[local])
                force += fc
                hess += hc
    # the body: one plane per part (the penalty along its normal; friction with the part that
    # presses hardest projects the step afterwards)
    r = body.radius[i]
    for p in range(lane, parts, lanes):
        if body.has[i, p] == 1:
            fc, hc = body_plane_force_hessian(xi, body.point[i, p], body.normal[i, p], r, body.stiffness)
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
    if body.friction != 0:
        best = friction_part(i, body.has, body.normal, body.lam)
    if best >= 0:
        limit = friction_limit(i, best, body.lam, verts.friction, verts.area, body.friction_pressure,
                               body.friction_used)
        new = body_stick_slip(new, sub.x_prev[i], hel, body.normal[i, best], body.disp[i, best], limit)
    x_out[i] = bounded_move(new, sub.x_det[i], sub.bound_end[i], sub.bound[i])
