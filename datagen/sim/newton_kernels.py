"""Warp kernels of the solver's global step: one Newton step of the whole substep's incremental
potential, solved by preconditioned conjugate gradients, before the vertex block descent sweeps.

Why: a vertex block descent sweep carries a load one vertex further, so woven cloth (membrane
stiffness k in the thousands of N/m against an inertia m/h² of about 1 N/m per vertex) needs
hundreds of sweeps before a garment's weight reaches the seam that carries it; at the production 20
sweeps a hanging cotton strip stretched 7x its static answer and oscillated without end, and its
mechanical energy rose (``benchmarks/convergence.py``). Conjugate gradients carry it across the
whole cloth in a few dozen matrix products, as implicit Euler solvers have done since Baraff and
Witkin (1998); the sweeps that follow add what the global step leaves out (cloth-cloth contacts,
body friction, the lock's kinks) and keep the conservative bounds.

The system is the incremental potential's Gauss-Newton Hessian at the substep's initial guess x₀:

    (M/h² + H_membrane + H_bending + D_other) d = f(x₀)

with H_membrane the full (all corner pairs) Gauss-Newton Hessian of the orthotropic StVK energy
plus its geometric part with the 2nd Piola stress projected to be positive semi-definite, both
times (1 + k_d/h) for Rayleigh damping; H_bending the hinges' Gauss-Newton Hessian k ∇θ∇θᵀ
(1 + k_d/h); and D_other the per-vertex blocks of the lock and the body contact penalty. f(x₀) is
the full force of those energies and inertia. The preconditioner is the block diagonal (each
vertex's 3x3). The matrix is applied element by element, never assembled.

No float sum depends on the order in which threads run: each element writes its share of a product
at its corners and every vertex gathers its own faces' and hinges' shares in its fixed incidence
order (:func:`gather_product`); the per-scene dot products are summed by one block of threads per
scene in a fixed order (:func:`scene_dot`). So a GPU run repeats
bitwise, and a scene's result is the same in any batch and on any number of GPUs.

Every scene of a batch has its own scalars (the products and step lengths of its own
conjugate-gradient iteration), so a scene's result does not depend on what else is in its batch.
"""

from __future__ import annotations

import warp as wp

from datagen.sim.kernels import (body_plane_force_hessian, bounded_move, buckled_stiffness, friction_force_hessian,
                                 friction_limit, friction_part, hinge_frame, hinge_gradients, lock_force_hessian, vec5)
from datagen.sim.kernel_groups import BodyContact, Bending, Membrane, Substep, Vertices


@wp.func
def _corner_weights(D: wp.mat22, local: int) -> wp.vec2:
    c = wp.vec2(-(D[0, 0] + D[1, 0]), -(D[0, 1] + D[1, 1]))
    if local == 1:
        c = wp.vec2(D[0, 0], D[0, 1])
    elif local == 2:
        c = wp.vec2(D[1, 0], D[1, 1])
    return c


@wp.func
def _psd_stress(s00: float, s01: float, s11: float) -> wp.mat22:
    """The 2x2 stress with its negative principal values set to zero (compression carries no
    geometric stiffness: the Hessian stays positive semi-definite)."""
    mean = 0.5 * (s00 + s11)
    rad = wp.sqrt(0.25 * (s00 - s11) * (s00 - s11) + s01 * s01)
    l1 = mean + rad
    l2 = mean - rad
    if l2 >= 0.0:
        return wp.mat22(s00, s01, s01, s11)
    if l1 <= 0.0:
        return wp.mat22(0.0, 0.0, 0.0, 0.0)
    # keep l1 only: l1 v vᵀ with v the eigenvector of l1
    v = wp.vec2(1.0, 0.0)
    if rad > 1.0e-20:
        if s00 >= s11:
            v = wp.normalize(wp.vec2(l1 - s11, s01))
        else:
            v = wp.normalize(wp.vec2(s01, l1 - s00))
    return wp.mat22(l1 * v[0] * v[0], l1 * v[0] * v[1], l1 * v[0] * v[1], l1 * v[1] * v[1])


