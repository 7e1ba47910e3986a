"""Warp kernels of the cloth solver (vertex block descent), as free functions.

Every array is an explicit argument; :mod:`datagen.sim.solver` only arranges the launches. The
kernels run unchanged on CPU and CUDA.

Energies (per element, SI units; see ``docs/simulator.md``):

- membrane: orthotropic St. Venant-Kirchhoff on each triangle in its material frame (weft u, warp
  v): ``A [k_u/2 G_uu² + k_v/2 G_vv² + k_uv G_uu G_vv + 2 k_s G_uv²]`` with the Green strain
  ``G = (FᵀF - I)/2``, stiffnesses in N/m, ``k_uv = ν sqrt(k_u k_v)``, A the triangle's rest area
  (of its reference shape, ``tri_area`` = |det Dm|/2: the energy is an integral over the rest shape);
  a direction in compression (G_uu or G_vv below zero) is on the buckling branch: its stiffness
  and the coupling times the material's buckling ratio r (:func:`buckled_stiffness`; the energy
  stays continuous with a continuous gradient in that direction, and positive definite in G);
- bending: discrete shells (Grinspun et al. 2003) on each interior edge,
  ``k_b/2 · 3|ē|²/(Ā₁+Ā₂) · (θ - θ̄)²`` with the rest angle θ̄ of the rest shape, k_b in N·m;
- inertia ``m/(2h²)|x - y|²`` with ``y = x₀ + h v₀ + h² (g - c_air v₀ / ρ)``;
- Rayleigh damping of the membrane and bending: ``(k_d/h) H_e (x - x₀)``;
- contacts: ``k_c/2 (r - d)²`` for a distance d below the radius r, against the body (one
  closest-point plane per vertex) and the cloth itself (vertex-triangle and edge-edge pairs);
  cloth-cloth Coulomb friction ``μ λ_n`` on the tangential displacement in the solve (smoothed
  below ``ε_v h``), body friction as a stick/slip projection of each vertex's Newton step
  (``body_stick_slip``).

Each vertex takes one Newton step on its local energy per colour sweep (Chen et al. 2024,
"Vertex Block Descent", SIGGRAPH), with Gauss-Seidel order across colours. Within a colour every
vertex reads the positions of the start of the sweep (a Jacobi step for the contacts that couple
same-coloured vertices), so the result does not depend on the order of threads. The sweeps' and
the global step's moves of each vertex between two detections are bounded by ``bound_fraction`` x
its distance to the nearest cloth primitive found at detection (Chen et al. 2024, §3.6
conservative bounds) when that primitive is within the search distance, so the iterations cannot
carry the cloth through itself. The bound is measured from the segment along which the body
carries the vertex over the substep (:func:`carry_bound`, :func:`bounded_move`): it holds back how
far the iterations move a vertex, not how fast cloth may follow a limb.
"""

from __future__ import annotations

import warp as wp

from datagen.sim.detection_kernels import triangle_closest_bary

vec5 = wp.types.vector(length=5, dtype=float)
"""A triangle's membrane law: (k_u, k_v, k_uv, k_s [N/m], buckling ratio r [-])."""


@wp.func
def buckled_stiffness(k: vec5, g00: float, g11: float) -> wp.vec4:
    """(k_u, k_v, k_uv, k_s) at Green strains G_uu = ``g00``, G_vv = ``g11``: a direction in
    compression has its stiffness times r, and the coupling is times r for each compressed
    direction (so k_uv² <= k_u k_v still holds and the energy stays convex in G)."""
    ru = float(1.0)
    rv = float(1.0)
    if g00 < 0.0:
        ru = k[4]
    if g11 < 0.0:
        rv = k[4]
    return wp.vec4(k[0] * ru, k[1] * rv, k[2] * ru * rv, k[3])


@wp.func
def contact_force_hessian(dx_rel: wp.vec3, n: wp.vec3, depth: float, k: float, mu: float, eps_u: float,
                          weight: float):
    """Force and Hessian on one vertex of a penalty contact ``k/2 depth²`` along n with Coulomb
    friction ``mu`` times the current penalty force; ``weight`` is the vertex's share (barycentric
    weight). (Body friction is not here: it is ``body_stick_slip``'s, with the lagged normal force.)"""
    lam = k * depth
    f = n * (lam * weight)
    h = wp.outer(n, n) * (k * weight * weight)
    if mu > 0.0 and lam > 0.0:
        ff, hf = friction_force_hessian(dx_rel, n, mu * lam * wp.abs(weight), eps_u)
        f = f + ff
        h = h + hf
    return f, h


@wp.func
def body_plane_force_hessian(xi: wp.vec3, point: wp.vec3, n: wp.vec3, r: float, k: float):
    """Force and Hessian of one body contact plane (through ``point``, normal ``n``) on a vertex at
    ``xi``: the penalty ``k/2 (r - dist)²`` while the vertex is closer than ``r``, else zero.
    (Friction with the body is ``body_stick_slip``'s and ``friction_force_hessian``'s.)"""
    f = wp.vec3(0.0)
    h = wp.mat33(0.0)
    dist = wp.dot(xi - point, n)
    if dist < r:
        f, h = contact_force_hessian(wp.vec3(0.0), n, r - dist, k, 0.0, 0.0, 1.0)
    return f, h


