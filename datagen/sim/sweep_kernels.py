"""The sweeps' per-vertex solve, its sums split over several threads per vertex.

A vertex's local Newton step sums the forces and Hessians of its faces, hinges, cloth-cloth
contacts and body planes. One thread per vertex does them one after another: on a GPU a colour of
64 T-shirts is about 25,000 vertices, a tenth of the threads an H100 keeps in flight, and each
thread's chain of dependent loads sets the launch's time. So a colour is solved by two launches:

- :func:`colour_partials`, ``(groups, vertices)`` threads: group ``g`` of a vertex sums its items
  ``g, g + groups, ...`` (each incident face: membrane, and the contacts of other vertices with that
  face at this corner; each hinge stencil: bending, and on the edge's own ends its edge-edge
  contacts; each of its own vertex-triangle contacts; each body part's plane). A warp holds one
  group of 32 vertices, so its threads take the same kind of item together.
- :func:`solve_colour_vertices`, one thread per vertex: adds the groups in order, solves the 3x3
  step, applies friction and the move bound, and writes the vertex (it reads no other vertex, and
  the partials read every position before it runs, so no copy of the colour is needed).

Every sum has a fixed order, so the result depends neither on thread timing nor on the batch.
(Blocks of threads sharing a vertex through ``wp.tile_sum`` were tried first: 3.8x slower on an
H100, each warp then holding one vertex whose threads take different kinds of item.)
"""

from __future__ import annotations

import warp as wp

from datagen.sim.detection_kernels import triangle_closest_bary
from datagen.sim.kernels import (bending_force_hessian, body_stick_slip, contact_force_hessian, friction_limit,
                                 friction_part, membrane_force_hessian, vec5)


@wp.func
def edge_contacts(e: int, local: int, x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3),
                  edges: wp.array2d(dtype=wp.int32), ee_count: wp.array(dtype=wp.int32),
                  ee_edge: wp.array2d(dtype=wp.int32), self_radius: float, self_k: float, self_friction: float,
                  eps_u: float):
    """Force and Hessian on the end ``local`` (0 or 1) of edge ``e`` from its edge-edge contacts."""
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
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
    return force, hess


@wp.func
def corner_contacts(t: int, local: int, x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3),
                    faces: wp.array2d(dtype=wp.int32), tv_count: wp.array(dtype=wp.int32),
                    tv_vert: wp.array2d(dtype=wp.int32), self_radius: float, self_k: float, self_friction: float,
                    eps_u: float):
    """Force and Hessian on corner ``local`` of triangle ``t`` from the vertices in contact with it."""
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
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
    return force, hess


@wp.func
def vertex_contact(i: int, t: int, x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3),
                   faces: wp.array2d(dtype=wp.int32), self_radius: float, self_k: float, self_friction: float,
                   eps_u: float):
    """Force and Hessian on vertex ``i`` from its contact with triangle ``t``."""
    xi = x[i]
    a = faces[t, 0]
    b = faces[t, 1]
    c = faces[t, 2]
    w = triangle_closest_bary(xi, x[a], x[b], x[c])
    p = x[a] * w[0] + x[b] * w[1] + x[c] * w[2]
    dist = wp.length(xi - p)
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
    if dist < self_radius and dist > 1.0e-9:
        n = (xi - p) / dist
        rel = (xi - x_prev[i]) - ((x[a] - x_prev[a]) * w[0] + (x[b] - x_prev[b]) * w[1] + (x[c] - x_prev[c]) * w[2])
        force, hess = contact_force_hessian(rel, n, self_radius - dist, self_k, self_friction, eps_u, 1.0)
    return force, hess