@wp.kernel
def vertex_force_diagonal(x: wp.array(dtype=wp.vec3), verts: Vertices, membrane: Membrane, bending: Bending,
                          body: BodyContact, sub: Substep, face_force: wp.array2d(dtype=wp.vec3),
                          edge_force: wp.array2d(dtype=wp.vec3), force_out: wp.array(dtype=wp.vec3),
                          diag_other: wp.array(dtype=wp.mat33)):
    """Every vertex's force (inertia, membrane with lock and damping, bending, body contact and
    friction) and the 3x3 block of the Hessian that the element products do not give (inertia,
    lock, body contact and friction). The membrane's StVK and damping forces and the hinges'
    forces are each element's shares at its corners (``face_force``, ``edge_force``: written by
    :func:`membrane_linearise` and :func:`bending_linearise` at the same x), gathered here in the
    vertex's fixed incidence order; each element is evaluated once, not once for each of its corners
    (the per-corner evaluation took 5.6 conjugate-gradient iterations' time on the CPU).

    Body friction is the sweeps' (the part that pressed hardest, its lagged normal force capped at
    ``friction_pressure`` x the vertex's area, less what the inertial prediction used), as a
    Coulomb force smoothed below ``eps_u``: a vertex held by friction is a stiff tangential spring
    here, so the global step does not slide cloth along the body that friction holds. (Without it
    the global step found the frictionless equilibrium every substep and the sweeps could not take
    it all back: an elastic skirt band on the hips, which narrow upwards, crept 8.5 cm up the body
    of a person standing still, and 25 of 32 skirts of a paper-motion-like store failed on slip.)

    ``body.global_friction`` 2 (lagged) smooths the spring below the vertex's slide of the last substep
    (``sub.slip``) instead: a vertex that slid keeps the Coulomb force μλ at that slide, where the
    stiff spring, linearised once, pulled it along with the skin with whatever force that took
    (the silk dress of the long runs tore at 121 % stretch, the pants at 361 %). 1: the stiff
    spring; 0: no friction here."""
    i = wp.tid()
    if verts.active[i] == 0:
        force_out[i] = wp.vec3(0.0)
        diag_other[i] = wp.identity(n=3, dtype=float)
        return
    xi = x[i]
    m_h2 = verts.mass[i] / (sub.h * sub.h)
    force = (sub.inertia_target[i] - xi) * m_h2
    hess = wp.identity(n=3, dtype=float) * m_h2
    for k in range(membrane.v2f_offsets[i], membrane.v2f_offsets[i + 1]):
        f = membrane.v2f[k, 0]
        local = membrane.v2f[k, 1]
        force += face_force[f, local]
        lk = membrane.lock[f]
        if lk[1] > 0.0:
            D = membrane.dm_inv[f]
            x0 = x[membrane.faces[f, 0]]
            x1 = x[membrane.faces[f, 1]]
            x2 = x[membrane.faces[f, 2]]
            f0 = (x1 - x0) * D[0, 0] + (x2 - x0) * D[1, 0]
            f1 = (x1 - x0) * D[0, 1] + (x2 - x0) * D[1, 1]
            fl, hl = lock_force_hessian(f0, f1, _corner_weights(D, local), lk[0], lk[1] * membrane.area[f])
            force += fl
            hess += hl
    for k in range(bending.v2e_offsets[i], bending.v2e_offsets[i + 1]):
        force += edge_force[bending.v2e[k, 0], bending.v2e[k, 1]]
    r = body.radius[i]
    for p in range(body.has.shape[1]):
        if body.has[i, p] == 1:
            fc, hc = body_plane_force_hessian(xi, body.point[i, p], body.normal[i, p], r, body.stiffness)
            force += fc
            hess += hc
    if body.global_friction != 0:
        best = friction_part(i, body.has, body.normal, body.lam)
        if best >= 0:
            limit = friction_limit(i, best, body.lam, verts.friction, verts.area, body.friction_pressure,
                                   body.friction_used)
            if limit > 0.0:
                smooth = sub.eps_u
                if body.global_friction == 2:
                    smooth = wp.max(sub.eps_u, sub.slip[i])
                ff, hf = friction_force_hessian((xi - sub.x_prev[i]) - body.disp[i, best], body.normal[i, best], limit,
                                                smooth)
                force += ff
                hess += hf
    force_out[i] = force
    diag_other[i] = hess