@wp.func
def friction_force_hessian(dx_rel: wp.vec3, n: wp.vec3, limit: float, eps_u: float):
    """Coulomb friction of at most ``limit`` [N] against the tangential part of the relative
    displacement ``dx_rel`` over the substep, smoothed (a stiff spring) below ``eps_u``."""
    t = dx_rel - n * wp.dot(n, dx_rel)
    scale = limit / wp.max(wp.length(t), eps_u)
    return -t * scale, (wp.identity(n=3, dtype=float) - wp.outer(n, n)) * scale


@wp.kernel
def forward_step(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), mass: wp.array(dtype=float),
                 area: wp.array(dtype=float), active: wp.array(dtype=wp.int32), gravity: wp.vec3, air_drag: float,
                 h: float, x_prev: wp.array(dtype=wp.vec3), inertia_target: wp.array(dtype=wp.vec3),
                 pinned_target: wp.array(dtype=wp.vec3)):
    """Save x₀, form the inertial target y; pinned vertices move to their target (friction with the
    body acts in the solve: ``body_stick_slip``)."""
    i = wp.tid()
    x_prev[i] = x[i]
    if active[i] == 0:
        inertia_target[i] = pinned_target[i]
        return
    a = gravity
    if mass[i] > 0.0:
        a = a - v[i] * (air_drag * area[i] / mass[i])
    inertia_target[i] = x[i] + (v[i] + a * h) * h


@wp.func
def bounded_move(new: wp.vec3, start: wp.vec3, end: wp.vec3, bound: float) -> wp.vec3:
    """``new`` kept within ``bound`` [m] of the segment from ``start`` (a vertex's position at the
    last cloth-cloth detection) to ``end`` (where the body carries it by the
    substep's end: :func:`carry_bound`): moved onto that distance towards the segment's nearest
    point when farther. With ``end == start`` the bound is the ball about ``start``, computed as it
    always was (bitwise)."""
    q = start
    seg = end - start
    s2 = wp.dot(seg, seg)
    if s2 > 0.0:
        q = start + seg * wp.clamp(wp.dot(new - start, seg) / s2, 0.0, 1.0)
    move = new - q
    L = wp.length(move)
    if L > bound:
        return q + move * (bound / L)
    return new


@wp.kernel
def global_bounds(min_dist: wp.array(dtype=float), fraction: float, bound: wp.array(dtype=float)):
    """The global step's move bound [m]: ``fraction`` x the distance to the nearest non-neighbouring
    cloth primitive (``detection_kernels.detect_*``'s ``min_dist``), without the sweeps' floor.

    The sweeps' bound counts a distance below ``bound_floor`` (6 mm) as the floor, because the
    cloth-cloth contact forces in the sweeps keep such pairs apart. The global step has no
    cloth-cloth contact: with the floor, two layers 3-4.5 mm apart (a pair in contact) could each
    move 2.7 mm towards the other in it and cross. (The initial guess keeps the sweeps' bound:
    without the floor there too, the two layers of ``tests/sim/test_fast_limb.py`` could not keep
    up with the limb, 735 %.) In ``small``'s scene 34 (pants:0 squatting, the
    front panels folding under the belly as the hip flexes past 74 degrees) every new crossing of
    frames 81-82 appeared in the global step (238 edge-triangle pairs 2.8-4.5 mm apart before it,
    none in the sweeps, the projection or the untangling), the sweeps undid most of them and
    left 4 and 8 at the frames' ends, 81 at frame 90 (the gate allows 50). Unfloored, two primitives
    close at most ``2 x fraction`` of their distance in the global step."""
    i = wp.tid()
    bound[i] = fraction * min_dist[i]


CARRY_MIN = wp.constant(1.0e-6)
"""A body part's move in a substep [m] below which it carries nothing (:func:`carry_bound`): the two
poses of a body at rest that a substep interpolates differ by float rounding (about 1e-8 m), and a
carry that small would only change the bits of a scene whose body does not move."""

CARRY_FULL = wp.constant(0.5)
"""The share of the body query within which a body part's move carries a vertex's bound in full
(:func:`carry_bound`); from there to the query's edge the carry fades to nothing."""


