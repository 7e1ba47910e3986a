"""The solver's settings (``datagen.sim.settings``): groups, limits from field metadata, and the flat
names of before the groups, in Python and in config files."""

from __future__ import annotations

import dataclasses

import pytest

from datagen.config import load_config, parse_assignments
from datagen.errors import ConfigError, InputError
from datagen.sim.settings import (FLAT_NAMES, BodyContactConfig, LaunchConfig, ProjectionConfig, SelfContactConfig,
                                  SolverConfig, StepConfig, check_limits)

GROUPS = (StepConfig, BodyContactConfig, ProjectionConfig, SelfContactConfig, LaunchConfig, SolverConfig)


def test_every_limited_field_is_refused_outside_its_range_with_its_name_value_and_range():
    """For every field with limits in its metadata, a value just outside them is refused by the one
    validator with an InputError that names the group and field, the value and the allowed range."""
    tried = 0
    for cls in GROUPS:
        for f in dataclasses.fields(cls):
            meta = f.metadata
            bad = ([0.5 * meta["min"] - 1.0] if "min" in meta else []) + \
                  ([meta["above"]] if "above" in meta else []) + \
                  ([meta["max"] + 1] if "max" in meta else []) + ([meta["below"]] if "below" in meta else [])
            if "choices" in meta:
                bad = [3] if f.type in (int, "int") else ["no-such-choice"]
            for value in bad:
                if f.type in (int, "int"):
                    value = int(value)
                with pytest.raises(InputError) as exc:
                    cls(**{f.name: value})
                msg = str(exc.value)
                assert f"{cls.__name__}.{f.name} = {value!r}" in msg, msg
                assert "allowed" in msg or "choose one of" in msg, msg
                tried += 1
    assert tried >= 25
    with pytest.raises(InputError,
                       match=r"SelfContactConfig.radius = -0.001 is out of range; allowed: 0 < radius \[m\]"):
        SelfContactConfig(radius=-0.001)
    with pytest.raises(InputError,
                       match=r"StepConfig.chebyshev_rho = 1.0 is out of range; allowed: 0 <= chebyshev_rho < 1"):
        StepConfig(chebyshev_rho=1.0)


def test_limits_that_relate_two_fields_of_a_group():
    with pytest.raises(InputError, match="query .* must exceed radius"):
        SelfContactConfig(radius=0.004, query=0.004)
    with pytest.raises(InputError, match="untangle_step = 0.005 must be at most radius"):
        SelfContactConfig(untangle_step=0.005)
    with pytest.raises(InputError, match="bound_floor .* must be at most 1.5 x radius"):
        SelfContactConfig(bound_floor=0.0061)
    SelfContactConfig(bound_floor=0.006)  # 1.5 x the default radius: allowed


def test_check_limits_passes_fields_without_limits_and_refuses_a_non_number():
    @dataclasses.dataclass(frozen=True)
    class Example:
        name: str = "x"
        k: float = dataclasses.field(default=1.0, metadata={"above": 0.0})

    check_limits(Example())
    with pytest.raises(InputError, match=r"Example.k = nan must be a finite number"):
        check_limits(Example(k=float("nan")))


def test_flat_names_build_and_read_the_groups():
    """``SolverConfig(self_radius=...)`` and ``config.self_radius`` (the names of before the groups)
    go through the groups; every flat name has a place, and a replace by a flat name keeps the rest."""
    for flat, path in FLAT_NAMES.items():
        group, name = path.split(".")
        assert any(f.name == name for f in dataclasses.fields(type(getattr(SolverConfig(), group)))), flat
    c = SolverConfig(self_collision=False, substeps=7, cuda_graph=False, sweep_lanes=8, air_drag=0.0)
    assert c == SolverConfig(self_contact=SelfContactConfig(enabled=False), steps=StepConfig(substeps=7),
                             launch=LaunchConfig(cuda_graph=False, sweep_lanes=8), air_drag=0.0)
    assert (c.self_collision, c.substeps, c.iterations, c.sweep_lanes) == (False, 7, 20, 8)
    r = dataclasses.replace(c, cuda_graph=True)
    assert r.launch == LaunchConfig(cuda_graph=True, sweep_lanes=8) and r.steps.substeps == 7
    assert SolverConfig(steps=StepConfig(substeps=3), iterations=5).steps == StepConfig(substeps=3, iterations=5)
    assert SolverConfig(**{"self_contact.radius": 0.005}).self_contact.radius == 0.005
    with pytest.raises(AttributeError, match="no_such_setting"):
        _ = SolverConfig().no_such_setting
    with pytest.raises(InputError, match="SelfContactConfig.radius"):
        SolverConfig(self_radius=0.0)


def test_config_files_take_groups_flat_names_and_dotted_keys_and_refuse_one_setting_twice():
    nested = load_config(SolverConfig, {"steps": {"iterations": 10}, "self_contact": {"radius": 0.005}})
    flat = load_config(SolverConfig, {"iterations": 10, "self_radius": 0.005})
    dotted = load_config(SolverConfig, parse_assignments(["steps.iterations=10", "self_contact.radius=0.005"]))
    assert nested == flat == dotted == SolverConfig(steps=StepConfig(iterations=10),
                                                    self_contact=SelfContactConfig(radius=0.005))
    mixed = load_config(SolverConfig, {"self_contact": {"query": 0.02}, "self_radius": 0.005, "sweep_lanes": 8})
    assert mixed.self_contact == SelfContactConfig(radius=0.005, query=0.02) and mixed.launch.sweep_lanes == 8
    with pytest.raises(ConfigError, match="self_radius and self_contact.radius are the same setting; give it once"):
        load_config(SolverConfig, {"self_contact": {"radius": 0.004}, "self_radius": 0.003})
    with pytest.raises(ConfigError, match=r"steps.iterations = 0 is out of range"):
        load_config(SolverConfig, {"iterations": 0})
    with pytest.raises(ConfigError, match=r"self_contact: SelfContactConfig.bound_fraction = 0.5 is out of range"):
        load_config(SolverConfig, {"bound_fraction": 0.5})
    with pytest.raises(ConfigError, match=r"unknown key\(s\) self_contact.nope"):
        load_config(SolverConfig, {"self_contact.nope": 1})
    with pytest.raises(ConfigError, match=r"launch.sweep_lanes = 3 is not allowed"):
        load_config(SolverConfig, {"sweep_lanes": 3})
