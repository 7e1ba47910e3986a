"""Warp kernels of the body projection at the end of every substep: the inside test with its
provable skip (:func:`may_have_entered`; the body parts' travel from :func:`body_parts_moved` and
:func:`add_travel`) and the move out of the body of the vertices it finds inside. Split from
:mod:`datagen.sim.kernels` (the solve and the body contact); :mod:`datagen.sim.solver` arranges the
launches. Every array is an explicit argument; the kernels run unchanged on CPU and CUDA."""

from __future__ import annotations

import warp as wp

from datagen.sim.detection_kernels import register_capped
from datagen.sim.kernels import body_surface_point

CHECK_SLACK = wp.constant(1.0e-4)
"""Safety margin of the projection's skip [m]: covers float32 rounding of the accumulated body
travel (about 1e-6 of its value; 1e-4 m at 100 m of travel) and of the distances."""


@wp.func
def box_distance(p: wp.vec3, lo: wp.vec3, hi: wp.vec3) -> float:
    """Distance from ``p`` to the box [lo, hi] (0 inside it)."""
    d = wp.max(wp.max(lo - p, p - hi), wp.vec3(0.0))
    return wp.length(d)


@wp.func
def may_have_entered(i: int, s: int, parts: int, moved: float, travel: wp.array2d(dtype=float),
                     check_travel: wp.array2d(dtype=float), check_bound: wp.array2d(dtype=float)) -> bool:
    """Whether cloth vertex ``i`` (scene ``s``), found outside the body at its last inside test,
    may be inside now. ``moved``: how far it has moved since, relative to its scene's reference body
    vertex; per body part p: ``check_bound[i, p]``, a lower bound on its distance from the part's
    surface then (0: unknown), and ``travel[s, p] - check_travel[i, p]``, a bound on how far any
    vertex of the part has moved since, relative to the reference (the sum of the substeps'
    largest relative moves).

    Exact, not a heuristic: the winding number changes only where a point crosses the surface.
    Translate everything by the reference's move (which changes no winding number) and take the
    straight path from then to now for the vertex and for every body vertex: a point of a part's
    surface is a convex combination of its face's corners, so it moves at most the part's travel;
    where the vertex's move plus that travel is below its distance from every part, it meets no
    surface on the path and is outside now as it was."""
    for p in range(parts):
        if moved + (travel[s, p] - check_travel[i, p]) + CHECK_SLACK >= check_bound[i, p]:
            return True
    return False


@wp.kernel
def body_parts_moved(prev: wp.array(dtype=wp.vec3), now: wp.array(dtype=wp.vec3),
                     part_vertices: wp.array(dtype=wp.int32), part_offsets: wp.array(dtype=wp.int32),
                     body_ref: wp.array(dtype=wp.int32), parts: int, chunk: int,
                     step_max: wp.array2d(dtype=float), box_lo: wp.array2d(dtype=wp.vec3),
                     box_hi: wp.array2d(dtype=wp.vec3)):
    """Per (scene, part) (dim 0: s * parts + p) and chunk of ``chunk`` of the part's vertices (dim
    1): the largest move of a vertex from ``prev`` to ``now`` relative to the scene's reference
    vertex, max-reduced into ``step_max`` (zeroed before), and the part's bounding box at ``now``
    (``box_lo``/``box_hi`` reset to +-inf before)."""
    sp, c = wp.tid()
    s = sp // parts
    p = sp - s * parts
    r = body_ref[s]
    if r < 0:
        return
    dr = now[r] - prev[r]
    lo = part_offsets[sp] + c * chunk
    hi = wp.min(lo + chunk, part_offsets[sp + 1])
    if hi <= lo:
        return
    m = float(0.0)
    blo = now[part_vertices[lo]]
    bhi = blo
    for k in range(lo, hi):
        j = part_vertices[k]
        m = wp.max(m, wp.length((now[j] - prev[j]) - dr))
        blo = wp.min(blo, now[j])
        bhi = wp.max(bhi, now[j])
    wp.atomic_max(step_max, s, p, m)
    wp.atomic_min(box_lo, s, p, blo)
    wp.atomic_max(box_hi, s, p, bhi)