@wp.kernel
def carry_bound(x_det: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3), has: wp.array2d(dtype=wp.int32),
                point: wp.array2d(dtype=wp.vec3), normal: wp.array2d(dtype=wp.vec3),
                body_disp: wp.array2d(dtype=wp.vec3), query: float, active: wp.array(dtype=wp.int32),
                bound_end: wp.array(dtype=wp.vec3)):
    """The far end of each vertex's bound segment (``bound_end`` [n]; :func:`bounded_move`): the
    vertex's position at the last detection ``x_det`` plus what is left of its carry over the
    substep (the carry less how far the vertex has already moved along it since the substep began
    at ``x_prev``). The carry is the move over the substep of the body part nearest the vertex
    (``body_disp`` at its plane), in full for a vertex that was within ``CARRY_FULL`` x ``query``
    [m] of that plane before the move, fading to nothing at ``query``.

    Why: the bound is ``bound_fraction`` x 6 mm at least, per detection, for cloth near other cloth:
    with 4 detections a substep and 10 substeps a frame, measured from ``x_det`` alone it held such
    cloth to 3.24 m/s. A walking ankle reaches 3.9 m/s: the bound held the bunched hem of a trouser
    leg back while the shin passed into it, and the projection then put the hem's vertices out on
    opposite sides of the shin (a 305 % tear, issue 66). The bound is there to keep the iterations
    from jumping cloth through cloth, not to hold cloth back from a limb: along the segment the body
    carries a vertex it may go as far as the body takes it, and no farther than the bound off it.
    The segment allows the move, it does not force it: a ball about the carried end did, and in
    ``tests/sim/test_fast_limb.py`` carried along each body face's normal the cloth in front of the
    limb was pulled apart at the edges between faces (1,218 %), carried along the limb's move the
    cloth the carry reached was pulled away from the cloth it did not (1,860 %); with the segment,
    36 %. The vertex's own inertia does not carry it: a segment along the inertial move of every
    vertex faster than its bound let a 60 cm square folding over a sphere at rest cross itself
    (``test_cloth_folding_on_itself_does_not_self_intersect``, 10 substeps). A vertex the body does
    not move keeps exactly the bound of before (``bound_end == x_det``), so a scene with a body at
    rest does not change at all."""
    i = wp.tid()
    start = x_det[i]
    end = start
    if active[i] != 0:
        carry = wp.vec3(0.0)
        own = int(-1)
        nearest = float(0.0)
        for p in range(has.shape[1]):
            if has[i, p] == 1:
                d = wp.length(x_prev[i] - point[i, p])
                if own < 0 or d < nearest:
                    own = p
                    nearest = d
        if own >= 0:
            disp = body_disp[i, own]
            if wp.length(disp) > CARRY_MIN:
                before = wp.dot(x_prev[i] - point[i, own], normal[i, own]) + wp.dot(disp, normal[i, own])
                carry = disp * wp.clamp((query - wp.abs(before)) / ((1.0 - CARRY_FULL) * query), 0.0, 1.0)
        L = wp.length(carry)
        if L > 0.0:
            along = carry / L
            left = L - wp.dot(start - x_prev[i], along)
            if left > 0.0:
                end = start + along * left
    bound_end[i] = end


@wp.kernel
def initial_guess(x_det: wp.array(dtype=wp.vec3), bound_end: wp.array(dtype=wp.vec3),
                  inertia_target: wp.array(dtype=wp.vec3),
                  v: wp.array(dtype=wp.vec3), v_old: wp.array(dtype=wp.vec3), gravity: wp.vec3, h: float,
                  body_lambda: wp.array2d(dtype=float), bound: wp.array(dtype=float),
                  active: wp.array(dtype=wp.int32), x: wp.array(dtype=wp.vec3)):
    """Start the iterations at y with only the part of gravity the vertex fell with over the last
    substep (VBD's adaptive initialisation, Chen et al. 2024 §3.4: ã = clamp(a·ĝ, 0, |g|) ĝ with
    a = (v - v_old)/h), clipped to each vertex's conservative bound (``bound`` about the segment
    ``x_det``-``bound_end``: :func:`bounded_move`).

    Starting at y drops every hanging vertex by g h² that the sweeps must carry back through the
    membrane; at 20 sweeps they had not, and the pull of the unconverged cloth slid a pair of
    pants off the hips through Coulomb friction that holds their weight ten times over. A vertex
    that the body pressed at the end of the last substep (``body_lambda``) starts at y: its weight
    is what presses it, and body friction has cut y's slide (without the weight, the cut alone
    started a patch on a slope uphill)."""
    i = wp.tid()
    if active[i] == 0:
        x[i] = inertia_target[i]
        return
    g2 = wp.dot(gravity, gravity)
    guess = inertia_target[i]
    pressed = float(0.0)
    for p in range(body_lambda.shape[1]):
        pressed = wp.max(pressed, body_lambda[i, p])
    if g2 > 0.0 and pressed <= 0.0:
        s = wp.clamp(wp.dot(v[i] - v_old[i], gravity) / (h * g2), 0.0, 1.0)
        guess = guess - gravity * ((1.0 - s) * h * h)
    if bound_end[i] == x_det[i]:  # not carried: the bound about x_det (bitwise the clip of before)
        d = guess - x_det[i]
        L = wp.length(d)
        if L > bound[i]:
            d = d * (bound[i] / L)
        x[i] = x_det[i] + d
    else:
        x[i] = bounded_move(guess, x_det[i], bound_end[i], bound[i])


@wp.kernel
def update_velocity(x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3), h: float,
                    v: wp.array(dtype=wp.vec3), v_old: wp.array(dtype=wp.vec3)):
    """The substep's velocity (x - x₀)/h; the one before it goes to ``v_old``."""
    i = wp.tid()
    v_old[i] = v[i]
    v[i] = (x[i] - x_prev[i]) / h


@wp.func
def body_surface_point(f: int, u: float, v: float, body_faces: wp.array2d(dtype=wp.int32),
                       body_prev: wp.array(dtype=wp.vec3), body_now: wp.array(dtype=wp.vec3)):
    """The point at barycentric (u, v) of body face f now, the face's unit normal (zero for a
    degenerate face) and the point's displacement since ``body_prev``."""
    a = body_faces[f, 0]
    b = body_faces[f, 1]
    c = body_faces[f, 2]
    w2 = 1.0 - u - v
    p = body_now[a] * u + body_now[b] * v + body_now[c] * w2
    n = wp.cross(body_now[b] - body_now[a], body_now[c] - body_now[a])
    ln = wp.length(n)
    if ln < 1.0e-20:
        n = wp.vec3(0.0)
    else:
        n = n / ln
    return p, n, p - (body_prev[a] * u + body_prev[b] * v + body_prev[c] * w2)


