"""The cloth solver's settings: :class:`SolverConfig` and its groups, each a frozen keyword-only dataclass.

Every field's limits are in its metadata (``min``/``max`` inclusive, ``above``/``below`` exclusive,
``choices``, and its ``unit``) and one validator, :func:`check_limits`, checks them all when a
group is made; the few limits that relate two fields of a group are checked after it. Config
files nest the groups (``[simulation.solver.self_contact] radius = 0.004``); the flat names of
before the groups (``self_radius = 0.004``) are still read, by the loader and by ``SolverConfig(...)``
(:data:`FLAT_NAMES`). What the defaults were chosen on, with the measurements, is in
``docs/solver_settings.md``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

from datagen.errors import InputError

GLOBAL_FRICTION = {"off": 0, "stiff": 1, "lagged": 2}
"""``BodyContactConfig.global_friction`` values and the code the global step's kernel takes."""

REGISTER_CAPS = {"none": (), "detection": ("detect_vertex_triangle", "detect_edge_edge", "test_inside_body")}
"""``LaunchConfig.register_caps`` values and the kernels each runs as their register-capped copies."""


def _limit(default, unit: str = "", why: str = "", **limits):
    """A field with ``default`` and its limits, unit and the reason for them (``why``) in the metadata
    (what :func:`check_limits` reads)."""
    return field(default=default, metadata={"unit": unit, "why": why, **limits})


def check_limits(config) -> None:
    """Check every field of the dataclass ``config`` against its metadata's limits (``min``, ``max``,
    ``above``, ``below``, ``choices``); an :class:`InputError` names the field, its value and what
    is allowed (and why, where the metadata's ``why`` says). Fields without limits pass."""
    for f in dataclasses.fields(config):
        meta, value = f.metadata, getattr(config, f.name)
        unit = f" [{meta['unit']}]" if meta.get("unit") else ""
        where = f"{type(config).__name__}.{f.name} = {value!r}"
        why = f": {meta['why']}" if meta.get("why") else ""
        if "choices" in meta:
            if value not in meta["choices"]:
                raise InputError(f"{where} is not allowed; choose one of {', '.join(map(repr, meta['choices']))}{why}")
            continue
        if not any(k in meta for k in ("min", "max", "above", "below")):
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InputError(f"{where} must be a finite number")
        lo = (f"{meta['min']:g} <= " if "min" in meta else f"{meta['above']:g} < " if "above" in meta else "")
        hi = (f" <= {meta['max']:g}" if "max" in meta else f" < {meta['below']:g}" if "below" in meta else "")
        if ("min" in meta and value < meta["min"] or "above" in meta and value <= meta["above"]
                or "max" in meta and value > meta["max"] or "below" in meta and value >= meta["below"]):
            raise InputError(f"{where} is out of range; allowed: {lo}{f.name}{hi}{unit}{why}")