@wp.kernel
def add_travel(step_max: wp.array2d(dtype=float), travel: wp.array2d(dtype=float)):
    """``travel += step_max``, then ``step_max = 0`` (per scene and part)."""
    s, p = wp.tid()
    travel[s, p] = travel[s, p] + step_max[s, p]
    step_max[s, p] = 0.0


@wp.kernel
def test_inside_body(body_meshes: wp.array(dtype=wp.uint64), scene: wp.array(dtype=wp.int32),
                     body_now: wp.array(dtype=wp.vec3), query: float, active: wp.array(dtype=wp.int32),
                     x: wp.array(dtype=wp.vec3), again: int, inside: wp.array(dtype=wp.int32),
                     pending: wp.array(dtype=wp.int32), hit_face: wp.array(dtype=wp.int32),
                     hit_uv: wp.array(dtype=wp.vec2), body_ref: wp.array(dtype=wp.int32), parts: int,
                     travel: wp.array2d(dtype=float), box_lo: wp.array2d(dtype=wp.vec3),
                     box_hi: wp.array2d(dtype=wp.vec3), check_x: wp.array(dtype=wp.vec3),
                     check_travel: wp.array2d(dtype=float), check_bound: wp.array2d(dtype=float),
                     skipped: wp.array(dtype=wp.int32), skip_tests: int, accuracy: float,
                     order: wp.array(dtype=wp.int32)):
    """The projection's inside test (its first half; :func:`move_out_of_body` is the second): marks
    in ``pending`` the vertices inside the body (winding number, the same test as the penetration
    metric), with their closest body face and its barycentric (u, v) in ``hit_face``/``hit_uv``.

    ``again`` 0: a first pass, which also marks them in ``inside``; 1: a second pass, which looks at
    those alone (the others have not moved since the first pass found them outside, and the body
    has not moved either, so it would find them outside again).

    The first pass skips a vertex that cannot have entered the body since its last test (see
    :func:`may_have_entered`): ``check_*`` hold where that test found it outside (relative to the
    scene's reference body vertex) and how far from each body part (``check_bound`` 0: test it);
    ``skipped`` marks the vertices skipped this pass. ``accuracy``: the winding number's β
    (``SolverConfig.projection_accuracy``).

    The test and the move are two kernels so that the test, which every vertex near the body takes
    every substep, is compiled apart from the move's search (26 directions, each a winding number),
    which few vertices take: on its own the test needs fewer registers and no large stack, so more
    threads run at once. Thread t takes vertex ``order[t]`` (``model.launch_order``)."""
    i = order[wp.tid()]
    pending[i] = 0
    if again == 0:
        inside[i] = 0
        skipped[i] = 0
    elif inside[i] == 0:
        return
    if active[i] == 0:
        return
    s = scene[i]
    ref = body_ref[s]
    if skip_tests == 0:
        ref = -1
    if again == 0 and ref >= 0:
        moved = wp.length((x[i] - body_now[ref]) - check_x[i])
        if not may_have_entered(i, s, parts, moved, travel, check_travel, check_bound):
            skipped[i] = 1
            return
    mesh = body_meshes[s]
    q = wp.mesh_query_point_sign_winding_number(mesh, x[i], query, accuracy, 0.5)
    check_bound[i, 0] = 0.0
    if not q.result:
        return
    if q.sign >= 0.0:
        if ref >= 0:
            check_x[i] = x[i] - body_now[ref]
            dist = wp.length(x[i] - wp.mesh_eval_position(mesh, q.face, q.u, q.v))
            for part in range(parts):
                check_travel[i, part] = travel[s, part]
                check_bound[i, part] = wp.max(dist, box_distance(x[i], box_lo[s, part], box_hi[s, part]))
        return
    inside[i] = 1
    pending[i] = 1
    hit_face[i] = q.face
    hit_uv[i] = wp.vec2(q.u, q.v)