@wp.kernel
def interpolate_body(b0: wp.array(dtype=wp.vec3), b1: wp.array(dtype=wp.vec3), alpha: float,
                     out: wp.array(dtype=wp.vec3)):
    """Body vertices at ``alpha`` within the frame."""
    i = wp.tid()
    out[i] = b0[i] * (1.0 - alpha) + b1[i] * alpha


@wp.func
def part_border(flags: int, u: float, v: float) -> bool:
    """True when barycentric (u, v) lies on a border edge of a part face (``part_edge_flags``)."""
    eps = 1.0e-5
    w = 1.0 - u - v
    return ((flags & 1) != 0 and w < eps) or ((flags & 2) != 0 and u < eps) or ((flags & 4) != 0 and v < eps)


@wp.func
def set_body_plane(i: int, p: int, f: int, u: float, v: float, xi: wp.vec3, r: float,
                   body_faces: wp.array2d(dtype=wp.int32), body_prev: wp.array(dtype=wp.vec3),
                   body_now: wp.array(dtype=wp.vec3), has: wp.array2d(dtype=wp.int32),
                   point: wp.array2d(dtype=wp.vec3), normal: wp.array2d(dtype=wp.vec3),
                   body_disp: wp.array2d(dtype=wp.vec3)) -> wp.vec3:
    """Store vertex i's contact plane with part p at barycentric (u, v) of body face f, the
    vertex's closest point on that part; returns the push out along its normal.

    The plane's normal is the closest feature's: where the closest point lies on an edge or a
    corner of the face and the vertex is on the face's outer side, the unit vector from the closest
    point to the vertex (the gradient of the distance to the body, continuous across the edge), not
    the face's normal, whose plane extended past a sharp edge (a square rim, a low-poly collider)
    invented body up to r beyond it and pushed cloth out to that. Elsewhere the face's normal.

    Returns the push out along the normal when the vertex is closer than r (or less than 2r behind
    the plane): to r from the closest feature, which at an edge is r from the real edge. (Pushing
    only by the body's advance along the normal let a strip fall through the crease of two parts,
    ``test_physics.test_cloth_in_the_crease_of_two_body_parts_is_held_by_both``.)"""
    pt, n, disp = body_surface_point(f, u, v, body_faces, body_prev, body_now)
    if wp.length(n) == 0.0:
        return wp.vec3(0.0)
    eps = 1.0e-6
    if u < eps or v < eps or 1.0 - u - v < eps:  # the closest point is on an edge or a corner
        e = xi - pt
        le = wp.length(e)
        if le > 1.0e-9 and wp.dot(e, n) > 0.0:
            n = e / le
    has[i, p] = 1
    point[i, p] = pt
    normal[i, p] = n
    body_disp[i, p] = disp
    d = wp.dot(xi - pt, n)
    if d < r and d > -2.0 * r:
        return n * (r - d)
    return wp.vec3(0.0)


MAX_BODY_PARTS = 8
"""The most body parts a batch may have (:func:`detect_body` keeps a closest point per part in
registers); ``ClothModelBuilder.add_body`` refuses part numbers outside 0..7. drape's bodies
have 5 (``datagen.body.skeleton.BODY_PARTS``)."""
part_floats = wp.types.vector(length=MAX_BODY_PARTS, dtype=float)
part_ints = wp.types.vector(length=MAX_BODY_PARTS, dtype=wp.int32)


