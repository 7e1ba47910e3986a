"""The garment types: one frozen :class:`GarmentType` record per type, everything a type is.

A record holds the type's name and frozen integer code, its style parameters (:class:`ParamSpec`
ranges), default material, expected openings, default edge length, an area guess for the
vertex-count estimate, and its silhouette as explicit fields: whether it hangs from the shoulders
or the waist, has sleeves, a skirt (a cone from the hips down), separate legs, an open front,
where its hem is measured from, which panels it is cut into, and what its openings are called.
The builder (:mod:`datagen.garment.types`) and the loop namer (:mod:`datagen.garment.mesh`) read
these fields, never a type's name or the names of its parameters.

The code is the type's identity in data: a store's ``garments/type`` holds it, and it salts the
seed of the type's style parameters, so a type's garments do not depend on where its record sits
here. Codes are frozen in :data:`schemas.garment_types.GARMENT_TYPE_CODES`; this module refuses at
import a record whose code is not the schema's for its name, or that another record has.

Adding a type = one record here (with the next unused code, also added to
``schemas/garment_types.py``) plus, if it has a piece no type has yet, that piece's geometry in
:func:`datagen.garment.types._design` and a field here saying which types have it. A type made of
existing pieces (another skirt length, a sleeveless jacket) is its record alone. No other type's
garments change: their parameters are salted by their own codes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

import schemas.garment_types as _schema
from datagen.errors import InputError
from datagen.materials import MATERIALS
from datagen.params import ParamSpec

__all__ = ["GARMENT_TYPES", "GarmentRegistryError", "GarmentType", "check_registry", "garment_type",
           "garment_type_names"]


class GarmentRegistryError(ValueError):
    """A garment type record that is malformed or whose code disagrees with the schema (a bug in
    drape's sources, found at import)."""


HangsFrom = Literal["shoulders", "waist"]
HemFrom = Literal["hips", "ankles"]
Panels = Literal["top", "skirt", "legs"]
SideOpening = Literal["cuff", "armhole", "hem", "none"]
TopOpening = Literal["neck", "waist"]

_PIECE_PARAMS = {
    "shoulders": ("ease_chest", "ease_waist", "ease_hip", "hem", "neck_drop", "neck_width", "neck_depth"),
    "waist": ("ease_waist", "ease_hip", "waist", "hem"),
    "sleeves": ("sleeve_length", "cuff_ease"),
    "armholes": ("armhole_drop",),
    "skirt": ("flare",),
    "separate_legs": ("leg_ease", "hem_ease"),
    "open_front": ("opening", "lapel_depth"),
    "back_slit": ("slit",),
}
"""The style parameters the geometry of each silhouette piece reads."""


EDGE_LENGTH_RANGE = (0.004, 0.1)
"""Target edge lengths a garment can be built at [m]: finer is too many vertices to simulate,
coarser cannot resolve necklines, cuffs and hems (at 0.5 m the checks fail; at 5 m there is no mesh)."""


@dataclass(frozen=True, kw_only=True)
class GarmentType:
    """One garment type.

    Attributes:
        name: the type's name (``drape garment list``, ``--type``, a config's ``name:seed``).
        code: its frozen integer code (:data:`schemas.garment_types.GARMENT_TYPE_CODES`): the
            store's ``garments/type`` and the salt of its style parameters' seed.
        params: style parameters, drawn uniformly from their ranges in this order by the seed.
        material: default material preset (:data:`datagen.materials.MATERIALS`).
        boundary_loops: openings a garment of this type has (a check).
        edge_length: default remeshing target [m], chosen for 2,000-8,000 vertices.
        area_guess: about the garment's area [m²], to estimate its vertex count before building.
        hangs_from: ``"shoulders"`` (a top: neckline, chest-waist-hip clearances, shoulder
            rest) or ``"waist"`` (a waist opening with an elastic waistband).
        sleeves: sleeves out to ``sleeve_length`` with a cuff; a top without them has armholes.
        skirt: a cone from the hips down widening by ``flare`` (skirts, dresses, coats).
        separate_legs: two leg tubes below the crotch (pants, shorts).
        open_front: the front open from the neckline down to the top button (jackets, coats).
        back_slit: a slit up the back from the hem, ``slit`` long (a straight skirt: without one
            a knee-length skirt cannot open round the thighs, and a wide stance stretched a cotton
            skirt by 11-14 % all round its hem, where a real one has a vent or rides up).
        hem_from: the ``hem`` parameter is measured down from the hip joints (``"hips"``) or up
            from the ankle joints (``"ankles"``).
        hem_floor_below_knee: the hem is kept no lower than this far below the knee joints [m]
            (None: no floor).
        sleeve_above_elbow: a short sleeve ends at least this far above the elbow joint [m]
            (None: no limit; long sleeves pass the elbow). Within about 8 cm of the joint the
            upper arm and forearm meet when the elbow bends, and a cuff there is caught in the
            fold: a T-shirt whose sleeve ended 2 cm above the elbow tore there when the arms came
            up into a boxing guard (elbows at 125 degrees).
        panels: ``"top"`` (front, back, left and right sleeve), ``"skirt"`` (front, back) or
            ``"legs"`` (left/right front/back).
        side_opening: what the openings left and right of the body's midline are called
            (``"cuff"``, ``"armhole"``, ``"hem"``, or ``"none"`` for a type without them).
        top_opening: what its highest midline opening is called (``"neck"`` or ``"waist"``).
    """

    name: str
    code: int
    params: Mapping[str, ParamSpec]
    material: str
    boundary_loops: int
    edge_length: float
    area_guess: float
    hangs_from: HangsFrom
    sleeves: bool
    skirt: bool
    separate_legs: bool
    open_front: bool
    hem_from: HemFrom
    hem_floor_below_knee: float | None
    panels: Panels
    side_opening: SideOpening
    top_opening: TopOpening
    sleeve_above_elbow: float | None = None
    back_slit: bool = False

    def __getstate__(self) -> dict:  # a read-only mapping does not pickle
        return {**self.__dict__, "params": dict(self.params)}

    def __setstate__(self, state: dict) -> None:
        for k, v in state.items():
            object.__setattr__(self, k, v)
        object.__setattr__(self, "params", MappingProxyType(dict(state["params"])))

    def __post_init__(self):
        object.__setattr__(self, "params", MappingProxyType(dict(self.params)))
        where = f"garment type {self.name!r}"
        choices = {"hangs_from": HangsFrom, "hem_from": HemFrom, "panels": Panels, "side_opening": SideOpening,
                   "top_opening": TopOpening}
        for field_name, kind in choices.items():
            if getattr(self, field_name) not in kind.__args__:
                raise GarmentRegistryError(f"{where}: {field_name} is {getattr(self, field_name)!r}; one of "
                                           f"{', '.join(kind.__args__)}")
        if not (isinstance(self.code, int) and self.code >= 0):
            raise GarmentRegistryError(f"{where}: code must be an integer >= 0, got {self.code!r}")
        if self.material not in MATERIALS:
            raise GarmentRegistryError(f"{where}: material {self.material!r} is not a preset ({', '.join(MATERIALS)})")
        if not (self.boundary_loops >= 1 and self.edge_length > 0 and self.area_guess > 0):
            raise GarmentRegistryError(f"{where}: boundary_loops, edge_length and area_guess must be positive")
        if any(not isinstance(s, ParamSpec) or not s.low <= s.high for s in self.params.values()):
            raise GarmentRegistryError(f"{where}: every style parameter is a ParamSpec with low <= high")
        top = self.hangs_from == "shoulders"
        # the pieces that go together, and the names that follow from them
        expected = {
            "top_opening": "neck" if top else "waist",
            "panels": "top" if top else ("legs" if self.separate_legs else "skirt"),
            "side_opening": ("cuff" if self.sleeves else "armhole") if top else ("hem" if self.separate_legs else "none"),
        }
        for field_name, value in expected.items():
            if getattr(self, field_name) != value:
                raise GarmentRegistryError(f"{where}: {field_name} is {getattr(self, field_name)!r} but its pieces "
                                           f"(hangs from the {self.hangs_from}, sleeves {self.sleeves}, separate legs "
                                           f"{self.separate_legs}) make it {value!r}")
        if not top and (self.sleeves or self.open_front):
            raise GarmentRegistryError(f"{where}: sleeves and an open front need a garment that hangs from the shoulders")
        if top and self.separate_legs:
            raise GarmentRegistryError(f"{where}: separate legs need a garment that hangs from the waist")
        if self.sleeve_above_elbow is not None and not (self.sleeves and self.sleeve_above_elbow >= 0):
            raise GarmentRegistryError(f"{where}: sleeve_above_elbow needs sleeves and a distance >= 0")
        if self.back_slit and not (self.skirt and not top):
            raise GarmentRegistryError(f"{where}: a back slit needs a skirt that hangs from the waist")
        if self.separate_legs and self.skirt:
            raise GarmentRegistryError(f"{where}: a skirt and separate legs do not go together")
        pieces = [self.hangs_from, "sleeves" if self.sleeves else ("armholes" if top else None),
                  "skirt" if self.skirt else None, "separate_legs" if self.separate_legs else None,
                  "open_front" if self.open_front else None, "back_slit" if self.back_slit else None]
        missing = [p for piece in pieces if piece for p in _PIECE_PARAMS[piece] if p not in self.params]
        if missing:
            raise GarmentRegistryError(f"{where}: its pieces need the style parameters {', '.join(missing)}")


_TOP = {
    "ease_chest": ParamSpec(0.015, 0.05, "clearance at the chest (m)"),
    "ease_waist": ParamSpec(0.015, 0.06, "clearance at the waist (m)"),
    "ease_hip": ParamSpec(0.015, 0.05, "clearance at the hips (m)"),
    "hem": ParamSpec(0.0, 0.12, "hem below the hip joints (m; kept 1.5 cm above the crotch)"),
    "neck_drop": ParamSpec(0.0, 0.03, "neckline lowered all round (m)"),
    "neck_width": ParamSpec(0.0, 0.03, "neck opening wider than the neck and its clearance (m)"),
    "neck_depth": ParamSpec(0.0, 0.09, "extra depth of the neckline at the front (m)"),
}
_SLEEVE = {
    "sleeve_length": ParamSpec(0.1, 0.25, "sleeve from the shoulder joint (m)"),
    "cuff_ease": ParamSpec(0.015, 0.045, "clearance at the cuff (m)"),
}
_SKIRT = {
    "flare": ParamSpec(0.0, 0.35, "widening of the skirt per metre below the hips"),
}
_LAPEL = ParamSpec(0.12, 0.22, "open front from the front neckline down to the top button (m); closed below it")

# the silhouettes, field by field; a record spreads one and sets the rest
_WAIST_EASE = {
    "ease_waist": ParamSpec(0.01, 0.03, "clearance at the waist (m)"),
    "ease_hip": ParamSpec(0.015, 0.04, "clearance at the hips (m)"),
}
_WAIST_DROP = {"waist": ParamSpec(0.0, 0.06, "waistband below the navel line (m)")}
"""The style parameters of every garment that hangs from the waist (skirts, pants, shorts); spread
where each type had them, so every type's parameters keep their draw order."""

_SLEEVED_TOP = {"hangs_from": "shoulders", "sleeves": True, "skirt": False, "separate_legs": False,
                "open_front": False, "hem_from": "hips", "hem_floor_below_knee": None, "panels": "top",
                "side_opening": "cuff", "top_opening": "neck"}
_SLEEVELESS_TOP = {**_SLEEVED_TOP, "sleeves": False, "side_opening": "armhole"}
_SKIRT_ONLY = {"hangs_from": "waist", "sleeves": False, "skirt": True, "separate_legs": False, "open_front": False,
               "hem_from": "hips", "hem_floor_below_knee": 0.12, "panels": "skirt", "side_opening": "none",
               "top_opening": "waist"}
_LEGS = {**_SKIRT_ONLY, "skirt": False, "separate_legs": True, "hem_floor_below_knee": None, "panels": "legs",
         "side_opening": "hem"}

_RECORDS = (
    GarmentType(name="tshirt", code=0, params={**_TOP, **_SLEEVE}, material="jersey", boundary_loops=4,
                edge_length=0.018, area_guess=1.1, **_SLEEVED_TOP, sleeve_above_elbow=0.09),
    GarmentType(name="long_sleeve_shirt", code=1,
                params={**_TOP, **_SLEEVE, "sleeve_length": ParamSpec(0.38, 0.47, "sleeve from the shoulder joint (m)")},
                material="cotton", boundary_loops=4, edge_length=0.02, area_guess=1.3, **_SLEEVED_TOP),
    GarmentType(name="tank_top", code=2,
                params={**_TOP, "armhole_drop": ParamSpec(0.02, 0.07, "armhole below the armpit line (m)")},
                material="jersey", boundary_loops=4, edge_length=0.016, area_guess=0.8, **_SLEEVELESS_TOP),
    GarmentType(name="jacket", code=3,
                params={**_TOP, **_SLEEVE,
                        "ease_chest": ParamSpec(0.035, 0.07, "clearance at the chest (m)"),
                        "ease_waist": ParamSpec(0.04, 0.08, "clearance at the waist (m)"),
                        "ease_hip": ParamSpec(0.035, 0.07, "clearance at the hips (m)"),
                        "sleeve_length": ParamSpec(0.4, 0.47, "sleeve from the shoulder joint (m)"),
                        "opening": ParamSpec(0.04, 0.12, "width of the open front (m)"),
                        "lapel_depth": _LAPEL},
                material="denim", boundary_loops=4, edge_length=0.02, area_guess=1.6,
                **{**_SLEEVED_TOP, "open_front": True}),
    GarmentType(name="coat", code=4,
                params={**_TOP, **_SLEEVE, **_SKIRT,
                        "ease_chest": ParamSpec(0.04, 0.07, "clearance at the chest (m)"),
                        "ease_waist": ParamSpec(0.045, 0.08, "clearance at the waist (m)"),
                        "ease_hip": ParamSpec(0.04, 0.07, "clearance at the hips (m)"),
                        "sleeve_length": ParamSpec(0.28, 0.36, "3/4 sleeve from the shoulder joint (m)"),
                        "hem": ParamSpec(0.35, 0.5, "hem below the hip joints (m), about the knee"),
                        "flare": ParamSpec(0.05, 0.2, "widening per metre below the hips"),
                        "opening": ParamSpec(0.04, 0.12, "width of the open front (m)"),
                        "lapel_depth": _LAPEL},
                material="wool", boundary_loops=4, edge_length=0.02, area_guess=2.4,
                **{**_SLEEVED_TOP, "open_front": True, "skirt": True}),
    GarmentType(name="dress", code=5,
                params={**_TOP, **_SKIRT,
                        "armhole_drop": ParamSpec(0.02, 0.06, "armhole below the armpit line (m)"),
                        "hem": ParamSpec(0.25, 0.5, "hem below the hip joints (m)")},
                material="silk", boundary_loops=4, edge_length=0.02, area_guess=1.8,
                **{**_SLEEVELESS_TOP, "skirt": True}),
    GarmentType(name="skirt", code=6,
                params={**_WAIST_EASE,
                        **_WAIST_DROP,
                        "hem": ParamSpec(0.2, 0.45, "hem below the hip joints (m)"),
                        "flare": ParamSpec(0.0, 0.06, "widening per metre below the hips (straight cut)"),
                        "slit": ParamSpec(0.2, 0.3, "back slit up from the hem (m; its top at most 10 cm below "
                                                    "the hip joints)")},
                material="cotton", boundary_loops=2, edge_length=0.013, area_guess=0.8, **_SKIRT_ONLY,
                back_slit=True),
    GarmentType(name="flared_skirt", code=7,
                params={**_WAIST_EASE,
                        **_WAIST_DROP,
                        "hem": ParamSpec(0.2, 0.4, "hem below the hip joints (m)"),
                        "flare": ParamSpec(0.3, 0.7, "widening per metre below the hips (A-line to circle)")},
                material="silk", boundary_loops=2, edge_length=0.015, area_guess=1.0, **_SKIRT_ONLY),
    GarmentType(name="pants", code=8,
                params={**_WAIST_EASE,
                        "leg_ease": ParamSpec(0.015, 0.04, "clearance around the thigh (m)"),
                        "hem_ease": ParamSpec(0.02, 0.06, "clearance at the hem (m)"),
                        **_WAIST_DROP,
                        "hem": ParamSpec(0.02, 0.1, "hem above the ankle joints (m)")},
                material="denim", boundary_loops=3, edge_length=0.02, area_guess=1.5,
                **{**_LEGS, "hem_from": "ankles"}),
    GarmentType(name="shorts", code=9,
                params={**_WAIST_EASE,
                        "leg_ease": ParamSpec(0.02, 0.05, "clearance around the thigh (m)"),
                        "hem_ease": ParamSpec(0.025, 0.06, "clearance at the hem (m)"),
                        **_WAIST_DROP,
                        "hem": ParamSpec(0.25, 0.36, "hem below the hip joints (m)")},
                material="cotton", boundary_loops=3, edge_length=0.015, area_guess=0.8, **_LEGS),
)

GARMENT_TYPES: dict[str, GarmentType] = {t.name: t for t in _RECORDS}
"""Every garment type by name. Its order is only the order of listings (``drape garment list``):
codes, not positions, identify a type in seeds and stores."""


def check_registry(types: Mapping[str, GarmentType] | None = None, codes: Mapping[str, int] | None = None) -> None:
    """Refuse (:class:`GarmentRegistryError`) records filed under another name, two records with one
    code, a record whose code is not the schema's for its name, or schema codes that are not
    0, 1, ... each once. Defaults: :data:`GARMENT_TYPES` and the schema's codes."""
    types = GARMENT_TYPES if types is None else types
    codes = _schema.GARMENT_TYPE_CODES if codes is None else codes
    where = "schemas/garment_types.py GARMENT_TYPE_CODES"
    by_code: dict[int, str] = {}
    for key, t in types.items():
        if key != t.name:
            raise GarmentRegistryError(f"garment type record {t.name!r} is registered under the name {key!r}")
        if t.code in by_code:
            raise GarmentRegistryError(f"garment types {by_code[t.code]!r} and {t.name!r} have the same code {t.code}; "
                                       "every type has its own code (a new type takes the next unused one)")
        by_code[t.code] = t.name
    if sorted(codes.values()) != list(range(len(codes))):
        raise GarmentRegistryError(f"the codes of {where} must be 0..{len(codes) - 1}, each once; they are "
                                   f"{sorted(codes.values())}")
    for t in types.values():
        if t.name not in codes:
            raise GarmentRegistryError(f"garment type {t.name!r} (code {t.code}) has no code in {where}; add "
                                       f"{t.name!r}: {len(codes)} there (codes are never renumbered or reused)")
        if codes[t.name] != t.code:
            raise GarmentRegistryError(f"garment type {t.name!r} has code {t.code} but {where} gives it "
                                       f"{codes[t.name]}; a type's code never changes (it is in stores and seeds)")


def garment_type(name: str) -> GarmentType:
    """The record of type ``name``; an unknown name is refused with the list of types."""
    try:
        return GARMENT_TYPES[name]
    except (KeyError, TypeError):
        raise InputError(f"unknown garment type {name!r}; types: {', '.join(GARMENT_TYPES)}") from None


def garment_type_names() -> list[str]:
    """Every type's name indexed by its code (``names[code] == name``): a store's
    ``garment_type_names`` for its ``garments/type`` codes. A code reserved by the schema whose
    type has no record (retired) keeps its schema name."""
    codes = _schema.GARMENT_TYPE_CODES
    names = [""] * len(codes)
    for name, code in codes.items():
        names[code] = name
    return names


check_registry()