@wp.kernel
def move_out_of_body(body_meshes: wp.array(dtype=wp.uint64), body_face_base: wp.array(dtype=wp.int32),
                     scene: wp.array(dtype=wp.int32), body_faces: wp.array2d(dtype=wp.int32),
                     body_prev: wp.array(dtype=wp.vec3), body_now: wp.array(dtype=wp.vec3), query: float,
                     radius: wp.array(dtype=float), h: float, reach: float, x: wp.array(dtype=wp.vec3),
                     v: wp.array(dtype=wp.vec3), projected: wp.array(dtype=wp.int32),
                     pending: wp.array(dtype=wp.int32), hit_face: wp.array(dtype=wp.int32),
                     hit_uv: wp.array(dtype=wp.vec2), accuracy: float, order: wp.array(dtype=wp.int32)):
    """Hard non-penetration at the end of a substep, for the vertices :func:`test_inside_body` found
    inside (``pending``): the vertex moves to its closest body point plus half its contact radius
    along the face normal, and loses the velocity with which it moved into the body relative to the
    body's own velocity there (an inelastic impact; the tangential part is kept). The penalty
    contact does the work in the solve; this catches what it leaves inside, where one closest-point
    plane per vertex is not enough (armpits, crotch, between the legs) or the body moves faster than
    the penalty can push. Thread t takes vertex ``order[t]``."""
    i = order[wp.tid()]
    if pending[i] == 0:
        return
    s = scene[i]
    mesh = body_meshes[s]
    uv = hit_uv[i]
    p, n, disp = body_surface_point(body_face_base[s] + hit_face[i], uv[0], uv[1], body_faces, body_prev, body_now)
    if wp.length(n) == 0.0:
        return
    vb = disp / h
    r = radius[i]
    found = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    if wp.dot(x[i] - p, n) < 0.25 * r:
        # behind its closest face: out along the face normal, if that is outside (in a crease
        # between two faces, e.g. the crotch or an armpit, it can land under the other face)
        cand = p + n * (0.5 * r)
        qn = wp.mesh_query_point_sign_winding_number(mesh, cand, query, accuracy, 0.5)
        if (not qn.result) or qn.sign > 0.0:
            x[i] = cand
            found = 1
    if found == 0:
        # in front of its closest face yet inside, or the normal led nowhere: where body parts
        # overlap (an arm sunk into the torso, thighs into each other) the closest face is not the
        # way out. Take the nearest outside point among 26 directions at distances r, 2r, 4r, ...
        # up to ``reach`` (a vertex deeper than that stays inside: a longer jump would tear its
        # triangles, which the membrane cannot follow within the substep).
        t = r
        for _step in range(6):
            if found == 0 and t <= reach:
                for k in range(26):
                    if found == 0:
                        dz = float(k % 3) - 1.0
                        dy = float((k // 3) % 3) - 1.0
                        dx = float(k // 9) - 1.0
                        if k >= 13:  # skip (0, 0, 0)
                            dz = float((k + 1) % 3) - 1.0
                            dy = float(((k + 1) // 3) % 3) - 1.0
                            dx = float((k + 1) // 9) - 1.0
                        d = wp.normalize(wp.vec3(dx, dy, dz))
                        cand = x[i] + d * t
                        qc = wp.mesh_query_point_sign_winding_number(mesh, cand, query, accuracy, 0.5)
                        if (not qc.result) or qc.sign > 0.0:
                            x[i] = cand
                            n = d
                            found = 1
            t = t * 2.0
    rel = wp.dot(v[i] - vb, n)
    if rel < 0.0:
        v[i] = v[i] - n * rel
    wp.atomic_add(projected, scene[i], 1)


# a register-capped copy (``SolverConfig.register_caps``; detection_kernels.register_capped): the
# inside test runs for every cloth vertex near the body, every substep (80 registers uncapped, 768
# threads an SM)
test_inside_body_capped = register_capped(test_inside_body, 4)  # 64 registers, 1,024 threads
