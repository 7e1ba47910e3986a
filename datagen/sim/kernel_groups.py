"""The arguments of the solver's per-vertex kernels, in typed groups (``wp.struct``).

The sweep (:func:`datagen.sim.sweep_kernels.solve_colour`) and the global step's force and
diagonal (:func:`datagen.sim.newton_kernels.vertex_force_diagonal`) read the same model arrays,
contact lists and substep values. Each group is one ``wp.struct`` that the solver fills once
(:class:`~datagen.sim.solver.SolverVBD`: the model's groups at build time, the cloth-cloth lists
when they grow, the substep's values once a step) and passes as one argument; a kernel reads
``membrane.faces``, ``body.stiffness``... A new term adds a field to its group and the lines that
read it, not a position in two 40-argument lists.

Shapes: n vertices, F faces, E edges (hinges), P body parts; C the contact capacity per element.
Lengths in m, times in s. Every group works on any device (its arrays are the launch device's).
"""

from __future__ import annotations

import warp as wp

from datagen.sim.kernels import vec5


@wp.struct
class Vertices:
    """Per-vertex constants of the model."""

    mass: wp.array(dtype=float)  # [n] kg
    active: wp.array(dtype=wp.int32)  # [n] 0: pinned or frozen (held at its target)
    damping: wp.array(dtype=float)  # [n] Rayleigh stiffness damping of the vertex's material [s]
    friction: wp.array(dtype=float)  # [n] Coulomb coefficient with the body
    area: wp.array(dtype=float)  # [n] the vertex's share of the cloth's area [m²]


@wp.struct
class Membrane:
    """The triangles' orthotropic StVK membrane and the vertex-to-face adjacency."""

    faces: wp.array2d(dtype=wp.int32)  # [F, 3]
    dm_inv: wp.array(dtype=wp.mat22)  # [F] inverse rest shape matrices (weft, warp)
    area: wp.array(dtype=float)  # [F] rest area [m²]
    stiffness: wp.array(dtype=vec5)  # [F] (k_u, k_v, k_uv, k_s [N/m], buckling ratio r)
    lock: wp.array(dtype=wp.vec2)  # [F] (1 + lock strain, lock stiffness [N/m])
    v2f_offsets: wp.array(dtype=wp.int32)  # [n + 1] each vertex's range in v2f
    v2f: wp.array2d(dtype=wp.int32)  # [3F, 2] (face, corner) grouped by vertex


@wp.struct
class Bending:
    """The hinges' bending and the vertex-to-edge adjacency."""

    edges: wp.array2d(dtype=wp.int32)  # [E, 4] the edge (0, 1) and the opposite corners (2, 3; -1 on a boundary)
    rest_angle: wp.array(dtype=float)  # [E] rest dihedral angle [rad]
    stiffness: wp.array(dtype=float)  # [E] hinge stiffness [N·m] (0 on a boundary edge)
    v2e_offsets: wp.array(dtype=wp.int32)  # [n + 1] each vertex's range in v2e
    v2e: wp.array2d(dtype=wp.int32)  # [*, 2] (edge, stencil slot 0..3) grouped by vertex


@wp.struct
class BodyContact:
    """The body's contact planes per (vertex, part), its penalty and friction."""

    has: wp.array2d(dtype=wp.int32)  # [n, P] 1: the vertex has a plane of this part
    point: wp.array2d(dtype=wp.vec3)  # [n, P] the plane's point
    normal: wp.array2d(dtype=wp.vec3)  # [n, P] its unit normal
    disp: wp.array2d(dtype=wp.vec3)  # [n, P] the body's move at the contact over the substep
    radius: wp.array(dtype=float)  # [n] contact distance (thickness + margin)
    lam: wp.array2d(dtype=float)  # [n, P] the lagged normal forces [N]
    stiffness: float  # k_c [N/m]
    friction: int  # the sweeps' friction: 1 on, 0 off
    global_friction: int  # the global step's: settings.GLOBAL_FRICTION's code (0 off, 1 stiff, 2 lagged)
    friction_pressure: float  # the largest pressure friction sees [Pa]
    friction_used: wp.array(dtype=float)  # [n] friction force the inertial prediction already used [N]


@wp.struct
class SelfContact:
    """The cloth-cloth contact lists of the last detection and the contact law."""

    vt_count: wp.array(dtype=wp.int32)  # [n] triangles near each vertex
    vt_tri: wp.array2d(dtype=wp.int32)  # [n, C]
    tv_count: wp.array(dtype=wp.int32)  # [F] vertices near each triangle
    tv_vert: wp.array2d(dtype=wp.int32)  # [F, C]
    ee_count: wp.array(dtype=wp.int32)  # [E] edges near each edge
    ee_edge: wp.array2d(dtype=wp.int32)  # [E, C]
    radius: float  # contact distance
    stiffness: float  # [N/m]
    friction: float  # Coulomb coefficient


@wp.struct
class Substep:
    """What a substep's solve starts from."""

    x_prev: wp.array(dtype=wp.vec3)  # [n] positions at the substep's start
    x_det: wp.array(dtype=wp.vec3)  # [n] positions at the last cloth-cloth detection
    bound_end: wp.array(dtype=wp.vec3)  # [n] x_det carried by the body (kernels.carry_bound)
    inertia_target: wp.array(dtype=wp.vec3)  # [n] the inertial prediction y
    bound: wp.array(dtype=float)  # [n] how far a vertex may move off the segment x_det-bound_end
    slip: wp.array(dtype=float)  # [n] each vertex's slide along the body over the last substep
    h: float  # the substep [s]
    eps_u: float  # the friction's smoothing distance, friction_velocity x h
