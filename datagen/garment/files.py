"""Garments from files (OBJ, PLY, glTF/GLB, anything trimesh reads): validated, scaled, oriented."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from datagen.errors import InputError
from datagen.materials import Material, material
from datagen.garment.mesh import GarmentMesh
from datagen.garment.metadata import FileOrigin, GarmentMetadata

__all__ = ["UNIT_SCALES", "load_garment_file"]

log = logging.getLogger(__name__)

UNIT_SCALES = {"m": 1.0, "cm": 0.01, "mm": 0.001}


def _guess_units(extent: float) -> str:
    """A garment is 0.2-2 m across: pick the unit that puts ``extent`` there."""
    for unit in ("m", "cm", "mm"):
        if 0.1 <= extent * UNIT_SCALES[unit] <= 3.0:
            return unit
    raise InputError(f"cannot tell the units of a mesh {extent:g} units across (not a garment in m, cm or mm); "
                     "pass units='m'|'cm'|'mm'")


def load_garment_file(path: str | Path, *, units: str | None = None, up_axis: str | None = None,
                      remesh_edge_length: float | None = None, material_name: str | Material = "cotton") -> GarmentMesh:
    """Read a garment mesh and make it ready to simulate.

    Units are guessed from the size unless given ('m', 'cm', 'mm'); the up axis ('y' or 'z') is
    guessed as the longer of Y and Z (garments are taller than deep); both guesses are logged and
    stored in the metadata (``metadata.origin``, a :class:`~datagen.garment.metadata.FileOrigin`). Non-manifold edges, several components, degenerate faces or an empty
    mesh are refused with what to do. ``remesh_edge_length`` (m) remeshes isotropically.
    """
    import trimesh

    from datagen.garment import levelset
    from datagen.garment.checks import topology

    path = Path(path)
    if not path.is_file():
        raise InputError(f"garment file {path} does not exist")
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise InputError(f"{path}: trimesh cannot read it as a mesh ({exc})") from exc
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError(f"{path} holds no triangles; export the garment as a triangle or polygon mesh")
    mesh.merge_vertices()
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.faces, dtype=np.int64)
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    degenerate = int((area <= 1e-14 * max(area.max(), 1e-30)).sum())
    if degenerate:
        raise InputError(f"{path}: {degenerate} zero-area faces; clean the mesh (merge vertices, remove degenerate "
                         "faces) or pass remesh_edge_length")
    extent = np.ptp(v, axis=0)
    unit = units or _guess_units(float(extent.max()))
    if unit not in UNIT_SCALES:
        raise InputError(f"units must be one of {', '.join(UNIT_SCALES)}, got {unit!r}")
    up = up_axis or ("z" if extent[2] > 1.2 * extent[1] else "y")
    if up not in ("y", "z"):
        raise InputError(f"up_axis must be 'y' or 'z', got {up!r}")
    v = v * UNIT_SCALES[unit]
    if up == "z":
        v = v[:, [0, 2, 1]] * np.array([1.0, 1.0, -1.0])
    log.info("%s: units %s (%s), up axis %s (%s)", path, unit, "given" if units else "guessed from its size",
             up, "given" if up_axis else "guessed")
    topo = topology(v, f)
    if topo["non_manifold_edges"]:
        raise InputError(f"{path}: {topo['non_manifold_edges']} non-manifold edges (shared by more than two faces); "
                         "repair the mesh (e.g. pymeshlab meshing_repair_non_manifold_edges) before simulating")
    if topo["components"] != 1:
        raise InputError(f"{path}: {topo['components']} separate pieces; a garment must be one connected surface "
                         "(sew the panels, or load each piece on its own)")
    if remesh_edge_length:
        v, f = levelset.remesh(v, f, float(remesh_edge_length))
    meta = GarmentMetadata(type="file", origin=FileOrigin(
        source=str(path), units=unit, units_guessed=units is None, up_axis=up, up_axis_guessed=up_axis is None,
        remesh_edge_length=None if remesh_edge_length is None else float(remesh_edge_length)))
    return GarmentMesh.create(v, f, uv=v[:, :2].copy(), vertex_region=np.zeros(len(v), dtype=np.int32),
                              region_names=("panel0",), material=material(material_name), metadata=meta)
