"""Probes: what a solver tells an observer at defined points of a step, for benchmarks and diagnosis.

A solver holds a tuple of probes (``solver.probes``, empty in production: then it calls nothing and
reads nothing back). At each point below it calls the method of that name on every probe, with the
solver itself and the point's device arrays; a probe reads what it wants back to the host (which
syncs the device), so a solver with probes launches a step directly, never from a captured CUDA graph.
A probe must not write to what it is given: a probed run is bitwise the unprobed one.

:class:`SolverProbe` lists the points; :class:`SweepTrace` and :class:`CgTrace` record the sweeps'
and the global step's convergence.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class SolverProbe(Protocol):
    """The points at which a solver calls its probes (a probe defines those it wants; the base
    :class:`Probe` has every one do nothing).

    Arrays are the solver's device arrays (warp): positions ``x`` [particle_count, 3] in m.
    """

    def before_sweep(self, solver, substep: int, sweep: int, x) -> None:
        """Before sweep ``sweep`` (0-based) of substep ``substep`` (and its detection, if it has one)."""

    def after_sweep(self, solver, substep: int, sweep: int, x, last: bool) -> None:
        """After the sweep's colours and its Chebyshev extrapolation; ``last``: the substep's last sweep."""

    def global_residual(self, solver, iteration: int, rz, last: bool) -> None:
        """The global step's per-scene rᵀP⁻¹r [scene_count] float64 before its conjugate-gradient
        iteration ``iteration`` (0: before the first) and after the last (``last``: no iteration follows);
        with ``StepConfig.warm_start`` a Newton step's first call is ``iteration`` -1, the cold start
        d = 0 (fᵀP⁻¹f), and 0 is then the warm start's."""


class Probe:
    """A :class:`SolverProbe` whose every point does nothing: subclass it and define the points you want."""

    def before_sweep(self, solver, substep: int, sweep: int, x) -> None:
        pass

    def after_sweep(self, solver, substep: int, sweep: int, x, last: bool) -> None:
        pass

    def global_residual(self, solver, iteration: int, rz, last: bool) -> None:
        pass


class SweepTrace(Probe):
    """The sweeps' convergence: ``entries`` gets one tuple a sweep, (substep, sweep, every vertex's
    move in that sweep [particle_count] in m, and on a substep's last sweep which vertices touch the
    body and which have cloth-cloth contacts [particle_count] bool, else None, None)."""

    def __init__(self):
        self.entries: list[tuple] = []
        self._before = None

    def before_sweep(self, solver, substep: int, sweep: int, x) -> None:
        self._before = x.numpy().copy()

    def after_sweep(self, solver, substep: int, sweep: int, x, last: bool) -> None:
        self.entries.append((substep, sweep, np.linalg.norm(x.numpy() - self._before, axis=1),
                             (solver.body_has.numpy() > 0).any(1) if last else None,
                             solver.vt_count.numpy() > 0 if last else None))


class CgTrace(Probe):
    """The global step's convergence: ``entries`` gets one array a Newton step of the global step,
    its per-scene rᵀP⁻¹r before the first conjugate-gradient iteration and after each one,
    [global_iterations + 1, scene_count] float64 (with a warm start, its cold start first:
    [global_iterations + 2, scene_count])."""

    def __init__(self):
        self.entries: list[np.ndarray] = []
        self._rows: list[np.ndarray] = []
        self._cold = False

    def global_residual(self, solver, iteration: int, rz, last: bool) -> None:
        if iteration == -1 or iteration == 0 and not self._cold:  # a Newton step starts
            self._rows = []
        self._cold = iteration == -1
        self._rows.append(rz.numpy().copy())
        if last:
            self.entries.append(np.stack(self._rows))