@dataclass(frozen=True, kw_only=True)
class StepConfig:
    """How a frame is integrated: substeps, the global step and the colour sweeps.

    Attributes:
        substeps: the fewest substeps per step (frame), 1-200.
        max_substep: the longest substep [s], in (0, 0.1]: a step of dt has
            :meth:`substeps_for` (dt) = max(``substeps``, ⌈dt / ``max_substep``⌉) substeps, so the
            substep follows the frame time and not the frame count (the default, 1/300 s, is the
            production 10 substeps of a 30 fps frame; at 15 fps a frame gets 20). The solver holds
            its energy balance and statics up to this substep length with the default sweeps and
            CG iterations (``docs/simulator.md``, physics limits); at 1/150 s (15 fps with a fixed 10)
            the woven presets make energy and polyester hangs 37 % long.
        substep_edge: the mesh edge length [m] that ``max_substep`` is measured at, >= 0 (0: off): a
            finer mesh (the smallest of the scenes' median rest edge lengths) takes substeps shorter
            in proportion, since the stiffness against a vertex's mass grows as 1/edge² and the same
            sweeps and CG iterations then converge alike (denim's Cusick fall at 1 cm edges made
            energy at 10 substeps, none at 15; at 13 still 1.5e-3 of gravity's work). The default,
            1.5 cm, is the edge length the presets and the Cusick test are fitted at; of the garment
            types' default meshes only the skirt's (1.3 cm) gets more (12 at 30 fps).
        substep_cap: the most substeps the rule of :meth:`substeps_for` may ask for a step, 1-1000:
            a frame time or an edge length that needs more (a mesh of 1 mm edges at 30 fps, a frame
            of 0.5 s) is refused with an :class:`~datagen.errors.InputError` that says what to change,
            rather than run for hours (``substeps`` itself may be set higher).
        iterations: colour sweeps per substep, 1-200.
        global_iterations: conjugate-gradient iterations of the global Newton step that starts every
            substep (:mod:`datagen.sim.newton_kernels`), 0-1000; 0: off, the sweeps alone (which
            carry a load one vertex per sweep: woven cloth needs it carried across the garment at once).
        global_steps: Newton steps of the global step, 1-10, each ``global_iterations`` conjugate-gradient
            iterations from the elements relinearised where the last one ended (its forces, each
            element's deformation, its branch of the buckling law); the preconditioner is the first's.
        warm_start: start the global step's conjugate gradients from the correction the last substep's
            solve made to its initial guess (scaled per scene to the step along it that minimises the
            quadratic model, within [0, 1]) instead of from zero (``newton_kernels.warm_start``).
        compression_hessian: the stiffness the global step's Hessian gives a direction in
            compression: ``buckled`` (the buckling branch's, r x the tension stiffness, the
            curvature at x) or ``tension`` (the tension branch's, which bounds the membrane's
            energy in the Green strain from above on both branches; ``newton_kernels._membrane_law``).
        chebyshev_rho: spectral radius estimate for the Chebyshev acceleration of the sweeps, in
            [0, 1); 0: off.
        chebyshev_contacts: whether the acceleration also extrapolates vertices that have cloth-cloth
            (vertex-triangle) contacts; False leaves them at their sweep's result.
        chebyshev_body_contacts: the same for vertices in contact with the body.
        colour_hinge_wings: whether the sweeps' colouring also separates a hinge's two wing vertices
            (the corners opposite its edge, which share only the bending stencil). False colours by
            the triangles alone (fewer colours, so fewer sweep launches): a wing then reads the other
            wing's position from the sweep before (a colour's results go to a copy, so nothing
            depends on thread order).
    """

    substeps: int = _limit(10, min=1, max=200)
    max_substep: float = _limit(1.0 / 300.0, "s", above=0.0, max=0.1)
    substep_edge: float = _limit(0.015, "m", min=0.0)
    substep_cap: int = _limit(100, min=1, max=1000)
    iterations: int = _limit(20, min=1, max=200)
    global_iterations: int = _limit(20, min=0, max=1000)
    global_steps: int = _limit(1, min=1, max=10)
    warm_start: bool = True
    compression_hessian: str = field(default="buckled", metadata={"choices": ("buckled", "tension")})
    chebyshev_rho: float = _limit(0.7, min=0.0, below=1.0)
    chebyshev_contacts: bool = True
    chebyshev_body_contacts: bool = True
    colour_hinge_wings: bool = False

    def __post_init__(self):
        check_limits(self)

    def substeps_for(self, dt: float, edge: float = 0.0) -> int:
        """Substeps of a step of ``dt`` [s] on a mesh of edge length ``edge`` [m] (0: not known):
        max(``substeps``, ⌈dt / (``max_substep`` x min(1, edge / ``substep_edge``))⌉), with a
        relative 1e-6 of slack, so that 1/30 s at 1/300 s is 10, not 11 by rounding.

        Raises :class:`~datagen.errors.InputError` where the rule asks for more than
        ``substep_cap`` (and more than ``substeps``): the frame is too long or the mesh too fine
        for the solver to hold its energy balance in a sane number of substeps."""
        longest = self.max_substep
        if edge > 0.0 and self.substep_edge > 0.0:
            longest *= min(1.0, edge / self.substep_edge)
        needed = int(math.ceil(dt / longest * (1.0 - 1e-6)))
        if needed > max(int(self.substeps), int(self.substep_cap)):
            fps_min = math.ceil(1.0 / (self.substep_cap * longest) * (1.0 - 1e-9))
            edge_min = self.substep_edge * dt / (self.substep_cap * self.max_substep)
            mesh = f" on a mesh of {edge * 1e3:.3g} mm edges" if edge > 0.0 else ""
            coarser = (f", or mesh the cloth with edges of {edge_min * 1e3:.3g} mm or longer"
                       if edge > 0.0 and edge_min <= self.substep_edge else "")
            raise InputError(
                f"a step of {dt:g} s{mesh} needs {needed} substeps of at most {longest:.3g} s "
                f"(StepConfig.max_substep = {self.max_substep:.3g} s, shorter in proportion on a mesh finer than "
                f"substep_edge = {self.substep_edge * 1e3:g} mm), more than StepConfig.substep_cap = "
                f"{self.substep_cap}: simulate at {fps_min:g} frames/s or more (drape simulate --fps){coarser}, "
                f"or raise substep_cap if you accept the cost (docs/simulator.md, physics limits)")
        return max(int(self.substeps), needed)


