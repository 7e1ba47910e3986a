"""Seeded style parameters shared by the procedural generators (motions, garments).

A generator declares its parameters as :class:`ParamSpec` ranges; :func:`draw_params` draws each
uniformly from its range with a generator seeded by ``(seed, *key)`` and applies user overrides,
checking names and ranges. :func:`parse_param_args` reads the CLI's ``--param NAME=VALUE``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from datagen.errors import InputError

__all__ = ["ParamSpec", "draw_params", "parse_param_args"]


@dataclass(frozen=True)
class ParamSpec:
    """A style parameter: its range [low, high] (drawn uniformly by the seed) and meaning."""

    low: float
    high: float
    doc: str


def draw_params(specs: dict[str, ParamSpec], seed: int, key: tuple[int, ...], owner: str,
                overrides: dict | None = None) -> dict[str, float]:
    """Draw every parameter of ``specs`` from ``default_rng([seed, *key])``, then apply ``overrides``.

    ``owner`` names what the parameters belong to in error messages (e.g. ``"'walk'"``).
    """
    rng = np.random.default_rng([int(seed), *key])
    params = {name: float(rng.uniform(s.low, s.high)) for name, s in specs.items()}
    for name, value in (overrides or {}).items():
        if name not in specs:
            raise InputError(f"{owner} has no style parameter {name!r}; its parameters: {', '.join(specs)}")
        s = specs[name]
        value = float(value)
        if not (s.low <= value <= s.high):
            raise InputError(f"style parameter {name!r} of {owner} is {value:g}; allowed range is "
                             f"[{s.low:g}, {s.high:g}] ({s.doc})")
        params[name] = value
    return params


def parse_param_args(items: list[str]) -> dict[str, float]:
    """``["tempo=1.1", ...]`` from ``--param`` flags as ``{"tempo": 1.1, ...}``."""
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InputError(f"--param {item!r}: write it as NAME=VALUE, e.g. --param tempo=1.1")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise InputError(f"--param {item!r}: {value!r} is not a number") from None
    return out