@wp.kernel
def detect_body(body_meshes: wp.array(dtype=wp.uint64), body_face_base: wp.array(dtype=wp.int32),
                body_face_part: wp.array(dtype=wp.int32), body_face_border: wp.array(dtype=wp.int32),
                x: wp.array(dtype=wp.vec3), scene: wp.array(dtype=wp.int32), body_faces: wp.array2d(dtype=wp.int32),
                body_prev: wp.array(dtype=wp.vec3), body_now: wp.array(dtype=wp.vec3), query: float,
                radius: wp.array(dtype=float), active: wp.array(dtype=wp.int32),
                inertia_target: wp.array(dtype=wp.vec3), has: wp.array2d(dtype=wp.int32), point: wp.array2d(dtype=wp.vec3), normal: wp.array2d(dtype=wp.vec3),
                body_disp: wp.array2d(dtype=wp.vec3), order: wp.array(dtype=wp.int32)):
    """Contact planes of each cloth vertex with the body (this substep's pose), one slot per body
    part: the closest point of the whole body within ``query`` (in its part's slot), and the
    closest point of every other part within ``query`` that is not on that part's border (where
    it meets the part the vertex is over). Each plane is a point, the outward face normal and the
    body's displacement there in the substep. Where a posed body overlaps itself (arm and torso
    at the armpit, a hand on the thigh) the cloth between the two parts gets a plane from each:
    the nearest alone pushed it into the other part, from which the end-of-substep projection
    then threw it out a hand's width away, tearing its triangles.

    One box query of the scene's body mesh (every face whose bounds come within ``query``) gives
    every part's closest point at once (kept per part in the thread's own vectors, at most
    :data:`MAX_BODY_PARTS`); the whole body's is the nearest of them. So only the whole body's
    tree is refitted each substep, not one per part.

    A vertex that the body's move has put closer than a plane's contact radius (or just behind
    it: less than two radii) is first moved out along the normal (the pushes of its planes
    added; :func:`set_body_plane`), with its inertial target, so the body's push is never held back by the cloth's
    conservative move bound (which is measured from these positions). Thread t takes vertex
    ``order[t]``."""
    i = order[wp.tid()]
    P = has.shape[1]
    best_dist = part_floats(query)
    best_face = part_ints(-1)
    best_u = part_floats(0.0)
    best_v = part_floats(0.0)
    for p in range(P):
        has[i, p] = 0
    s = scene[i]
    xi = x[i]
    r = radius[i]
    base = body_face_base[s]
    q = wp.mesh_query_aabb(body_meshes[s], xi - wp.vec3(query), xi + wp.vec3(query))
    f = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    while wp.mesh_query_aabb_next(q, f):
        g = base + f
        a = body_now[body_faces[g, 0]]
        b = body_now[body_faces[g, 1]]
        c = body_now[body_faces[g, 2]]
        w = triangle_closest_bary(xi, a, b, c)
        d = wp.length(xi - (a * w[0] + b * w[1] + c * w[2]))
        p = body_face_part[g]
        if d < best_dist[p] or (d == best_dist[p] and best_face[p] >= 0 and g < best_face[p]):
            best_dist[p] = d
            best_face[p] = g
            best_u[p] = w[0]
            best_v[p] = w[1]
    own = int(-1)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    nearest = float(query)  # noqa: RUF046 (warp: a mutable float in the loop)
    for p in range(P):
        if best_face[p] >= 0 and (own < 0 or best_dist[p] < nearest):
            own = p
            nearest = best_dist[p]
    push = wp.vec3(0.0)
    if own >= 0:
        push = push + set_body_plane(i, own, best_face[own], best_u[own], best_v[own], xi, r, body_faces, body_prev,
                                     body_now, has, point, normal, body_disp)
    for p in range(P):
        g = best_face[p]
        if p != own and g >= 0:
            if not part_border(body_face_border[g], best_u[p], best_v[p]):
                push = push + set_body_plane(i, p, g, best_u[p], best_v[p], xi, r, body_faces, body_prev, body_now,
                                             has, point, normal, body_disp)
    if active[i] != 0:
        x[i] = xi + push
        inertia_target[i] = inertia_target[i] + push


@wp.func
def membrane_force_hessian(i: int, local: int, f: int, x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3),
                           faces: wp.array2d(dtype=wp.int32), dm_inv: wp.array(dtype=wp.mat22),
                           tri_area: wp.array(dtype=float), tri_stiff: wp.array(dtype=vec5),
                           tri_lock: wp.array(dtype=wp.vec2), damping: float, h: float):
    """Force and Hessian block on corner ``local`` of face ``f`` (orthotropic StVK and the lock,
    see module doc)."""
    x0 = x[faces[f, 0]]
    x1 = x[faces[f, 1]]
    x2 = x[faces[f, 2]]
    D = dm_inv[f]
    # F = sum_j x_j c_jᵀ with c_1 = row 0 of Dm⁻¹, c_2 = row 1, c_0 = -(c_1 + c_2)
    f0 = (x1 - x0) * D[0, 0] + (x2 - x0) * D[1, 0]
    f1 = (x1 - x0) * D[0, 1] + (x2 - x0) * D[1, 1]
    c = wp.vec2(-(D[0, 0] + D[1, 0]), -(D[0, 1] + D[1, 1]))
    if local == 1:
        c = wp.vec2(D[0, 0], D[0, 1])
    elif local == 2:
        c = wp.vec2(D[1, 0], D[1, 1])
    g00 = 0.5 * (wp.dot(f0, f0) - 1.0)
    g11 = 0.5 * (wp.dot(f1, f1) - 1.0)
    g01 = 0.5 * wp.dot(f0, f1)
    k = buckled_stiffness(tri_stiff[f], g00, g11)
    ku = k[0]
    kv = k[1]
    kuv = k[2]
    ks = k[3]
    s00 = ku * g00 + kuv * g11
    s11 = kv * g11 + kuv * g00
    s01 = 2.0 * ks * g01
    A = tri_area[f]
    sc0 = s00 * c[0] + s01 * c[1]
    sc1 = s01 * c[0] + s11 * c[1]
    force = -(f0 * sc0 + f1 * sc1) * A
    m00 = ku * c[0] * c[0] + ks * c[1] * c[1]
    m11 = ks * c[0] * c[0] + kv * c[1] * c[1]
    m01 = (kuv + ks) * c[0] * c[1]
    hess = (wp.outer(f0, f0) * m00 + wp.outer(f1, f1) * m11 + (wp.outer(f0, f1) + wp.outer(f1, f0)) * m01) * A
    if damping > 0.0:
        # viscous (Rayleigh) damping: the material tangent applied to the Green strain rate of the
        # whole triangle over the substep (zero for rigid motions; no geometric part, which would
        # feed energy in under compression)
        u0 = x0 - x_prev[faces[f, 0]]
        u1 = x1 - x_prev[faces[f, 1]]
        u2 = x2 - x_prev[faces[f, 2]]
        d0 = (u1 - u0) * D[0, 0] + (u2 - u0) * D[1, 0]
        d1 = (u1 - u0) * D[0, 1] + (u2 - u0) * D[1, 1]
        r00 = wp.dot(f0, d0)
        r11 = wp.dot(f1, d1)
        r01 = 0.5 * (wp.dot(f0, d1) + wp.dot(f1, d0))
        t00 = ku * r00 + kuv * r11
        t11 = kv * r11 + kuv * r00
        t01 = 2.0 * ks * r01
        scale = damping / h
        force = force - (f0 * (t00 * c[0] + t01 * c[1]) + f1 * (t01 * c[0] + t11 * c[1])) * (A * scale)
        hess = hess * (1.0 + scale)
    geo = c[0] * sc0 + c[1] * sc1
    if geo > 0.0:
        hess = hess + wp.identity(n=3, dtype=float) * (geo * A)
    lk = tri_lock[f]
    if lk[1] > 0.0:
        fl, hl = lock_force_hessian(f0, f1, c, lk[0], lk[1] * A)
        force += fl
        hess += hl
    return force, hess


