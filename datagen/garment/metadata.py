"""What a garment records about itself: :class:`GarmentMetadata`, a frozen typed record.

A procedural garment (:func:`~datagen.garment.types.make_garment`) fills every field of the build;
a garment read from a mesh file (:func:`~datagen.garment.files.load_garment_file`) has type
``"file"`` and its :class:`FileOrigin` instead; :meth:`GarmentMesh.create
<datagen.garment.mesh.GarmentMesh.create>` adds the counts, area and material to either. Fields a
garment of some origin cannot have are ``None``. :meth:`GarmentMetadata.to_dict` and
:meth:`GarmentMetadata.from_dict` are the JSON form stored in a garment ``.npz`` (the same keys
as the plain dict of garment builder 8 and older, so those files still read); ``from_dict``
refuses keys it does not know.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from types import MappingProxyType
from typing import Any

from datagen.errors import InputError
from datagen.materials import Material

__all__ = ["FileOrigin", "GarmentMetadata", "Waistband"]


def _refuse_unknown(cls, d: Mapping, what: str) -> None:
    if not isinstance(d, Mapping):
        raise InputError(f"{what} must be a JSON object, got {type(d).__name__}")
    known = [f.name for f in fields(cls)]
    unknown = sorted(set(d) - set(known))
    if unknown:
        raise InputError(f"{what} has unknown key(s) {', '.join(map(repr, unknown))}; its keys are {', '.join(known)}")


def _opt(value, kind, key: str, what: str):
    if value is None:
        return None
    try:
        if kind is bool:
            if not isinstance(value, bool):
                raise TypeError
            return value
        if kind is int and (isinstance(value, bool) or float(value) != int(value)):
            raise ValueError
        return kind(value)
    except (TypeError, ValueError):
        raise InputError(f"{what}: {key} must be {kind.__name__}, got {value!r}") from None


@dataclass(frozen=True, kw_only=True)
class Waistband:
    """The elastic band of a garment that hangs from the waist.

    Attributes:
        top: height of the waist opening [m]; the band is the faces within ``width`` below it.
        width: height of the band [m].
        weft_scale: the band's rest length around the body as a share of the built one.
        girth_body: the body's girth under the band [m] (convex hull of its cross-section).
        girth_garment: the built garment's girth there [m].
    """

    top: float
    width: float
    weft_scale: float
    girth_body: float
    girth_garment: float

    def to_dict(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_dict(cls, d: Mapping) -> Waistband:
        what = "garment metadata 'waistband'"
        _refuse_unknown(cls, d, what)
        missing = [f.name for f in fields(cls) if f.name not in d]
        if missing:
            raise InputError(f"{what} lacks {', '.join(missing)}")
        return cls(**{k: _opt(v, float, k, what) for k, v in d.items()})


@dataclass(frozen=True, kw_only=True)
class FileOrigin:
    """Where a garment read from a mesh file came from and how it was read.

    Attributes:
        source: the file's path.
        units: the file's length unit (``m``, ``cm``, ``mm``) and whether it was guessed.
        up_axis: the file's up axis (``y``, ``z``) and whether it was guessed.
        remesh_edge_length: the isotropic remeshing target [m], or None if not remeshed.
    """

    source: str
    units: str
    units_guessed: bool
    up_axis: str
    up_axis_guessed: bool
    remesh_edge_length: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_dict(cls, d: Mapping) -> FileOrigin:
        what = "garment metadata 'origin'"
        _refuse_unknown(cls, d, what)
        missing = [f.name for f in fields(cls) if f.name not in d and f.name != "remesh_edge_length"]
        if missing:
            raise InputError(f"{what} lacks {', '.join(missing)}")
        return cls(source=str(d["source"]), units=str(d["units"]), up_axis=str(d["up_axis"]),
                   units_guessed=_opt(d["units_guessed"], bool, "units_guessed", what),
                   up_axis_guessed=_opt(d["up_axis_guessed"], bool, "up_axis_guessed", what),
                   remesh_edge_length=_opt(d.get("remesh_edge_length"), float, "remesh_edge_length", what))


_FILE_KEYS = ("source", "units", "units_guessed", "up_axis", "up_axis_guessed", "remesh_edge_length")
"""Keys of a file garment's origin, which the plain-dict metadata (before the record) kept at the
top level."""


@dataclass(frozen=True, kw_only=True)
class GarmentMetadata:
    """A garment's metadata; every field is optional (None) but for what its origin always has.

    Attributes:
        type: garment type name (``"file"`` for a garment read from a mesh file; None: unknown).
        params: style parameters (empty for a garment from a file), read-only.
        seed: the seed that drew them.
        betas: shape β of the body the garment was built on.
        target_edge_length: remeshing target [m].
        expected_boundary_loops: openings its type has (a check).
        builder_version: version of the garment builder that made it.
        build_seconds: wall time of the build [s].
        waistband: its elastic waistband, or None (tops, file garments).
        origin: where a garment from a mesh file came from, or None.
        vertex_count, face_count: mesh size.
        rest_area_m2: area of the rest shape [m²].
        boundary_loops: open boundaries the mesh has.
        material: the cloth material it was made with.
    """

    type: str | None = None
    params: Mapping[str, float] = field(default_factory=dict)
    seed: int | None = None
    betas: tuple[float, ...] | None = None
    target_edge_length: float | None = None
    expected_boundary_loops: int | None = None
    builder_version: int | None = None
    build_seconds: float | None = None
    waistband: Waistband | None = None
    origin: FileOrigin | None = None
    vertex_count: int | None = None
    face_count: int | None = None
    rest_area_m2: float | None = None
    boundary_loops: int | None = None
    material: Material | None = None

    def __post_init__(self):
        object.__setattr__(self, "params", MappingProxyType({str(k): float(v) for k, v in self.params.items()}))
        if self.betas is not None:
            object.__setattr__(self, "betas", tuple(float(b) for b in self.betas))

    # a read-only mapping does not pickle: hand pickle a plain dict and make it read-only again
    def __getstate__(self) -> dict:
        return {**self.__dict__, "params": dict(self.params)}

    def __setstate__(self, state: dict) -> None:
        for k, v in state.items():
            object.__setattr__(self, k, v)
        object.__setattr__(self, "params", MappingProxyType(dict(state["params"])))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form; fields that are None (and empty ``params``) are left out."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None or (f.name == "params" and not value):
                continue
            if f.name == "params":
                value = dict(value)
            elif f.name == "betas":
                value = list(value)
            elif f.name == "material":
                value = value.as_dict()
            elif isinstance(value, (Waistband, FileOrigin)):
                value = value.to_dict()
            out[f.name] = value
        return out

    @classmethod
    def from_dict(cls, d: Mapping | None) -> GarmentMetadata:
        """The record of :meth:`to_dict`'s form (or the plain dict of older garment files, whose
        file-origin keys sit at the top level); unknown keys are refused."""
        what = "garment metadata"
        if d is None:
            return cls()
        if not isinstance(d, Mapping):
            raise InputError(f"{what} must be a JSON object, got {type(d).__name__}")
        d = dict(d)
        legacy = {k: d.pop(k) for k in _FILE_KEYS if k in d}
        if legacy:
            if "origin" in d:
                raise InputError(f"{what} has both 'origin' and its keys {', '.join(legacy)} at the top level")
            d["origin"] = legacy
        _refuse_unknown(cls, d, what)
        params = d.get("params") or {}
        if not isinstance(params, Mapping):
            raise InputError(f"{what}: params must be an object of name: value, got {params!r}")
        betas = d.get("betas")
        if betas is not None and not isinstance(betas, (list, tuple)):
            raise InputError(f"{what}: betas must be a list of numbers, got {betas!r}")
        mat = d.get("material")
        if mat is not None:
            try:
                mat = Material(**mat)
            except TypeError as e:
                raise InputError(f"{what}: material {mat!r} is not a material ({e})") from None
        try:
            params = {str(k): float(v) for k, v in params.items()}
            betas = None if betas is None else tuple(float(b) for b in betas)
        except (TypeError, ValueError):
            raise InputError(f"{what}: params and betas must hold numbers") from None
        return cls(type=_opt(d.get("type"), str, "type", what), params=params, seed=_opt(d.get("seed"), int, "seed", what),
                   betas=betas,
                   target_edge_length=_opt(d.get("target_edge_length"), float, "target_edge_length", what),
                   expected_boundary_loops=_opt(d.get("expected_boundary_loops"), int, "expected_boundary_loops", what),
                   builder_version=_opt(d.get("builder_version"), int, "builder_version", what),
                   build_seconds=_opt(d.get("build_seconds"), float, "build_seconds", what),
                   waistband=None if d.get("waistband") is None else Waistband.from_dict(d["waistband"]),
                   origin=None if d.get("origin") is None else FileOrigin.from_dict(d["origin"]),
                   vertex_count=_opt(d.get("vertex_count"), int, "vertex_count", what),
                   face_count=_opt(d.get("face_count"), int, "face_count", what),
                   rest_area_m2=_opt(d.get("rest_area_m2"), float, "rest_area_m2", what),
                   boundary_loops=_opt(d.get("boundary_loops"), int, "boundary_loops", what),
                   material=mat)
