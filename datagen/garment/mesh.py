"""The :class:`GarmentMesh` type: a garment's rest mesh, labels, UVs, material and metadata."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from datagen.errors import InputError
from datagen.garment.materials import Material

__all__ = ["GarmentMesh", "boundary_loops", "load_garment"]


def boundary_loops(faces: np.ndarray) -> list[np.ndarray]:
    """Ordered vertex loops [n] of the open boundaries of a manifold triangle mesh."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    boundary = edges[counts[inverse.ravel()] == 1]  # directed, as they appear in their one face
    nxt = {int(a): int(b) for a, b in boundary}
    loops, seen = [], set()
    for start in nxt:
        if start in seen:
            continue
        loop, v = [], start
        while v not in seen:
            seen.add(v)
            loop.append(v)
            v = nxt.get(v, start)
            if v == start:
                break
        loops.append(np.asarray(loop, dtype=np.int64))
    return loops


@dataclass(frozen=True, eq=False)
class GarmentMesh:
    """A garment ready to be draped.

    Attributes:
        vertices: rest shape [V, 3] in metres, placed on the body in its rest pose (the rest shape
            is the constructed shape in the body's frame; the simulator starts from it).
        faces: triangles [F, 3] (int64), outward-facing (away from the body).
        uv: material coordinates [V, 2] in metres: u along the weft (around the body or limb),
            v along the warp (down the body, along the limb).
        vertex_region: panel index per vertex [V] into ``region_names``.
        face_region: panel index per face [F] (the majority of its corners).
        region_names: panel names.
        seam_vertex: [V] bool, vertices on a seam between two panels.
        loops: named open boundaries: name -> vertex ids in order.
        material: the cloth material.
        metadata: type, style parameters, seed, body β, counts, rest area, edge length, ...
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    vertex_region: np.ndarray
    face_region: np.ndarray
    region_names: tuple[str, ...]
    seam_vertex: np.ndarray
    loops: dict[str, np.ndarray]
    material: Material
    metadata: dict = field(default_factory=dict)

    @classmethod
    def create(cls, vertices, faces, *, uv, vertex_region, region_names, material, metadata) -> GarmentMesh:
        """Derive face regions, seams, named loops and counts, and build the garment."""
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64)
        vr = np.asarray(vertex_region, dtype=np.int32)
        corner = vr[f]
        fr = np.where(corner[:, 1] == corner[:, 2], corner[:, 1], corner[:, 0]).astype(np.int32)
        seam = np.zeros(len(v), dtype=bool)
        for a, b in ((0, 1), (1, 2), (2, 0)):
            diff = corner[:, a] != corner[:, b]
            seam[f[diff, a]] = True
            seam[f[diff, b]] = True
        loops = _name_loops(v, boundary_loops(f))
        area = float(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum())
        meta = {**metadata, "vertex_count": len(v), "face_count": len(f), "rest_area_m2": area,
                "boundary_loops": len(loops), "material": material.as_dict()}
        return cls(vertices=v, faces=f, uv=np.asarray(uv, dtype=np.float64), vertex_region=vr, face_region=fr,
                   region_names=tuple(region_names), seam_vertex=seam, loops=loops, material=material, metadata=meta)

    @property
    def vertex_count(self) -> int:
        return len(self.vertices)

    def save(self, path: str | Path) -> Path:
        """Write ``.obj``/``.ply`` (geometry, via trimesh) or ``.npz`` (everything, no pickles)."""
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix in (".obj", ".ply"):
            import trimesh

            trimesh.Trimesh(self.vertices, self.faces, process=False).export(path)
        elif suffix == ".npz":
            loops = {f"loop_{k}": v for k, v in self.loops.items()}
            with open(path, "wb") as fh:
                np.savez(fh, vertices=self.vertices, faces=self.faces, uv=self.uv, vertex_region=self.vertex_region,
                         face_region=self.face_region, seam_vertex=self.seam_vertex,
                         region_names=np.array(json.dumps(list(self.region_names))),
                         material=np.array(json.dumps(self.material.as_dict())),
                         metadata=np.array(json.dumps(self.metadata)), **loops)
        else:
            raise InputError(f"{path}: garment files are .obj, .ply or .npz (labels and metadata only in .npz)")
        return path


def load_garment(path: str | Path) -> GarmentMesh:
    """Read a garment written by :meth:`GarmentMesh.save` as ``.npz``."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"garment file {path} does not exist")
    with np.load(path, allow_pickle=False) as d:
        loops = {k[5:]: d[k] for k in d.files if k.startswith("loop_")}
        return GarmentMesh(vertices=d["vertices"], faces=d["faces"], uv=d["uv"], vertex_region=d["vertex_region"],
                           face_region=d["face_region"], region_names=tuple(json.loads(str(d["region_names"]))),
                           seam_vertex=d["seam_vertex"], loops=loops,
                           material=Material(**json.loads(str(d["material"]))),
                           metadata=json.loads(str(d["metadata"])))


def _name_loops(v: np.ndarray, loops: list[np.ndarray]) -> dict[str, np.ndarray]:
    """Name open boundaries by where they are: the highest is the neck or waist, the lowest the hem,
    the outermost on each side a cuff (or leg hem), the rest by index."""
    if not loops:
        return {}
    centres = np.array([v[lp].mean(0) for lp in loops])
    names: dict[str, np.ndarray] = {}
    order = sorted(range(len(loops)), key=lambda i: -abs(centres[i, 0]))
    out = {}
    for i in order:
        c = centres[i]
        if abs(c[0]) > 0.12:
            name = "left_opening" if c[0] > 0 else "right_opening"
        elif c[1] == centres[:, 1].max():
            name = "top_opening"
        elif c[1] == centres[:, 1].min():
            name = "hem"
        else:
            name = "opening"
        base, k = name, 1
        while name in out:
            k += 1
            name = f"{base}_{k}"
        out[name] = loops[i]
    names.update(out)
    return names