@dataclass(frozen=True, kw_only=True)
class BodyContactConfig:
    """Contact of the cloth with the body: a penalty plane per body part, and Coulomb friction.

    Attributes:
        stiffness: contact stiffness k_c [N/m], > 0.
        margin: contact distance beyond the material's thickness [m], >= 0.
        query: contact search distance [m], > 0 (the projection searches twice as far).
        friction: Coulomb friction with the body (``kernels.body_stick_slip``); off only to diagnose
            what it does.
        friction_pressure: the largest contact pressure friction sees [Pa], > 0: a vertex's friction
            normal force is at most this x its area, so cloth squeezed where the skinned body
            overlaps itself (the armpit) is not pinned by an unbounded penalty force. An elastic
            waistband presses about 1-3 kPa, a garment's weight about 100 Pa.
        global_friction: body friction in the global step: ``lagged`` (a Coulomb force smoothed
            below the vertex's slide along the body over the last substep), ``stiff`` (smoothed below
            ``friction_velocity`` x h only: a vertex in contact follows the body in the linearised
            step) or ``off`` (``newton_kernels.vertex_force_diagonal``).
    """

    stiffness: float = _limit(1.0e4, "N/m", above=0.0)
    margin: float = _limit(0.002, "m", min=0.0)
    query: float = _limit(0.03, "m", above=0.0)
    friction: bool = True
    friction_pressure: float = _limit(1000.0, "Pa", above=0.0)
    global_friction: str = field(default="lagged", metadata={"choices": tuple(GLOBAL_FRICTION)})

    def __post_init__(self):
        check_limits(self)


@dataclass(frozen=True, kw_only=True)
class ProjectionConfig:
    """The projection that ends every substep: vertices inside the body (winding-number test) move
    out to its surface and lose their inward velocity (``projection_kernels.test_inside_body``,
    ``move_out_of_body``).

    Attributes:
        enabled: whether the projection runs.
        skip: let the inside test skip a vertex that provably cannot have entered the body since its
            last test (``projection_kernels.may_have_entered``); the result is bitwise that of
            testing every vertex. Off only to measure what it saves.
        reach: how far the search for a way out (where the closest face's normal does not lead
            outside) may move a vertex [m], >= 0.
        accuracy: β of the winding-number test (warp's fast winding number counts a subtree of the
            body's tree as its dipole when the point lies farther than β times its radius), >= 1:
            below 1 a body part counts as its dipole from inside its bounding sphere and the answer
            breaks. The penetration metric keeps warp's β = 2, so it judges the projection independently.
    """

    enabled: bool = True
    skip: bool = True
    reach: float = _limit(0.1, "m", min=0.0)
    accuracy: float = _limit(1.25, min=1.0, why="below 1 warp's winding number counts a body part as its dipole "
                             "from inside its bounding sphere, and its inside-or-out answer breaks")

    def __post_init__(self):
        check_limits(self)