@wp.func
def _membrane_frame(x: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32), D: wp.mat22, f: int):
    """The deformation gradient's two columns of face ``f``."""
    x0 = x[faces[f, 0]]
    x1 = x[faces[f, 1]]
    x2 = x[faces[f, 2]]
    return (x1 - x0) * D[0, 0] + (x2 - x0) * D[1, 0], (x1 - x0) * D[0, 1] + (x2 - x0) * D[1, 1]


@wp.func
def _membrane_law(f0: wp.vec3, f1: wp.vec3, law: vec5, majorise: int):
    """The stiffnesses (k_u, k_v, k_uv, k_s) the Hessian uses at this deformation and the
    PSD-projected 2nd Piola stress (always the buckling branch's, the true stress).

    ``majorise`` 0: the Hessian's stiffnesses are the branch's at x (a compressed direction's x r);
    1: the tension branch's, the larger curvature of the two, so that the quadratic model bounds the
    membrane's energy in G from above on both branches and a step from compression into tension
    cannot overshoot (the model under-estimated the curvature there by 1/r = 10x)."""
    g00 = 0.5 * (wp.dot(f0, f0) - 1.0)
    g11 = 0.5 * (wp.dot(f1, f1) - 1.0)
    g01 = 0.5 * wp.dot(f0, f1)
    k = buckled_stiffness(law, g00, g11)
    S = _psd_stress(k[0] * g00 + k[2] * g11, 2.0 * k[3] * g01, k[1] * g11 + k[2] * g00)
    if majorise != 0:
        k = wp.vec4(law[0], law[1], law[2], law[3])
    return k, S


@wp.kernel
def element_diagonal(dm_inv: wp.array(dtype=wp.mat22), frame: wp.array2d(dtype=wp.vec3), law: wp.array(dtype=wp.vec4),
                     stress: wp.array(dtype=wp.mat22), face_scale: wp.array(dtype=float),
                     edges: wp.array2d(dtype=wp.int32), grad: wp.array2d(dtype=wp.vec3),
                     hinge_scale: wp.array(dtype=float),
                     v2f_offsets: wp.array(dtype=wp.int32), v2f: wp.array2d(dtype=wp.int32),
                     v2e_offsets: wp.array(dtype=wp.int32), v2e: wp.array2d(dtype=wp.int32),
                     out_diag: wp.array(dtype=wp.mat33)):
    """Each vertex's 3x3 diagonal block of H_membrane + H_bending (orthotropic StVK Gauss-Newton
    with the PSD-projected geometric part, and the hinges' k ∇θ∇θᵀ, both times 1 + k_d/h), summed
    over its own faces and hinges in their fixed order, from the elements' linearisation
    (:func:`membrane_linearise`, :func:`bending_linearise`)."""
    i = wp.tid()
    blk_sum = wp.mat33(0.0)
    for n in range(v2f_offsets[i], v2f_offsets[i + 1]):
        f = v2f[n, 0]
        D = dm_inv[f]
        f0 = frame[f, 0]
        f1 = frame[f, 1]
        k = law[f]
        S = stress[f]
        c = _corner_weights(D, v2f[n, 1])
        a = f0 * c[0]
        b = f1 * c[1]
        s = f0 * c[1] + f1 * c[0]
        blk = (wp.outer(a, a) * k[0] + wp.outer(b, b) * k[1] + (wp.outer(a, b) + wp.outer(b, a)) * k[2]
               + wp.outer(s, s) * k[3])
        geo = c[0] * (S[0, 0] * c[0] + S[0, 1] * c[1]) + c[1] * (S[1, 0] * c[0] + S[1, 1] * c[1])
        blk = blk + wp.identity(n=3, dtype=float) * geo
        blk_sum += blk * face_scale[f]
    for n in range(v2e_offsets[i], v2e_offsets[i + 1]):
        e = v2e[n, 0]
        if edges[e, 2] >= 0 and edges[e, 3] >= 0:
            g = grad[e, v2e[n, 1]]
            blk_sum += wp.outer(g, g) * hinge_scale[e]
    out_diag[i] = blk_sum


@wp.func
def _membrane_frame_delta(x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3),
                          faces: wp.array2d(dtype=wp.int32), D: wp.mat22, f: int):
    """The columns of the deformation gradient of face ``f``'s displacement x - x_prev."""
    u0 = x[faces[f, 0]] - x_prev[faces[f, 0]]
    u1 = x[faces[f, 1]] - x_prev[faces[f, 1]]
    u2 = x[faces[f, 2]] - x_prev[faces[f, 2]]
    return (u1 - u0) * D[0, 0] + (u2 - u0) * D[1, 0], (u1 - u0) * D[0, 1] + (u2 - u0) * D[1, 1]


