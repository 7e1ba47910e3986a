"""What crosses the simulator's boundary is values, not names: a scene carries its material as a
:class:`Material` (a custom one reaches the model as given), a failure is a typed code and a
message whose code the store knows."""

from __future__ import annotations

import dataclasses

import pytest

import datagen.sim.scene as sc
from datagen.errors import InputError
from datagen.generate.samples import failure_code
from datagen.materials import MATERIALS
from datagen.sim.metrics import FAILURE_CODES, Failure
from schemas.dataset import FAILURE_NAMES
from tests.sim.test_scene import falling_patch


def test_a_custom_material_named_like_a_preset_reaches_the_model_as_given(monkeypatch):
    """Before, the scene crossed with the material's name and the preset of that name was looked
    up again: a custom 'cotton' twice as dense simulated as the preset."""
    custom = dataclasses.replace(MATERIALS["cotton"], density=0.5, bending=3e-5)
    scene = dataclasses.replace(falling_patch(T=4), material=custom)
    seen = []
    original = sc.ClothModelBuilder.add_cloth

    def spy(self, *args, **kwargs):
        seen.append(kwargs["material_name"])
        return original(self, *args, **kwargs)

    monkeypatch.setattr(sc.ClothModelBuilder, "add_cloth", spy)
    sc.simulate([scene], sc.RunConfig(settle_rest=1, lead_in=0.0, settle_pose=0, ramp=0.0), device="cpu")
    assert seen == [custom] and seen[0] is custom


def test_a_scene_refuses_a_material_name():
    with pytest.raises(InputError, match="must be a Material"):
        dataclasses.replace(falling_patch(), material="cotton")


def test_failures_are_typed_and_every_code_has_a_store_code():
    assert set(FAILURE_CODES) <= set(FAILURE_NAMES) and FAILURE_NAMES[0] == "ok"
    for code in FAILURE_CODES:
        assert failure_code(Failure(code, "why")) == FAILURE_NAMES.index(code)
    assert failure_code(None) == 0
    assert str(Failure("slip", "3 cm")) == "slip: 3 cm"
    with pytest.raises(ValueError, match="not one of"):
        Failure("torn", "a code the store does not know")


def test_the_projection_accuracy_below_one_is_refused():
    """Below β = 1 warp's winding number breaks (benchmarks/winding_accuracy_probe.py of 62ea0bb: at 0.75 a
    fifth of the inside-or-out answers differ from β = 2's), so the solver refuses it in one line."""
    from datagen.sim.solver import SolverConfig

    assert SolverConfig().projection_accuracy == 1.25
    assert SolverConfig(projection_accuracy=1.0).projection_accuracy == 1.0
    with pytest.raises(InputError, match="ProjectionConfig.accuracy = 0.75 is out of range; allowed: 1 <= accuracy: "
                                         "below 1 warp's winding number"):
        SolverConfig(projection_accuracy=0.75)