@wp.kernel
def colour_partials(
    colour_verts: wp.array(dtype=wp.int32),
    x: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    active: wp.array(dtype=wp.int32),
    damping: wp.array(dtype=float),
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
    body_radius: wp.array(dtype=float),
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
    part_force: wp.array2d(dtype=wp.vec3),
    part_hess: wp.array2d(dtype=wp.mat33),
    part_elastic: wp.array2d(dtype=wp.mat33),
):
    """Group ``g``'s share of the force and Hessian of the ``k``-th vertex of a colour: the sum over
    its items ``g, g + groups, ...`` in order (``groups`` = the launch's first dimension), and of the
    membrane and bending part alone (``part_elastic``: with inertia, the stiffness friction acts
    against)."""
    g, k = wp.tid()
    groups = part_force.shape[0]
    i = colour_verts[k]
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
    hel = wp.mat33(0.0)
    if active[i] != 0:
        xi = x[i]
        kd = damping[i]
        f0 = v2f_offsets[i]
        faces_n = v2f_offsets[i + 1] - f0
        e0 = v2e_offsets[i]
        hinges_n = v2e_offsets[i + 1] - e0
        vt_n = wp.min(vt_count[i], vt_tri.shape[1])
        r = body_radius[i]
        for item in range(g, faces_n + hinges_n + vt_n + body_has.shape[1], groups):
            if item < faces_n:
                t = v2f[f0 + item, 0]
                local = v2f[f0 + item, 1]
                fm, hm = membrane_force_hessian(i, local, t, x, x_prev, faces, dm_inv, tri_area, tri_stiff, tri_lock,
                                                kd, h)
                fc, hc = corner_contacts(t, local, x, x_prev, faces, tv_count, tv_vert, self_radius, self_k,
                                         self_friction, eps_u)
                force += fm + fc
                hess += hm + hc
                hel += hm
            elif item < faces_n + hinges_n:
                e = v2e[e0 + item - faces_n, 0]
                local = v2e[e0 + item - faces_n, 1]
                if edges[e, 2] >= 0 and edges[e, 3] >= 0:
                    fb, hb = bending_force_hessian(i, local, e, x, x_prev, edges, rest_angle, bend_k, kd, h)
                    force += fb
                    hess += hb
                    hel += hb
                if local < 2:
                    fc, hc = edge_contacts(e, local, x, x_prev, edges, ee_count, ee_edge, self_radius, self_k,
                                           self_friction, eps_u)
                    force += fc
                    hess += hc
            elif item < faces_n + hinges_n + vt_n:
                fc, hc = vertex_contact(i, vt_tri[i, item - faces_n - hinges_n], x, x_prev, faces, self_radius,
                                        self_k, self_friction, eps_u)
                force += fc
                hess += hc
            else:
                p = item - faces_n - hinges_n - vt_n
                if body_has[i, p] == 1:
                    n = body_normal[i, p]
                    dist = wp.dot(xi - body_point[i, p], n)
                    if dist < r:
                        fc, hc = contact_force_hessian(wp.vec3(0.0), n, r - dist, body_k, 0.0, eps_u, 1.0)
                        force += fc
                        hess += hc
    part_force[g, k] = force
    part_hess[g, k] = hess
    part_elastic[g, k] = hel


@wp.kernel
def solve_colour_vertices(
    colour_verts: wp.array(dtype=wp.int32),
    x: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    x_det: wp.array(dtype=wp.vec3),
    inertia_target: wp.array(dtype=wp.vec3),
    mass: wp.array(dtype=float),
    active: wp.array(dtype=wp.int32),
    bound: wp.array(dtype=float),
    friction: wp.array(dtype=float),
    body_has: wp.array2d(dtype=wp.int32),
    body_normal: wp.array2d(dtype=wp.vec3),
    body_disp: wp.array2d(dtype=wp.vec3),
    body_lambda: wp.array2d(dtype=float),
    h: float,
    vertex_area: wp.array(dtype=float),
    body_friction: int,
    friction_pressure: float,
    friction_used: wp.array(dtype=float),
    part_force: wp.array2d(dtype=wp.vec3),
    part_hess: wp.array2d(dtype=wp.mat33),
    part_elastic: wp.array2d(dtype=wp.mat33),
):
    """One Newton step on the local energy of the ``k``-th vertex of a colour from its groups'
    partial sums (:func:`colour_partials`), then Coulomb friction with the body on that step
    (``kernels.body_stick_slip``) and the move bound; writes the vertex in ``x``."""
    k = wp.tid()
    i = colour_verts[k]
    if active[i] == 0:
        return
    xi = x[i]
    m_h2 = mass[i] / (h * h)
    force = (inertia_target[i] - xi) * m_h2
    hess = wp.identity(n=3, dtype=float) * m_h2
    hel = hess
    for g in range(part_force.shape[0]):
        force += part_force[g, k]
        hess += part_hess[g, k]
        hel += part_elastic[g, k]
    if wp.abs(wp.determinant(hess)) < 1.0e-20:
        return
    new = xi + wp.inverse(hess) * force
    if body_friction != 0:
        best = friction_part(i, body_has, body_normal, body_lambda)
        if best >= 0:
            limit = friction_limit(i, best, body_lambda, friction, vertex_area, friction_pressure, friction_used)
            new = body_stick_slip(new, x_prev[i], hel, body_normal[i, best], body_disp[i, best], limit)
    move = new - x_det[i]
    L = wp.length(move)
    if L > bound[i]:
        new = x_det[i] + move * (bound[i] / L)
    x[i] = new