@wp.kernel
def membrane_linearise(x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32),
                       dm_inv: wp.array(dtype=wp.mat22), tri_area: wp.array(dtype=float),
                       tri_stiff: wp.array(dtype=vec5), damping: wp.array(dtype=float), h: float, majorise: int,
                       frame: wp.array2d(dtype=wp.vec3), law: wp.array(dtype=wp.vec4), stress: wp.array(dtype=wp.mat22),
                       scale: wp.array(dtype=float), force: wp.array2d(dtype=wp.vec3)):
    """What :func:`membrane_product` needs of each triangle at the step's linearisation point x,
    computed once a Newton step instead of once a conjugate-gradient iteration (x does not move
    while they run): its deformation gradient's columns ``frame[f]``, its stiffnesses ``law[f]``,
    its PSD-projected stress ``stress[f]`` and its area times 1 + k_d/h ``scale[f]``; and its
    orthotropic StVK force with Rayleigh damping at each corner ``force[f, corner]`` (the lock's
    is the vertex's: :func:`vertex_force_diagonal`), the same force as
    ``kernels.membrane_force_hessian`` gives each corner, evaluated once for the triangle."""
    f = wp.tid()
    D = dm_inv[f]
    f0, f1 = _membrane_frame(x, faces, D, f)
    k, S = _membrane_law(f0, f1, tri_stiff[f], majorise)
    frame[f, 0] = f0
    frame[f, 1] = f1
    law[f] = k
    stress[f] = S
    kd = damping[faces[f, 0]]
    A = tri_area[f]
    scale[f] = A * (1.0 + kd / h)
    # the true stress (buckling branch at x, not the majoriser's stiffnesses) and the damping's
    g00 = 0.5 * (wp.dot(f0, f0) - 1.0)
    g11 = 0.5 * (wp.dot(f1, f1) - 1.0)
    g01 = 0.5 * wp.dot(f0, f1)
    kb = buckled_stiffness(tri_stiff[f], g00, g11)
    s00 = kb[0] * g00 + kb[2] * g11
    s11 = kb[1] * g11 + kb[2] * g00
    s01 = 2.0 * kb[3] * g01
    if kd > 0.0:
        # Rayleigh damping: the material tangent on the Green strain rate over the substep
        d0, d1 = _membrane_frame_delta(x, x_prev, faces, D, f)
        r00 = wp.dot(f0, d0)
        r11 = wp.dot(f1, d1)
        r01 = 0.5 * (wp.dot(f0, d1) + wp.dot(f1, d0))
        rate = kd / h
        s00 += (kb[0] * r00 + kb[2] * r11) * rate
        s11 += (kb[1] * r11 + kb[2] * r00) * rate
        s01 += 2.0 * kb[3] * r01 * rate
    for j in range(3):
        c = _corner_weights(D, j)
        force[f, j] = -(f0 * (s00 * c[0] + s01 * c[1]) + f1 * (s01 * c[0] + s11 * c[1])) * A


