"""A pattern program's design space: its parameters, how they are drawn, checked and counted.

A program declares its parameters as an ordered tuple of :class:`Choice` (a discrete option) and
:class:`Range` (a continuous value with the smallest *visible* step) entries. A parameter may
apply only under other choices (``when={"sleeve": ("set_in",)}``: a cuff only on a sleeve).

- :meth:`DesignSpace.sample` draws every parameter from a numpy Generator in declaration order
  (uniform over a choice's options and a range), so a seed always gives the same design and
  overriding one parameter never shifts the draw of another.
- :meth:`DesignSpace.resolve` applies user overrides (unknown names and out-of-range values are an
  :class:`~datagen.errors.InputError` listing what is allowed) and drops the parameters that do not
  apply to the resulting choices.
- :meth:`DesignSpace.count` is the number of visibly distinct designs: the sum, over every
  combination of the choices, of the product of the bins of the ranges that apply under it, a
  range of width ``high - low`` with visible step ``step`` having ``floor(width / step) + 1`` bins
  (values a step apart look different; a step is e.g. 5 cm of a length or 10 % of a girth).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from datagen.errors import InputError

__all__ = ["Choice", "DesignSpace", "Range"]


def _when(value) -> dict[str, tuple]:
    return {str(k): tuple(v) for k, v in dict(value or {}).items()}


@dataclass(frozen=True, kw_only=True)
class Choice:
    """A discrete design parameter: one of ``options`` (strings or booleans), drawn uniformly."""

    name: str
    options: tuple
    doc: str
    when: Mapping[str, tuple] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "options", tuple(self.options))
        object.__setattr__(self, "when", _when(self.when))
        if len(self.options) < 1 or len(set(self.options)) != len(self.options):
            raise ValueError(f"choice {self.name!r}: options must be distinct and at least one")

    def draw(self, rng: np.random.Generator):
        return self.options[int(rng.integers(len(self.options)))]

    def check(self, value, owner: str):
        for o in self.options:  # also "true"/"false" for booleans and "4" for 4 (as the command line gives)
            if isinstance(o, bool) or isinstance(value, bool):
                if value is o or (isinstance(value, str) and value.lower() == str(o).lower()):
                    return o
            elif value == o or (isinstance(o, int) and isinstance(value, str) and value.strip() == str(o)):
                return o
        raise InputError(f"design parameter {self.name!r} of {owner} is {value!r}; one of "
                         f"{', '.join(map(str, self.options))} ({self.doc})")

    def bins(self) -> int:
        return len(self.options)


@dataclass(frozen=True, kw_only=True)
class Range:
    """A continuous design parameter in [low, high], drawn uniformly; ``step`` is the smallest
    difference that shows (the counting bin), in the parameter's own unit ``unit``."""

    name: str
    low: float
    high: float
    step: float
    unit: str
    doc: str
    when: Mapping[str, tuple] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "when", _when(self.when))
        if not (self.low <= self.high and self.step > 0):
            raise ValueError(f"range {self.name!r}: needs low <= high and a positive step")

    def draw(self, rng: np.random.Generator) -> float:
        return float(rng.uniform(self.low, self.high))

    def check(self, value, owner: str) -> float:
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise InputError(f"design parameter {self.name!r} of {owner} must be a number, got {value!r}") from None
        if not (math.isfinite(v) and self.low - 1e-12 <= v <= self.high + 1e-12):
            raise InputError(f"design parameter {self.name!r} of {owner} is {v:g}; allowed range is "
                             f"[{self.low:g}, {self.high:g}] {self.unit} ({self.doc})")
        return v

    def bins(self) -> int:
        return int(math.floor((self.high - self.low) / self.step + 1e-9)) + 1


Param = Choice | Range


@dataclass(frozen=True)
class DesignSpace:
    """An ordered tuple of design parameters (see the module's docstring)."""

    params: tuple[Param, ...]

    def __post_init__(self):
        names = [p.name for p in self.params]
        if len(set(names)) != len(names):
            raise ValueError(f"design space has repeated parameters: {names}")
        by = {p.name: p for p in self.params}
        for p in self.params:
            for k, opts in p.when.items():
                if k not in by or not isinstance(by[k], Choice) or names.index(k) > names.index(p.name):
                    raise ValueError(f"parameter {p.name!r} depends on {k!r}, which is not an earlier choice")
                if any(o not in by[k].options for o in opts):
                    raise ValueError(f"parameter {p.name!r} depends on {k!r} being one of {opts}, not all options")

    def __add__(self, other: DesignSpace) -> DesignSpace:
        return DesignSpace(self.params + other.params)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)

    @staticmethod
    def _applies(p: Param, values: Mapping[str, object]) -> bool:
        return all(values.get(k) in opts for k, opts in p.when.items())

    def sample(self, rng: np.random.Generator) -> dict[str, object]:
        """Every parameter drawn in order (also those that will not apply, so the stream is fixed)."""
        return {p.name: p.draw(rng) for p in self.params}

    def resolve(self, drawn: Mapping[str, object], overrides: Mapping[str, object], owner: str) -> dict[str, object]:
        """``drawn`` with ``overrides`` applied and checked, keeping only the parameters that apply."""
        values = dict(drawn)
        for name, value in overrides.items():
            if name not in self.names:
                raise InputError(f"{owner} has no design parameter {name!r}; its parameters: {', '.join(self.names)}")
            values[name] = self.param(name).check(value, owner)
        out = {}
        for p in self.params:
            if self._applies(p, out):
                out[p.name] = values[p.name]
            elif p.name in overrides:
                need = ", ".join(f"{k} in ({', '.join(map(str, v))})" for k, v in p.when.items())
                raise InputError(f"design parameter {p.name!r} of {owner} applies only when {need}; the design "
                                 f"has {', '.join(f'{k}={out.get(k)!r}' for k in p.when)}")
        return out

    def count(self) -> int:
        """Visibly distinct designs (see the module's docstring)."""
        choices = [p for p in self.params if isinstance(p, Choice)]
        total = 0
        for combo in itertools.product(*(c.options for c in choices)):
            values = dict(zip((c.name for c in choices), combo))
            # a choice that does not apply contributes one design, not one per option
            live = {}
            for p in self.params:
                if isinstance(p, Choice) and self._applies(p, live):
                    live[p.name] = values[p.name]
            if any(c.name not in live and values[c.name] != c.options[0] for c in choices):
                continue
            n = 1
            for p in self.params:
                if isinstance(p, Range) and self._applies(p, live):
                    n *= p.bins()
            total += n
        return total