@wp.func
def lock_force_hessian(f0: wp.vec3, f1: wp.vec3, c: wp.vec2, lam_lock: float, kA: float):
    """Force and Hessian on one corner (shape weights ``c``) of the lock ``kA/2 Σ (λ - λ_lock)²``
    over the triangle's principal stretches λ above ``λ_lock`` (F = [f0 f1]; the eigenvectors of
    FᵀF held fixed: the Hessian is PSD)."""
    a = wp.dot(f0, f0)
    b = wp.dot(f1, f1)
    cc = wp.dot(f0, f1)
    mean = 0.5 * (a + b)
    rad = wp.sqrt(0.25 * (a - b) * (a - b) + cc * cc)
    force = wp.vec3(0.0)
    hess = wp.mat33(0.0)
    if mean + rad <= lam_lock * lam_lock:
        return force, hess
    # eigenvector of the larger eigenvalue of FᵀF = [[a, cc], [cc, b]]
    v = wp.vec2(1.0, 0.0)
    if rad > 1.0e-12:
        if a >= b:
            v = wp.normalize(wp.vec2(mean + rad - b, cc))
        else:
            v = wp.normalize(wp.vec2(cc, mean + rad - a))
    for k in range(2):
        mu = mean + rad
        vk = v
        if k == 1:
            mu = mean - rad
            vk = wp.vec2(-v[1], v[0])
        lam = wp.sqrt(wp.max(mu, 0.0))
        if lam > lam_lock:
            w = f0 * vk[0] + f1 * vk[1]  # F v, of length λ
            u = w / lam
            vc = wp.dot(vk, c)
            force -= u * (kA * (lam - lam_lock) * vc)
            hess += wp.outer(u, u) * (kA * vc * vc) + (wp.identity(n=3, dtype=float) - wp.outer(u, u)) * (
                kA * (lam - lam_lock) * vc * vc / lam)
    return force, hess


@wp.func
def hinge_frame(x0: wp.vec3, x1: wp.vec3, x2: wp.vec3, x3: wp.vec3):
    """A hinge's edge E = x1 - x0, its length, the two triangles' (unnormalised) normals N1, N2 and
    their squared lengths."""
    E = x1 - x0
    N1 = wp.cross(E, x2 - x0)
    N2 = wp.cross(x3 - x0, E)
    return E, wp.length(E), N1, N2, wp.dot(N1, N1), wp.dot(N2, N2)


@wp.func
def hinge_gradients(x0: wp.vec3, x1: wp.vec3, x2: wp.vec3, x3: wp.vec3):
    """dθ/dx of a hinge's four stencil vertices (0, 1: the hinge; 2, 3: the opposite corners;
    Bridson et al. 2003, signs for drape's θ); zeros for a degenerate hinge."""
    E, L, N1, N2, n1sq, n2sq = hinge_frame(x0, x1, x2, x3)
    if L < 1.0e-12 or n1sq < 1.0e-24 or n2sq < 1.0e-24:
        return wp.vec3(0.0), wp.vec3(0.0), wp.vec3(0.0), wp.vec3(0.0)
    Eh = E / L
    a = N1 / n1sq
    b = N2 / n2sq
    return (-(a * wp.dot(x2 - x1, Eh) + b * wp.dot(x3 - x1, Eh)), a * wp.dot(x2 - x0, Eh) + b * wp.dot(x3 - x0, Eh),
            -a * L, -b * L)


@wp.func
def stencil_pick(g0: wp.vec3, g1: wp.vec3, g2: wp.vec3, g3: wp.vec3, slot: int) -> wp.vec3:
    """The one of a hinge's four stencil vectors that belongs to ``slot``."""
    g = g3
    if slot == 0:
        g = g0
    elif slot == 1:
        g = g1
    elif slot == 2:
        g = g2
    return g