@wp.kernel
def membrane_product(faces: wp.array2d(dtype=wp.int32), dm_inv: wp.array(dtype=wp.mat22),
                     frame: wp.array2d(dtype=wp.vec3), law: wp.array(dtype=wp.vec4), stress: wp.array(dtype=wp.mat22),
                     scale: wp.array(dtype=float), p: wp.array(dtype=wp.vec3), out: wp.array2d(dtype=wp.vec3)):
    """Each triangle's share of H_membrane p at its three corners, ``out[f, corner]`` (gathered per
    vertex by :func:`gather_product`, so no sum depends on thread order), from the triangle's
    linearisation (:func:`membrane_linearise`)."""
    f = wp.tid()
    i0 = faces[f, 0]
    i1 = faces[f, 1]
    i2 = faces[f, 2]
    D = dm_inv[f]
    f0 = frame[f, 0]
    f1 = frame[f, 1]
    k = law[f]
    S = stress[f]
    A = scale[f]
    c0 = _corner_weights(D, 0)
    c1 = _corner_weights(D, 1)
    c2 = _corner_weights(D, 2)
    p0 = p[i0]
    p1 = p[i1]
    p2 = p[i2]
    df0 = p0 * c0[0] + p1 * c1[0] + p2 * c2[0]
    df1 = p0 * c0[1] + p1 * c1[1] + p2 * c2[1]
    al = wp.dot(f0, df0)
    be = wp.dot(f1, df1)
    sg = wp.dot(f0, df1) + wp.dot(f1, df0)
    ta = k[0] * al + k[2] * be
    tb = k[1] * be + k[2] * al
    ts = k[3] * sg
    # geometric part: Σ_k (c_jᵀ S c_k) p_k = (dF S) c_j with dF = [df0 df1]
    g0 = df0 * S[0, 0] + df1 * S[1, 0]
    g1 = df0 * S[0, 1] + df1 * S[1, 1]
    for j in range(3):
        c = _corner_weights(D, j)
        out[f, j] = (f0 * (c[0] * ta + c[1] * ts) + f1 * (c[1] * tb + c[0] * ts) + g0 * c[0] + g1 * c[1]) * A


@wp.kernel
def bending_linearise(x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3), edges: wp.array2d(dtype=wp.int32),
                      rest_angle: wp.array(dtype=float), bend_k: wp.array(dtype=float), damping: wp.array(dtype=float),
                      h: float, grad: wp.array2d(dtype=wp.vec3), scale: wp.array(dtype=float),
                      force: wp.array2d(dtype=wp.vec3)):
    """What :func:`bending_product` needs of each hinge at the linearisation point x, once a Newton
    step: the angle's gradients at its four stencil vertices ``grad[e]`` and k (1 + k_d/h)
    ``scale[e]``; and the hinge's force with Rayleigh damping on the angle's rate at each stencil
    vertex ``force[e, slot]`` (``kernels.bending_force_hessian``'s, evaluated once for the hinge).
    All zero for a boundary edge or a degenerate hinge."""
    e = wp.tid()
    zero = wp.vec3(0.0)
    if edges[e, 2] < 0 or edges[e, 3] < 0:
        for j in range(4):
            grad[e, j] = zero
            force[e, j] = zero
        scale[e] = 0.0
        return
    x0 = x[edges[e, 0]]
    x1 = x[edges[e, 1]]
    x2 = x[edges[e, 2]]
    x3 = x[edges[e, 3]]
    g0, g1, g2, g3 = hinge_gradients(x0, x1, x2, x3)
    grad[e, 0] = g0
    grad[e, 1] = g1
    grad[e, 2] = g2
    grad[e, 3] = g3
    k = bend_k[e]
    kd = damping[edges[e, 0]]
    scale[e] = k * (1.0 + kd / h)
    E, L, N1, N2, n1sq, n2sq = hinge_frame(x0, x1, x2, x3)
    if L < 1.0e-12 or n1sq < 1.0e-24 or n2sq < 1.0e-24:
        for j in range(4):
            force[e, j] = zero
        return
    Eh = E / L
    n1 = N1 / wp.sqrt(n1sq)
    n2 = N2 / wp.sqrt(n2sq)
    theta = wp.atan2(wp.dot(wp.cross(n1, n2), Eh), wp.dot(n1, n2))
    t = k * (theta - rest_angle[e])
    if kd > 0.0:
        rate = (wp.dot(g0, x0 - x_prev[edges[e, 0]]) + wp.dot(g1, x1 - x_prev[edges[e, 1]])
                + wp.dot(g2, x2 - x_prev[edges[e, 2]]) + wp.dot(g3, x3 - x_prev[edges[e, 3]]))
        t += k * rate * kd / h
    force[e, 0] = -g0 * t
    force[e, 1] = -g1 * t
    force[e, 2] = -g2 * t
    force[e, 3] = -g3 * t


