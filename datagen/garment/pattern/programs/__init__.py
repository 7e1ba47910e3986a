"""Pattern programs: sewing patterns from seeded design parameters, fitted to a body's measurements.

A :class:`PatternProgram` has a design space (:class:`~.space.DesignSpace`: discrete choices and
continuous ranges, some applying only under others), draws a design from a numpy Generator, and
builds a validated :class:`~datagen.garment.pattern.model.Pattern` from a design and a
:class:`~datagen.body.measurements.BodyMeasurements`. Lengths and girths are read from the
measurements and ease is added to girths, so one design fits every body.

:func:`make_pattern` is the entry point: ``make_pattern("skirt_circle", 3, measurements,
fullness=1.0)``. :func:`count_designs` counts the visibly distinct designs of every program from
their declared spaces (docs/patterns.md, "Design space").

Modules: :mod:`.space` (parameters, draws, counting), :mod:`.fit` (girth profiles, placement
frame), :mod:`.outline` (named edges, mirrored halves, panels, stitches), :mod:`.bands`
(waistbands, cuffs, stand collars), :mod:`.skirts`, :mod:`.trousers`, :mod:`.bodice` (bodices and
set-in sleeves), :mod:`.collars` (collars and hoods), :mod:`.garments` (tops, dresses, jackets).
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from datagen.body.measurements import BodyMeasurements
from datagen.errors import InputError
from datagen.garment.pattern.model import Pattern
from datagen.garment.pattern.programs.garments import (DRESS_SPACE, JACKET_SPACE, SKIRT_PROGRAM_SPACES, TOP_SPACE,
                                                       build_dress, build_jacket, build_skirt, build_top)
from datagen.garment.pattern.programs.space import Choice, DesignSpace, Range
from datagen.garment.pattern.programs.trousers import SHORTS_SPACE, TROUSERS_SPACE, build_trousers

__all__ = ["PROGRAMS", "Choice", "DesignSpace", "PatternProgram", "Range", "count_designs", "count_families",
           "design_of", "make_pattern"]

SEED_SALT = 60
"""Salts every program's draw (with the program's name), so programs never share a stream."""


@dataclass(frozen=True)
class PatternProgram:
    """A garment's design space and how it is built.

    Attributes:
        name: the program's name (``make_pattern``'s first argument).
        family: ``"skirt"``, ``"trousers"``, ``"top"``, ``"dress"`` or ``"jacket"``.
        sample: draws a design from a Generator (every parameter, in the space's order).
        build: (design, measurements) -> Pattern.
        space: the declared design space (draws, overrides, counting).
        doc: one line on what the program makes.
    """

    name: str
    family: str
    sample: Callable[[np.random.Generator], Mapping[str, object]]
    build: Callable[[Mapping[str, object], BodyMeasurements], Pattern]
    space: DesignSpace
    doc: str = ""


def _program(name: str, family: str, space: DesignSpace, build, doc: str) -> PatternProgram:
    return PatternProgram(name=name, family=family, sample=space.sample, build=build, space=space, doc=doc)


def _trousers(name: str):
    def build(design, m):
        return build_trousers(design, m, name)
    return build


PROGRAMS: Mapping[str, PatternProgram] = MappingProxyType({p.name: p for p in (
    _program("skirt_straight", "skirt", SKIRT_PROGRAM_SPACES["straight"], build_skirt("straight"),
             "straight or pencil skirt with a back vent, darts or none"),
    _program("skirt_a_line", "skirt", SKIRT_PROGRAM_SPACES["a_line"], build_skirt("a_line"), "A-line skirt"),
    _program("skirt_circle", "skirt", SKIRT_PROGRAM_SPACES["circle"], build_skirt("circle"),
             "half-circle to full-circle skirt in 2 or 4 panels"),
    _program("skirt_gored", "skirt", SKIRT_PROGRAM_SPACES["gored"], build_skirt("gored"),
             "4-12 gores, with or without godets"),
    _program("trousers", "trousers", TROUSERS_SPACE, _trousers("trousers"), "long trousers, narrow to wide legs"),
    _program("shorts", "trousers", SHORTS_SPACE, _trousers("shorts"), "shorts and culottes"),
    _program("top", "top", TOP_SPACE, build_top,
             "T-shirt, blouse, tank top, hoodie, crop top or tunic: necklines, sleeves, cuffs, darts, collar, hood"),
    _program("dress", "dress", DRESS_SPACE, build_dress, "a bodice and an A-line or circle skirt"),
    _program("jacket", "jacket", JACKET_SPACE, build_jacket, "open-front jacket with or without a collar or hood"),
)})
"""Every pattern program by name."""


def _program_named(name: str) -> PatternProgram:
    try:
        return PROGRAMS[name]
    except (KeyError, TypeError):
        raise InputError(f"unknown pattern program {name!r}; programs: {', '.join(PROGRAMS)}") from None


def design_of(name: str, seed: int, **overrides) -> dict[str, object]:
    """The design program ``name`` draws with ``seed`` (deterministic), with ``overrides`` applied."""
    prog = _program_named(name)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"a pattern's seed must be an integer 0 or more, got {seed!r}")
    rng = np.random.default_rng([int(seed), zlib.crc32(name.encode()), SEED_SALT])
    return prog.space.resolve(prog.sample(rng), overrides, f"pattern program {name!r}")


def make_pattern(name: str, seed: int, measurements: BodyMeasurements, **overrides) -> Pattern:
    """The pattern of program ``name`` with the design drawn by ``seed`` (``overrides`` fix design
    parameters by name), fitted to ``measurements``.

    Raises :class:`InputError` for an unknown program or parameter, or a value out of its range
    (the message lists what is allowed)."""
    if not isinstance(measurements, BodyMeasurements):
        raise InputError(f"make_pattern needs BodyMeasurements (datagen.body.measurements.measure_body), "
                         f"got {type(measurements).__name__}")
    design = design_of(name, seed, **overrides)
    return _program_named(name).build(design, measurements)


def count_designs(coarse: bool = False, ranges=None) -> dict[str, int]:
    """Visibly distinct designs per program, from the declared spaces (:meth:`DesignSpace.count`).
    ``coarse``: count the discrete choices only (every continuous range one bin); ``ranges``: count
    the bins of these ranges only (names), the others one bin each."""
    keep = set() if coarse else (None if ranges is None else set(ranges))
    out = {}
    for name, prog in PROGRAMS.items():
        space = prog.space
        if keep is not None:
            space = DesignSpace(tuple(
                Range(name=p.name, low=p.low, high=p.low, step=1.0, unit=p.unit, doc=p.doc, when=p.when)
                if isinstance(p, Range) and p.name not in keep else p for p in space.params))
        out[name] = space.count()
    return out


def count_families(coarse: bool = False, ranges=None) -> dict[str, int]:
    """:func:`count_designs` summed per family (programs of one family make different designs)."""
    out: dict[str, int] = {}
    for name, n in count_designs(coarse, ranges).items():
        fam = PROGRAMS[name].family
        out[fam] = out.get(fam, 0) + n
    return out