@dataclass(frozen=True, kw_only=True)
class SelfContactConfig:
    """Contact of the cloth with itself: vertex-triangle and edge-edge penalties with friction,
    move bounds that keep primitives from crossing between detections, and the untangling of
    crossings that happen anyway.

    Attributes:
        enabled: whether the cloth collides with itself.
        radius: contact distance [m], > 0.
        stiffness: contact stiffness [N/m], > 0.
        friction: Coulomb friction coefficient, >= 0.
        query: search distance [m], above ``radius``: a vertex with a non-neighbouring cloth primitive
            closer than this moves at most ``bound_fraction`` of that distance per detection.
        bound_floor: the distance to the nearest cloth primitive below which the move bound stops
            shrinking [m], in (0, 1.5 x ``radius``] (primitives that touch must not freeze a vertex;
            pairs farther apart than 1.5 x ``radius`` are not contacts and cannot cross, closer ones
            are contacts and their forces keep them apart).
        bound_fraction: the share of its distance to the nearest non-neighbouring cloth primitive a
            vertex may move between two detections, in (0, 0.5): two primitives that both move that
            far towards each other still do not meet.
        capacity: initial contacts stored per vertex, triangle and edge, >= 1 (grown on demand).
        detection_interval: sweeps between detections within a substep, >= 0 (0: once per substep);
            each detection renews the move bounds from the current positions, so cloth pressed
            between the body and other cloth can follow a fast body.
        untangle_step: how far a vertex of a crossing moves per untangling iteration [m], in
            [0, ``radius``] (0: off). Before each substep every edge that crosses a triangle pushes
            the two apart along the gradient that shortens their intersection contour
            (:mod:`datagen.sim.untangle_kernels`).
        untangle_iterations: untangling iterations before each substep, 1-20 (each a refit of the
            cloth's triangle tree and an edge query).
    """

    enabled: bool = True
    radius: float = _limit(0.004, "m", above=0.0)
    stiffness: float = _limit(2.0e3, "N/m", above=0.0)
    friction: float = _limit(0.2, min=0.0)
    query: float = _limit(0.01, "m", above=0.0)
    bound_floor: float = _limit(0.006, "m", above=0.0)
    bound_fraction: float = _limit(0.45, above=0.0, below=0.5, why="at 0.5 or more two cloth primitives moving "
                                   "towards each other could meet between detections")
    capacity: int = _limit(16, min=1)
    detection_interval: int = _limit(5, min=0)
    untangle_step: float = _limit(0.002, "m", min=0.0)
    untangle_iterations: int = _limit(4, min=1, max=20)

    def __post_init__(self):
        check_limits(self)
        if self.query <= self.radius:
            raise InputError(f"SelfContactConfig.query ({self.query}) must exceed radius ({self.radius})")
        if self.untangle_step > self.radius:
            raise InputError(f"SelfContactConfig.untangle_step = {self.untangle_step} must be at most radius = "
                             f"{self.radius} m (0: off): a longer jump can carry cloth through other cloth")
        if self.bound_floor > 1.5 * self.radius + 1e-12:
            raise InputError(f"SelfContactConfig.bound_floor ({self.bound_floor}) must be at most 1.5 x radius "
                             f"({1.5 * self.radius:g}), the distance within which cloth pairs are contacts")


@dataclass(frozen=True, kw_only=True)
class LaunchConfig:
    """How the work is launched; none of these changes a result on the CPU (tested bitwise).

    Attributes:
        cuda_graph: on a CUDA device, capture a step's launches once as a CUDA graph and replay it
            (the same kernels in the same order, without Python's per-launch cost).
        register_caps: which kernels run as their register-capped copies
            (``detection_kernels.register_capped``: the same code under CUDA's ``__launch_bounds__``):
            ``none`` or ``detection`` (the two cloth-cloth queries and the projection's inside test).
        sweep_lanes: threads per vertex in the sweeps on a GPU (:mod:`datagen.sim.sweep_kernels`),
            a power of two from 1 to 32; a CPU thread walks each vertex alone whatever this says.
        coherent_order: launch the tree queries with one thread per vertex or edge in Morton order
            of the rest shape (``model.launch_order``) and sort every sweep colour the same way, so
            the threads of a warp hold cloth near each other; False: index order.
    """

    cuda_graph: bool = True
    register_caps: str = field(default="detection", metadata={"choices": tuple(REGISTER_CAPS)})
    sweep_lanes: int = field(default=4, metadata={"choices": (1, 2, 4, 8, 16, 32),
                                                  "why": "a power of two up to a warp's 32 threads"})
    coherent_order: bool = True

    def __post_init__(self):
        check_limits(self)


