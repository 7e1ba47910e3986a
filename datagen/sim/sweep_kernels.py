"""The sweep kernel of the vertex block descent (:func:`solve_colour`), one block of threads per vertex.

A vertex's Newton step sums forces and Hessians over the elements around it: its triangles
(membrane), its hinges (bending), its cloth-cloth contact lists and its body planes. One thread per
vertex walks that chain alone, about 30 elements and up to a few hundred contacts in a fold, and a
launch of one colour (40,000 vertices at 64 scenes) is then one wave of threads whose time the
longest chain sets. Here a block of ``lanes`` threads shares one vertex (as Newton's VBD does for
its elasticity): lane ``l`` takes the vertex's triangles, hinges, triangles' contact lists and body
planes ``l, l + lanes, ...`` and its own vertex-triangle contacts the same way; the block's sums are
added by warp's tile reduction in a fixed tree, and lane 0 takes the step. The order of every sum
is fixed by the vertex's own adjacency and contact lists and the block size, so a run repeats
bitwise and a scene does not depend on its batch.

On a CPU a block is one thread (warp's default): lane 0 takes every element in the order of a
plain loop, and the tile sums have one term, so the result is bitwise that of one thread per
vertex. Its own module, compiled for blocks of :data:`SWEEP_LANES` (``SolverConfig.sweep_lanes``
picks other sizes, each compiled when first launched).
"""

from __future__ import annotations

import warp as wp

from datagen.sim.detection_kernels import triangle_closest_bary
from datagen.sim.kernels import (bending_force_hessian, body_stick_slip, contact_force_hessian, friction_limit,
                                 friction_part, membrane_force_hessian, vec5)

SWEEP_LANES = 16
"""Threads per vertex in the sweeps on a GPU (``SolverConfig.sweep_lanes``' default)."""

wp.set_module_options({"block_dim": SWEEP_LANES})


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
    x_out: wp.array(dtype=wp.vec3),
):
    """One Newton step on the local energy of every vertex of one colour (writes ``x_out``), then
    Coulomb friction with the body on that step (:func:`~datagen.sim.kernels.body_stick_slip`).
    Launched with ``wp.launch_tiled(dim=[vertices of the colour], block_dim=lanes)``."""
    slot, lane = wp.tid()
    lanes = wp.block_dim()
    i = colour_verts[slot]
    xi = x[i]
    if active[i] == 0:  # the whole block: one vertex
        if lane == 0:
            x_out[i] = xi
        return
    m_h2 = mass[i] / (h * h)
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
    if lane == 0:
        force = (inertia_target[i] - xi) * m_h2
        hess = wp.identity(n=3, dtype=float) * m_h2
    kd = damping[i]
    # membrane
    for k in range(v2f_offsets[i] + lane, v2f_offsets[i + 1], lanes):
        fm, hm = membrane_force_hessian(i, v2f[k, 1], v2f[k, 0], x, x_prev, faces, dm_inv, tri_area, tri_stiff,
                                        tri_lock, kd, h)
        force += fm
        hess += hm
    hel = hess  # inertia, membrane and bending: the stiffness friction acts against
    # bending (every edge stencil the vertex belongs to) and edge-edge contacts
    for k in range(v2e_offsets[i] + lane, v2e_offsets[i + 1], lanes):
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
    for kk in range(lane, wp.min(vt_count[i], vt_tri.shape[1]), lanes):
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
    for k in range(v2f_offsets[i] + lane, v2f_offsets[i + 1], lanes):
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
    for p in range(lane, body_has.shape[1], lanes):
        if body_has[i, p] == 1:
            n = body_normal[i, p]
            dist = wp.dot(xi - body_point[i, p], n)
            if dist < r:
                fc, hc = contact_force_hessian(wp.vec3(0.0), n, r - dist, body_k, 0.0, eps_u, 1.0)
                force += fc
                hess += hc
    # the block's sums (every lane reaches them: the branches above are per lane, the returns per block)
    force = wp.tile_sum(wp.tile(force, preserve_type=True))[0]
    hess = wp.tile_sum(wp.tile(hess, preserve_type=True))[0]
    best = int(-1)
    if body_friction != 0:
        best = friction_part(i, body_has, body_normal, body_lambda)
    if best >= 0:  # the same for every lane of the block
        hel = wp.tile_sum(wp.tile(hel, preserve_type=True))[0]
    if lane != 0:
        return
    if wp.abs(wp.determinant(hess)) < 1.0e-20:
        x_out[i] = xi
        return
    dx = wp.inverse(hess) * force
    new = xi + dx
    if best >= 0:
        limit = friction_limit(i, best, body_lambda, friction, vertex_area, friction_pressure, friction_used)
        new = body_stick_slip(new, x_prev[i], hel, body_normal[i, best], body_disp[i, best], limit)
    move = new - x_det[i]
    L = wp.length(move)
    if L > bound[i]:
        new = x_det[i] + move * (bound[i] / L)
    x_out[i] = new
