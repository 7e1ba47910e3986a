"""Frozen integer codes of the garment types.

A store's ``garments/type`` holds these codes and its root attribute ``garment_type_names`` the
names indexed by code (``names[code] == name``); a garment's style parameters are drawn with its
type's code in the seed (``datagen.garment.registry``). So a code, once given, never changes and
is never given to another type: a new type takes the next unused code, a retired type keeps its
code reserved. ``datagen.garment.registry`` refuses, at import, a type whose code is not the one
here.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

__all__ = ["GARMENT_TYPE_CODES"]

GARMENT_TYPE_CODES: Mapping[str, int] = MappingProxyType({
    "tshirt": 0,
    "long_sleeve_shirt": 1,
    "tank_top": 2,
    "jacket": 3,
    "coat": 4,
    "dress": 5,
    "skirt": 6,
    "flared_skirt": 7,
    "pants": 8,
    "shorts": 9,
})
"""Garment type name -> its code in ``garments/type`` (read-only)."""