@wp.func
def bending_force_hessian(i: int, local: int, e: int, x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3),
                          edges: wp.array2d(dtype=wp.int32), rest_angle: wp.array(dtype=float),
                          bend_k: wp.array(dtype=float), damping: float, h: float):
    """Force and Gauss-Newton Hessian on stencil vertex ``local`` (0, 1: the hinge; 2, 3: the
    opposite corners) of the discrete-shells bending energy of edge ``e``."""
    x0 = x[edges[e, 0]]
    x1 = x[edges[e, 1]]
    x2 = x[edges[e, 2]]
    x3 = x[edges[e, 3]]
    E, L, N1, N2, n1sq, n2sq = hinge_frame(x0, x1, x2, x3)
    zero = wp.mat33(0.0)
    if L < 1.0e-12 or n1sq < 1.0e-24 or n2sq < 1.0e-24:
        return wp.vec3(0.0), zero
    Eh = E / L
    n1 = N1 / wp.sqrt(n1sq)
    n2 = N2 / wp.sqrt(n2sq)
    theta = wp.atan2(wp.dot(wp.cross(n1, n2), Eh), wp.dot(n1, n2))
    g0, g1, g2, g3 = hinge_gradients(x0, x1, x2, x3)
    g = stencil_pick(g0, g1, g2, g3, local)
    k = bend_k[e]
    dtheta = theta - rest_angle[e]
    force = -g * (k * dtheta)
    hess = wp.outer(g, g) * k
    if damping > 0.0:
        # Rayleigh damping on the rate of the angle (all four stencil vertices)
        rate = (wp.dot(g0, x0 - x_prev[edges[e, 0]]) + wp.dot(g1, x1 - x_prev[edges[e, 1]])
                + wp.dot(g2, x2 - x_prev[edges[e, 2]]) + wp.dot(g3, x3 - x_prev[edges[e, 3]]))
        force = force - g * (k * rate * damping / h)
        hess = hess * (1.0 + damping / h)
    return force, hess


PINCH_COS = wp.constant(0.5)
"""A vertex with contact planes from two parts (both within the body query) whose normals are more
than 60 degrees apart (cosine below this) is in a fold of the skinned body (a hip crease closing as
the thigh comes up, an armpit), where the two skin surfaces slide through each other as no real
skin does; friction with either one alone dragged the cloth across the fold and tore it (a pair of
shorts at 70 % in a squat at 75 degrees of hip flexion). Before, only a vertex that both parts
pressed (λ > 0) from sides more than 90 degrees apart counted; in a closing crease most vertices
are pressed by one side at a time, and at 60 degrees with that condition the shorts still tore."""


@wp.func
def friction_part(i: int, has: wp.array2d(dtype=wp.int32), normal: wp.array2d(dtype=wp.vec3),
                  lam: wp.array2d(dtype=float)) -> int:
    """The body part whose friction acts on vertex i: the one that pressed it hardest at the end
    of the last substep (λ lagged, as in IPC); -1 for none, and for a vertex in a fold of the body:
    a plane from another part within reach at more than 60 degrees to the best's (:data:`PINCH_COS`;
    it slides out of the fold)."""
    best = int(-1)
    big = float(0.0)
    for p in range(has.shape[1]):
        if has[i, p] == 1 and lam[i, p] > big:
            big = lam[i, p]
            best = p
    if best < 0:
        return best
    n = normal[i, best]
    for p in range(has.shape[1]):
        if p != best and has[i, p] == 1 and wp.dot(normal[i, p], n) < PINCH_COS:
            return -1
    return best


@wp.func
def friction_limit(i: int, part: int, lam: wp.array2d(dtype=float), friction: wp.array(dtype=float),
                   area: wp.array(dtype=float), max_pressure: float, used: wp.array(dtype=float)) -> float:
    """The body friction force vertex i has left within a substep [N]: μ times part ``part``'s lagged
    normal force, capped at ``max_pressure`` x the vertex's area, less what the inertial prediction
    used (the sweeps' and the global step's limit)."""
    return friction[i] * wp.min(lam[i, part], max_pressure * area[i]) - used[i]


@wp.func
def body_stick_slip(new: wp.vec3, x_prev: wp.vec3, hess: wp.mat33, n: wp.vec3, body_disp: wp.vec3, limit: float):
    """Coulomb friction with the body on a vertex's Newton step to ``new``: its slide t relative
    to the body (normal n, moved by ``body_disp`` over the substep) is taken back as far as a force
    of ``limit`` holds it against the vertex's local stiffness t̂ᵀ H t̂ (H: the Hessian of its
    inertia and the cloth around it, without the contacts, whose stiff normals would make any
    slide look too stiff to take back): all of it (static) when the force that moved it is below
    the limit.

    Forces that reach a vertex through the cloth (the weight of a pair of pants on its waistband, a
    membrane stretched over the shoulders) are resolved here, in the sweep, so Gauss-Seidel settles
    stick and slip across the cloth; the slide the whole cloth shares at the start of a substep,
    its own inertia and weight, is resolved before (``predict_body_friction``; ``limit`` is what
    that left of μ λ). Friction applied after the solve with only the inertia m/h² as the stiffness
    held cloth that its membrane pulled with a hundred times μ λ: a jersey T-shirt hung 40 %
    stretched from its shoulders on a body at rest. As a smoothed force it could not hold: its
    spring μ λ / ε is a thousandth of the membrane's."""
    rel = (new - x_prev) - body_disp
    t = rel - n * wp.dot(rel, n)
    lt = wp.length(t)
    if lt < 1.0e-12 or limit <= 0.0:
        return new
    th = t / lt
    allowed = limit / wp.max(wp.dot(th, hess * th), 1.0e-12)
    if lt <= allowed:
        return new - t
    return new - t * (allowed / lt)