FLAT_NAMES = {
    "substeps": "steps.substeps", "max_substep": "steps.max_substep", "substep_edge": "steps.substep_edge", "substep_cap": "steps.substep_cap",
    "iterations": "steps.iterations", "global_iterations": "steps.global_iterations",
    "global_steps": "steps.global_steps", "warm_start": "steps.warm_start",
    "compression_hessian": "steps.compression_hessian",
    "chebyshev_rho": "steps.chebyshev_rho", "chebyshev_contacts": "steps.chebyshev_contacts",
    "chebyshev_body_contacts": "steps.chebyshev_body_contacts", "colour_hinge_wings": "steps.colour_hinge_wings",
    "body_stiffness": "body.stiffness", "body_margin": "body.margin", "body_query": "body.query",
    "body_friction": "body.friction", "friction_pressure": "body.friction_pressure",
    "global_friction": "body.global_friction",
    "body_projection": "projection.enabled", "projection_skip": "projection.skip",
    "projection_reach": "projection.reach", "projection_accuracy": "projection.accuracy",
    "self_collision": "self_contact.enabled", "self_radius": "self_contact.radius",
    "self_stiffness": "self_contact.stiffness", "self_friction": "self_contact.friction",
    "self_query": "self_contact.query", "self_bound_floor": "self_contact.bound_floor",
    "bound_fraction": "self_contact.bound_fraction", "contact_capacity": "self_contact.capacity",
    "detection_interval": "self_contact.detection_interval", "untangle_step": "self_contact.untangle_step",
    "untangle_iterations": "self_contact.untangle_iterations",
    "cuda_graph": "launch.cuda_graph", "register_caps": "launch.register_caps", "sweep_lanes": "launch.sweep_lanes",
    "coherent_order": "launch.coherent_order",
}
"""The flat names of :class:`SolverConfig`'s fields before the groups, and where each now is
(``group.field``): config files, ``--set KEY=VALUE`` and ``SolverConfig(self_radius=...)`` may still
use them, and ``config.self_radius`` still reads one; drape's own code uses the groups."""


def _nest_flat(kwargs: dict) -> dict:
    """``SolverConfig``'s keyword arguments with the flat names (:data:`FLAT_NAMES`) and dotted names
    (``self_contact.radius``, as ``--set`` gives them) folded into their groups (a group given as well
    gets them as changes)."""
    if not any(k in FLAT_NAMES or "." in k for k in kwargs):
        return kwargs
    out, changes = {}, {}
    for key, value in kwargs.items():
        if key in FLAT_NAMES or "." in key:
            group, name = FLAT_NAMES.get(key, key).split(".", 1)
            changes.setdefault(group, {})[name] = value
        else:
            out[key] = value
    fields = {f.name: f for f in dataclasses.fields(SolverConfig)}
    for group, values in changes.items():
        base = out.get(group)
        out[group] = (fields[group].default_factory(**values) if base is None
                      else dataclasses.replace(base, **values))
    return out


@dataclass(frozen=True, kw_only=True)
class SolverConfig:
    """Solver settings (SI units), in groups.

    Attributes:
        gravity: gravitational acceleration [m/s²], Y up.
        air_drag: linear air drag per area [kg/(m² s)], >= 0.
        friction_velocity: the slide velocity below which friction (with the body and with the cloth
            itself) is smoothed, static [m/s], > 0.
        steps: substeps, sweeps and the global step (:class:`StepConfig`).
        body: contact with the body (:class:`BodyContactConfig`).
        projection: the end-of-substep projection out of the body (:class:`ProjectionConfig`).
        self_contact: contact of the cloth with itself (:class:`SelfContactConfig`).
        launch: how the work is launched, results unchanged (:class:`LaunchConfig`).

    ``SolverConfig(self_radius=0.005)`` and ``config.self_radius`` still take and read the flat
    names of before the groups (:data:`FLAT_NAMES`).
    """

    gravity: tuple[float, float, float] = (0.0, -9.81, 0.0)
    air_drag: float = _limit(0.02, "kg/(m² s)", min=0.0)
    friction_velocity: float = _limit(1.0e-3, "m/s", above=0.0)
    steps: StepConfig = field(default_factory=StepConfig)
    body: BodyContactConfig = field(default_factory=BodyContactConfig)
    projection: ProjectionConfig = field(default_factory=ProjectionConfig)
    self_contact: SelfContactConfig = field(default_factory=SelfContactConfig)
    launch: LaunchConfig = field(default_factory=LaunchConfig)

    config_aliases = FLAT_NAMES
    """What :func:`datagen.config.load_config` reads a flat key as."""

    def __post_init__(self):
        check_limits(self)
        if len(self.gravity) != 3:
            raise InputError(f"SolverConfig.gravity must have three components [m/s²], got {self.gravity!r}")

    def __getattr__(self, name: str):
        """A flat name of before the groups (:data:`FLAT_NAMES`) reads its group's field."""
        path = FLAT_NAMES.get(name)
        if path is None:
            raise AttributeError(f"'SolverConfig' object has no attribute {name!r}")
        group, field_name = path.split(".")
        return getattr(object.__getattribute__(self, group), field_name)


def _taking_flat_names(init):
    @functools.wraps(init)
    def __init__(self, **kwargs):
        init(self, **_nest_flat(kwargs))
    return __init__


SolverConfig.__init__ = _taking_flat_names(SolverConfig.__init__)
