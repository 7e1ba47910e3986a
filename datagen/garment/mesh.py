"""The :class:`GarmentMesh` type: a garment's rest mesh, labels, UVs, material and metadata
(:class:`~datagen.garment.metadata.GarmentMetadata`)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from datagen.errors import InputError
from datagen.garment.metadata import GarmentMetadata
from datagen.garment.registry import GARMENT_TYPES, GarmentType
from datagen.geometry.topology import unique_edges
from datagen.materials import Material

__all__ = ["GarmentMesh", "GarmentMetadata", "boundary_loops", "load_garment"]


def boundary_loops(faces: np.ndarray) -> list[np.ndarray]:
    """Ordered vertex loops [n] of the open boundaries of a manifold triangle mesh."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    _, inverse, counts = unique_edges(faces, return_inverse=True, return_counts=True)
    boundary = edges[counts[inverse] == 1]  # directed, as they appear in their one face
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
            v along the warp (up the body, along the limb); each vertex in its own panel's chart
            (see ``face_uv`` for what a simulator should use).
        vertex_region: panel index per vertex [V] into ``region_names``.
        face_region: panel index per face [F] (the majority of its corners).
        region_names: panel names.
        seam_vertex: [V] bool, vertices on a seam between two panels.
        loops: named open boundaries: name -> vertex ids in order.
        material: the cloth material.
        metadata: a :class:`~datagen.garment.metadata.GarmentMetadata`: type, style parameters,
            seed, body β, counts, rest area, edge length, waistband, ... (a mapping given here is
            read by :meth:`GarmentMetadata.from_dict`, which refuses unknown keys).
        face_uv: material coordinates of every face corner [F, 3, 2] (m), all three in the chart
            of the face's panel, so every face has a valid (u, v) frame, also on seams and where
            a sleeve's chart wraps at its underarm seam; :meth:`material_frames` gives the
            directions. The rest metric is the 3D rest shape; the UVs give directions and
            approximate lengths (u is an angle times the panel's mean radius).

    A garment of the **pattern** kind (:mod:`datagen.garment.pattern`, ``kind == "pattern"``) is
    made of flat panels that are not welded: its rest state is flat cloth, ``vertices`` are the
    start positions around the body, and these are set as well (None for the shell kind):

        rest_uv: each vertex's 2D coordinate in its panel [V, 2] [m] (the flat rest state);
            ``vertex_region`` is its panel (``panel_id``), ``region_names`` the panel names;
            ``uv`` is ``rest_uv`` turned into the panel's (weft, warp) grain frame.
        stitch_pairs: vertex pairs to be sewn together [P, 2] (int64).
        face_grain: the warp direction of every face in its panel's 2D frame [F, 2] (unit).
        pattern: the sewing pattern it came from, as GarmentCode specification JSON text
            (:func:`datagen.garment.pattern.spec.read_spec` reads it back).
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
    metadata: GarmentMetadata = field(default_factory=GarmentMetadata)
    face_uv: np.ndarray | None = None
    rest_uv: np.ndarray | None = None
    stitch_pairs: np.ndarray | None = None
    face_grain: np.ndarray | None = None
    pattern: str | None = None

    def __post_init__(self):
        if not isinstance(self.metadata, GarmentMetadata):
            object.__setattr__(self, "metadata", GarmentMetadata.from_dict(self.metadata))

    @classmethod
    def create(cls, vertices, faces, *, uv, vertex_region, region_names, material, metadata, face_uv=None,
               extra_seam=None, loops=None, rest_uv=None, stitch_pairs=None, face_grain=None,
               pattern=None) -> GarmentMesh:
        """Derive face regions, seams, named loops and counts, and build the garment.

        ``metadata`` is a :class:`GarmentMetadata` (or its dict form) without the counts, which
        are filled in here; its ``type``'s record names the openings. ``face_uv`` [F, 3, 2]
        defaults to the vertices' UVs; ``extra_seam`` [V] marks seams that are not panel borders
        (a sleeve's underarm seam). ``loops`` (name -> vertex ids) replaces the openings found
        from the mesh's boundary (a pattern's panels are not welded: their openings come from the
        free edges); ``rest_uv``, ``stitch_pairs``, ``face_grain`` and ``pattern`` make a garment
        of the pattern kind (class docstring)."""
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
        if extra_seam is not None:
            seam |= np.asarray(extra_seam, dtype=bool)
        if not isinstance(metadata, GarmentMetadata):
            metadata = GarmentMetadata.from_dict(metadata)
        if loops is None:
            loops = _name_loops(v, boundary_loops(f), GARMENT_TYPES.get(metadata.type or ""))
        else:
            loops = {str(k): np.asarray(x, dtype=np.int64) for k, x in loops.items()}
        area = float(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum())
        meta = replace(metadata, vertex_count=len(v), face_count=len(f), rest_area_m2=area, boundary_loops=len(loops),
                       material=material)
        return cls(vertices=v, faces=f, uv=np.asarray(uv, dtype=np.float64), vertex_region=vr, face_region=fr,
                   region_names=tuple(region_names), seam_vertex=seam, loops=loops, material=material, metadata=meta,
                   face_uv=np.asarray(uv, dtype=np.float64)[f] if face_uv is None else np.asarray(face_uv, dtype=np.float64),
                   rest_uv=None if rest_uv is None else np.asarray(rest_uv, dtype=np.float64),
                   stitch_pairs=None if stitch_pairs is None else np.asarray(stitch_pairs, dtype=np.int64).reshape(-1, 2),
                   face_grain=None if face_grain is None else np.asarray(face_grain, dtype=np.float64),
                   pattern=pattern)

    @property
    def vertex_count(self) -> int:
        return len(self.vertices)

    @property
    def kind(self) -> str:
        """``"pattern"`` for flat panels to be sewn (``rest_uv`` set), ``"shell"`` for a built shell."""
        return "shell" if self.rest_uv is None else "pattern"

    @property
    def panel_id(self) -> np.ndarray:
        """Panel index of every vertex [V] (``vertex_region``)."""
        return self.vertex_region

    def material_frames(self) -> np.ndarray:
        """Unit weft and warp directions of every face [F, 2, 3] (rest shape).

        ``[:, 0]`` is the weft: along the face's line of constant v (horizontal on the trunk and
        legs, around the arm on sleeves), pointing to increasing u; where v barely changes over a
        face (the top of a shoulder) it is the direction in which u grows fastest. ``[:, 1]`` is
        the warp, the in-plane perpendicular normal × weft (up the body, along the limb).
        """
        tri = self.vertices[self.faces]
        fuv = self.uv[self.faces] if self.face_uv is None else self.face_uv
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area2 = np.linalg.norm(n, axis=1, keepdims=True) + 1e-30
        n /= area2
        grad = np.zeros((len(tri), 2, 3))
        for k in range(3):  # gradient of a linear function on a triangle: sum f_k (n x e_k) / (2 area)
            e = np.cross(n, tri[:, (k + 2) % 3] - tri[:, (k + 1) % 3]) / area2
            grad += fuv[:, k, :, None] * e[:, None, :]
        gu, gv = grad[:, 0], grad[:, 1]
        along = np.cross(gv, n)  # the line of constant v
        along *= np.sign(np.einsum("ij,ij->i", along, gu))[:, None]
        steep = np.linalg.norm(gv, axis=1) > 0.3  # v changes enough over the face to define its level line
        weft = np.where(steep[:, None], along, gu)
        weft /= np.linalg.norm(weft, axis=1, keepdims=True) + 1e-30
        return np.stack([weft, np.cross(n, weft)], axis=1)

    def weft_rest_scale(self) -> np.ndarray:
        """Rest length along the weft relative to the built mesh, per face [F]: below 1 on the
        elastic waistband of a garment that hangs from the waist (``metadata.waistband``), 1
        elsewhere; the simulator shortens those faces' rest shape around the body."""
        scale = np.ones(len(self.faces))
        band = self.metadata.waistband
        if band is not None:
            centroid_y = self.vertices[self.faces][:, :, 1].mean(1)
            scale[centroid_y >= band.top - band.width] = band.weft_scale
        return scale

    def _pattern_arrays(self) -> dict[str, np.ndarray]:
        if self.rest_uv is None:
            return {}
        return {"rest_uv": self.rest_uv,
                "stitch_pairs": np.zeros((0, 2), np.int64) if self.stitch_pairs is None else self.stitch_pairs,
                "face_grain": np.zeros((0, 2)) if self.face_grain is None else self.face_grain,
                "pattern": np.array(self.pattern or "")}

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
                np.savez(fh, vertices=self.vertices, faces=self.faces, uv=self.uv,
                         face_uv=self.uv[self.faces] if self.face_uv is None else self.face_uv,
                         vertex_region=self.vertex_region,
                         face_region=self.face_region, seam_vertex=self.seam_vertex,
                         region_names=np.array(json.dumps(list(self.region_names))),
                         material=np.array(json.dumps(self.material.as_dict())),
                         metadata=np.array(json.dumps(self.metadata.to_dict())), **loops,
                         **self._pattern_arrays())
        else:
            raise InputError(f"{path}: garment files are .obj, .ply or .npz (labels and metadata only in .npz)")
        return path


def load_garment(path: str | Path) -> GarmentMesh:
    """Read a garment written by :meth:`GarmentMesh.save` as ``.npz`` (one without metadata reads
    with empty metadata; metadata with keys :class:`GarmentMetadata` does not know is refused)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"garment file {path} does not exist")
    with np.load(path, allow_pickle=False) as d:
        loops = {k[5:]: d[k] for k in d.files if k.startswith("loop_")}
        try:
            meta = GarmentMetadata.from_dict(json.loads(str(d["metadata"]))) if "metadata" in d.files else GarmentMetadata()
        except (InputError, ValueError) as e:
            raise InputError(f"{path}: {e}") from None
        return GarmentMesh(vertices=d["vertices"], faces=d["faces"], uv=d["uv"], vertex_region=d["vertex_region"],
                           face_region=d["face_region"], region_names=tuple(json.loads(str(d["region_names"]))),
                           seam_vertex=d["seam_vertex"], loops=loops,
                           material=Material(**json.loads(str(d["material"]))),
                           metadata=meta,
                           face_uv=d["face_uv"] if "face_uv" in d.files else None,
                           rest_uv=d["rest_uv"] if "rest_uv" in d.files else None,
                           stitch_pairs=d["stitch_pairs"] if "stitch_pairs" in d.files else None,
                           face_grain=d["face_grain"] if "face_grain" in d.files else None,
                           pattern=(str(d["pattern"]) or None) if "pattern" in d.files else None)


def _name_loops(v: np.ndarray, loops: list[np.ndarray], garment_type: GarmentType | None = None
                ) -> dict[str, np.ndarray]:
    """Name open boundaries by where they are and what the garment's type record says.

    Openings off the midline (centre more than 6 cm from it) are ``left_``/``right_`` plus the
    type's ``side_opening`` (``cuff`` of sleeved tops, ``armhole`` of sleeveless ones, ``hem`` of
    separate legs). Of the openings on the midline the highest is the type's ``top_opening``
    (``neck`` or ``waist``) and the lowest ``hem`` (the ``neck`` of a type with an open front runs
    down the front to the top button); a type with separate legs has one midline opening, its top
    one; an open-front type with one midline opening (the front open down to the hem, garment
    builder 7 and older) has ``neck_front_hem``. Garments of other origins (files, no record) get
    ``top_opening``, ``hem``, ``left_opening``, ``right_opening`` and ``opening`` by position.
    """
    if not loops:
        return {}
    t = garment_type
    centres = np.array([v[lp].mean(0) for lp in loops])
    side_word = None if t is None or t.side_opening == "none" else t.side_opening
    side_limit = 0.06 if side_word else 0.12
    top_word = "top_opening" if t is None else t.top_opening
    out: dict[str, np.ndarray] = {}
    mid = [i for i in range(len(loops)) if abs(centres[i, 0]) <= side_limit]
    for i in sorted(range(len(loops)), key=lambda i: -abs(centres[i, 0])):
        c = centres[i]
        if abs(c[0]) > side_limit:
            name = ("left_" if c[0] > 0 else "right_") + (side_word or "opening")
        elif t is not None and t.open_front and len(mid) == 1:
            name = "neck_front_hem"
        elif c[1] == centres[mid, 1].max() and (len(mid) > 1 or (t is not None and t.separate_legs)):
            name = top_word
        elif c[1] == centres[mid, 1].min():
            name = "hem"
        else:
            name = "opening"
        base, k = name, 1
        while name in out:
            k += 1
            name = f"{base}_{k}"
        out[name] = loops[i]
    return out
