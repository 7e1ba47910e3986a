"""What a cloth solver offers the scene driver and the metrics (:class:`ClothSolver`), and the solvers
known by name (:data:`SOLVERS`), one of which :class:`~datagen.sim.scene.RunConfig` selects.

A new solver is a class that satisfies :class:`ClothSolver` (built from a finalised
:class:`~datagen.sim.model.ClothModel` and a :class:`~datagen.sim.settings.SolverConfig`) plus one
entry in :data:`SOLVERS`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from datagen.errors import InputError
from datagen.sim.settings import SolverConfig
from datagen.sim.solver import SolverVBD


@runtime_checkable
class ClothSolver(Protocol):
    """A solver of a batch of scenes (one model): advances the cloth against the moving bodies.

    Besides the methods, the metrics (:meth:`~datagen.sim.metrics.Metrics.measure`) read the
    collider the last step ended on: ``body_ids`` (one warp mesh id per scene, [scene_count]
    uint64), ``body_sub`` (its vertices [m], [body_vertex_count, 3]) and the launch orders
    ``vertex_order`` [particle_count] and ``edge_order`` [edge_count] (int32; any permutation).
    """

    model: object
    config: SolverConfig
    probes: tuple
    body_ids: object
    body_sub: object
    vertex_order: object
    edge_order: object

    def step(self, state_in, state_out, control, dt: float) -> None:
        """Advance every scene by ``dt`` [s], the body moving from the last control to ``control``;
        ``state_in`` is read and ``state_out`` written (they may be the same)."""

    def reset_body(self, control) -> None:
        """Take ``control`` as the body's pose at the start of the next step (no motion in between)."""

    def place_body(self, control) -> None:
        """Put the body at ``control`` now: the next step's start and the collider the metrics read."""

    def freeze(self, state, scene: int) -> None:
        """Stop simulating scene ``scene`` (held where ``state`` has it); the other scenes are unchanged."""


SOLVERS: dict[str, type] = {"vbd": SolverVBD}
"""The solvers by the name :attr:`~datagen.sim.scene.RunConfig.solver_name` gives: each a class built
as ``cls(model, config, probes=...)`` that satisfies :class:`ClothSolver`."""


def solver_class(name: str) -> type:
    """The solver class called ``name``, or an :class:`InputError` that lists the known names."""
    try:
        return SOLVERS[name]
    except KeyError:
        raise InputError(f"unknown solver {name!r}; known solvers: {', '.join(sorted(SOLVERS))}") from None


def make_solver(name: str, model, config: SolverConfig, *, probes: tuple = ()) -> ClothSolver:
    """The solver ``name`` of :data:`SOLVERS` built on ``model`` with ``config`` and ``probes``
    (:mod:`datagen.sim.probes`)."""
    return solver_class(name)(model, config, probes=probes)