@wp.kernel
def bending_product(edges: wp.array2d(dtype=wp.int32), grad: wp.array2d(dtype=wp.vec3), scale: wp.array(dtype=float),
                    p: wp.array(dtype=wp.vec3), out: wp.array2d(dtype=wp.vec3)):
    """Each hinge's share of its Gauss-Newton Hessian k (1 + k_d/h) ∇θ∇θᵀ times p at its four
    stencil vertices, ``out[e, slot]`` (zero for a boundary edge or a degenerate hinge), from the
    hinge's linearisation (:func:`bending_linearise`)."""
    e = wp.tid()
    if edges[e, 2] < 0 or edges[e, 3] < 0:
        for j in range(4):
            out[e, j] = wp.vec3(0.0)
        return
    g0 = grad[e, 0]
    g1 = grad[e, 1]
    g2 = grad[e, 2]
    g3 = grad[e, 3]
    s = scale[e] * (wp.dot(g0, p[edges[e, 0]]) + wp.dot(g1, p[edges[e, 1]]) + wp.dot(g2, p[edges[e, 2]])
                    + wp.dot(g3, p[edges[e, 3]]))
    out[e, 0] = g0 * s
    out[e, 1] = g1 * s
    out[e, 2] = g2 * s
    out[e, 3] = g3 * s


@wp.kernel
def gather_product(diag: wp.array(dtype=wp.mat33), p: wp.array(dtype=wp.vec3),
                   v2f_offsets: wp.array(dtype=wp.int32), v2f: wp.array2d(dtype=wp.int32),
                   v2e_offsets: wp.array(dtype=wp.int32), v2e: wp.array2d(dtype=wp.int32),
                   face_part: wp.array2d(dtype=wp.vec3), edge_part: wp.array2d(dtype=wp.vec3),
                   out: wp.array(dtype=wp.vec3)):
    """out = D p + Σ the vertex's faces' and hinges' shares, in the vertex's fixed incidence order."""
    i = wp.tid()
    acc = diag[i] * p[i]
    for n in range(v2f_offsets[i], v2f_offsets[i + 1]):
        acc += face_part[v2f[n, 0], v2f[n, 1]]
    for n in range(v2e_offsets[i], v2e_offsets[i + 1]):
        acc += edge_part[v2e[n, 0], v2e[n, 1]]
    out[i] = acc


@wp.kernel
def invert_blocks(diag_other: wp.array(dtype=wp.mat33), diag_elements: wp.array(dtype=wp.mat33),
                  active: wp.array(dtype=wp.int32), inverse: wp.array(dtype=wp.mat33)):
    """The preconditioner: each vertex's full 3x3 diagonal block, inverted (zero for pinned vertices)."""
    i = wp.tid()
    blk = diag_other[i] + diag_elements[i]
    if active[i] == 0 or wp.abs(wp.determinant(blk)) < 1.0e-30:
        inverse[i] = wp.mat33(0.0)
    else:
        inverse[i] = wp.inverse(blk)


@wp.kernel
def cg_start(force: wp.array(dtype=wp.vec3), inverse: wp.array(dtype=wp.mat33), active: wp.array(dtype=wp.int32),
             r: wp.array(dtype=wp.vec3), z: wp.array(dtype=wp.vec3), p: wp.array(dtype=wp.vec3),
             d: wp.array(dtype=wp.vec3)):
    """d = 0, r = f, z = P⁻¹ r, p = z."""
    i = wp.tid()
    ri = force[i]
    if active[i] == 0:
        ri = wp.vec3(0.0)
    zi = inverse[i] * ri
    r[i] = ri
    z[i] = zi
    p[i] = zi
    d[i] = wp.vec3(0.0)


@wp.kernel
def warm_start(warm: wp.array(dtype=wp.vec3), q: wp.array(dtype=wp.vec3), inverse: wp.array(dtype=wp.mat33),
               scene: wp.array(dtype=wp.int32), fw: wp.array(dtype=wp.float64), wqw: wp.array(dtype=wp.float64),
               active: wp.array(dtype=wp.int32), d: wp.array(dtype=wp.vec3), r: wp.array(dtype=wp.vec3),
               z: wp.array(dtype=wp.vec3), p: wp.array(dtype=wp.vec3)):
    """Start the iterations at d = α w instead of 0, w the correction the last substep's solve made
    to its initial guess (``warm``) and q = H w: α = fᵀw / wᵀHw of the vertex's scene, clamped to
    [0, 1], the step along w that minimises the quadratic model (so the start is never worse than
    d = 0 in the model); r = f - α q, z = P⁻¹ r, p = z."""
    i = wp.tid()
    s = scene[i]
    alpha = float(0.0)
    if wqw[s] > wp.float64(0.0) and fw[s] > wp.float64(0.0):
        alpha = wp.min(float(fw[s] / wqw[s]), 1.0)
    if active[i] == 0:
        return
    d[i] = warm[i] * alpha
    ri = r[i] - q[i] * alpha
    r[i] = ri
    zi = inverse[i] * ri
    z[i] = zi
    p[i] = zi