@wp.kernel
def predict_body_friction(x_prev: wp.array(dtype=wp.vec3), mass: wp.array(dtype=float), active: wp.array(dtype=wp.int32),
                          has: wp.array2d(dtype=wp.int32), normal: wp.array2d(dtype=wp.vec3),
                          body_disp: wp.array2d(dtype=wp.vec3), lam: wp.array2d(dtype=float),
                          friction: wp.array(dtype=float), area: wp.array(dtype=float), max_pressure: float, h: float,
                          y: wp.array(dtype=wp.vec3), used: wp.array(dtype=float)):
    """Coulomb friction on each vertex's inertial prediction y (its velocity and weight over the
    substep): the tangential slide relative to the body is cut by up to μ λ h²/m, and the force it
    took (``used``) is not available to the sweeps' friction (``body_stick_slip``).

    The normal force λ is at most ``max_pressure`` x the vertex's area: a posed skinned body
    overlaps itself where real skin would give way (arm and torso at the armpit), and the penalty
    of cloth squeezed into such an overlap (50 N per vertex for 5 mm) pinned it while the arm
    dragged its neighbours on: triangles there stretched past 100 %."""
    i = wp.tid()
    used[i] = 0.0
    if active[i] == 0 or mass[i] <= 0.0:
        return
    best = friction_part(i, has, normal, lam)
    if best < 0:
        return
    n = normal[i, best]
    rel = (y[i] - x_prev[i]) - body_disp[i, best]
    t = rel - n * wp.dot(rel, n)
    lt = wp.length(t)
    if lt < 1.0e-12:
        return
    m_h2 = mass[i] / (h * h)
    limit = friction[i] * wp.min(lam[i, best], max_pressure * area[i])
    take = wp.min(lt, limit / m_h2)
    y[i] = y[i] - t * (take / lt)
    used[i] = take * m_h2


@wp.kernel
def copy_colour(colour_verts: wp.array(dtype=wp.int32), src: wp.array(dtype=wp.vec3), dst: wp.array(dtype=wp.vec3)):
    tid = wp.tid()
    i = colour_verts[tid]
    dst[i] = src[i]


@wp.kernel
def chebyshev(x: wp.array(dtype=wp.vec3), x_nm1: wp.array(dtype=wp.vec3), x_nm2: wp.array(dtype=wp.vec3),
              x_det: wp.array(dtype=wp.vec3), bound_end: wp.array(dtype=wp.vec3), bound: wp.array(dtype=float),
              active: wp.array(dtype=wp.int32), omega: float, contacts: wp.array(dtype=wp.int32), skip_contacts: int,
              body_has: wp.array2d(dtype=wp.int32), skip_body: int):
    """Chebyshev semi-iterative acceleration of the sweeps (Wang 2015; VBD §3.5), bounded like the
    sweeps themselves (:func:`bounded_move`); keeps the last two iterates. With ``skip_contacts``, a vertex with
    cloth-cloth contacts (``contacts[i] > 0``) keeps its sweep's result; with ``skip_body``, one
    with a body contact (any ``body_has[i, part]``)."""
    i = wp.tid()
    xi = x[i]
    accelerate = active[i] != 0 and omega != 1.0 and (skip_contacts == 0 or contacts[i] == 0)
    if accelerate and skip_body != 0:
        for j in range(body_has.shape[1]):
            if body_has[i, j] != 0:
                accelerate = False
    if accelerate:
        xi = bounded_move(x_nm2[i] + (xi - x_nm2[i]) * omega, x_det[i], bound_end[i], bound[i])
        x[i] = xi
    x_nm2[i] = x_nm1[i]
    x_nm1[i] = xi


@wp.kernel
def record_slip(x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3), has: wp.array2d(dtype=wp.int32),
                normal: wp.array2d(dtype=wp.vec3), disp: wp.array2d(dtype=wp.vec3), lam: wp.array2d(dtype=float),
                slip: wp.array(dtype=float)):
    """How far each vertex slid along the body part whose friction acts on it next substep, over the
    substep that just ended [m] (0 where none does): the global step's lagged slip."""
    i = wp.tid()
    p = friction_part(i, has, normal, lam)
    slip[i] = 0.0
    if p >= 0:
        n = normal[i, p]
        rel = (x[i] - x_prev[i]) - disp[i, p]
        slip[i] = wp.length(rel - n * wp.dot(n, rel))


@wp.kernel
def body_contact_force(x: wp.array(dtype=wp.vec3), has: wp.array2d(dtype=wp.int32), point: wp.array2d(dtype=wp.vec3),
                       normal: wp.array2d(dtype=wp.vec3), radius: wp.array(dtype=float), k: float,
                       lam: wp.array2d(dtype=float)):
    """The body's normal force on each vertex at the end of a substep, per part plane: the next
    substep's friction normal force (lagged, as in IPC), so friction does not depend on the
    iterate's penetration."""
    i = wp.tid()
    for p in range(has.shape[1]):
        lam[i, p] = 0.0
        if has[i, p] == 1:
            d = wp.dot(x[i] - point[i, p], normal[i, p])
            if d < radius[i]:
                lam[i, p] = k * (radius[i] - d)