@wp.kernel
def record_correction(x: wp.array(dtype=wp.vec3), x_init: wp.array(dtype=wp.vec3), active: wp.array(dtype=wp.int32),
                      warm: wp.array(dtype=wp.vec3)):
    """The correction the substep's solve made to its initial guess, x - x_init (zero for an
    inactive vertex): the next substep's global step starts from it (:func:`warm_start`)."""
    i = wp.tid()
    if active[i] == 0:
        warm[i] = wp.vec3(0.0)
    else:
        warm[i] = x[i] - x_init[i]


DOT_LANES = 256
"""Threads per scene of :func:`scene_dot` on a GPU (warp's default block, so the module is compiled
once for it and for the one-thread-per-item kernels)."""


@wp.kernel
def scene_dot(a: wp.array(dtype=wp.vec3), b: wp.array(dtype=wp.vec3), particle_range: wp.array2d(dtype=wp.int32),
              out: wp.array(dtype=wp.float64)):
    """Σ a·b over each scene's vertices (float64), one block per scene (``wp.launch_tiled``): lane
    ``l`` sums the vertices ``p0 + l, p0 + l + lanes, ...`` in order, and ``wp.tile_sum`` adds the
    lanes in a fixed tree. The order is fixed by the scene's own vertices and the block size, so it
    is the same in every run and in every batch (on a CPU a block is one thread: vertex order)."""
    s, lane = wp.tid()
    acc = wp.float64(0.0)
    for i in range(particle_range[s, 0] + lane, particle_range[s, 1], wp.block_dim()):
        acc += wp.float64(wp.dot(a[i], b[i]))
    total = wp.tile_sum(wp.tile(acc))
    if lane == 0:
        out[s] = total[0]


@wp.kernel
def cg_step(p: wp.array(dtype=wp.vec3), q: wp.array(dtype=wp.vec3), inverse: wp.array(dtype=wp.mat33),
            scene: wp.array(dtype=wp.int32), rz: wp.array(dtype=wp.float64), pq: wp.array(dtype=wp.float64),
            d: wp.array(dtype=wp.vec3), r: wp.array(dtype=wp.vec3), z: wp.array(dtype=wp.vec3)):
    """α = rz/pq of the vertex's scene; d += α p; r -= α q; z = P⁻¹ r."""
    i = wp.tid()
    s = scene[i]
    alpha = float(0.0)
    if pq[s] > wp.float64(0.0):
        alpha = float(rz[s] / pq[s])
    d[i] = d[i] + p[i] * alpha
    ri = r[i] - q[i] * alpha
    r[i] = ri
    z[i] = inverse[i] * ri


@wp.kernel
def cg_direction(z: wp.array(dtype=wp.vec3), scene: wp.array(dtype=wp.int32), rz: wp.array(dtype=wp.float64),
                 rz_new: wp.array(dtype=wp.float64), p: wp.array(dtype=wp.vec3)):
    """p = z + β p with β = rz_new/rz of the vertex's scene."""
    i = wp.tid()
    s = scene[i]
    beta = float(0.0)
    if rz[s] > wp.float64(0.0):
        beta = float(rz_new[s] / rz[s])
    p[i] = z[i] + p[i] * beta


@wp.kernel
def apply_step(d: wp.array(dtype=wp.vec3), x_det: wp.array(dtype=wp.vec3), bound_end: wp.array(dtype=wp.vec3),
               bound: wp.array(dtype=float), active: wp.array(dtype=wp.int32), x: wp.array(dtype=wp.vec3)):
    """x += d, each vertex kept within its conservative bound (``bound``: the global step's, without
    the sweeps' floor: :func:`datagen.sim.kernels.global_bounds`) of the segment from its detection
    position to where the body carries it (:func:`datagen.sim.kernels.bounded_move`)."""
    i = wp.tid()
    if active[i] == 0:
        return
    x[i] = bounded_move(x[i] + d[i], x_det[i], bound_end[i], bound[i])
