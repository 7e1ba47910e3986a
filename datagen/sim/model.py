"""The cloth model: what does not change during a run, for one scene or a batch of scenes.

``ClothModelBuilder.add_cloth(...)`` adds one garment (a triangle mesh with its material) to a
scene with its own body; ``finalize(device)`` concatenates every scene into flat warp arrays:
rest geometry, per-triangle material frames and stiffnesses, hinge edges, vertex adjacency and a
graph colouring for the vertex block descent solver. Scenes share no vertex, edge or contact;
each scene's vertices, faces and edges are contiguous, each scene has its own collision
structures and its own colouring (merged by colour index), so a scene's result does not depend
on what else is in its batch.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from datagen.errors import InputError
from datagen.materials import Material, material


@dataclass
class _ClothPart:
    vertices: np.ndarray
    faces: np.ndarray
    material: Material
    scene: int
    frames: np.ndarray | None
    pinned: np.ndarray | None
    weft_scale: np.ndarray | None = None


@dataclass
class ClothModel:
    """Flat arrays of every scene's cloth (numpy copies in ``host``, warp arrays as attributes).

    Attributes (warp arrays on ``device``):
        rest_positions: rest shape [m], shape [particle_count, 3].
        mass: vertex mass [kg] (a third of each adjacent triangle's area x areal density).
        vertex_area: vertex area [m²] (for air drag).
        active: 1 for simulated vertices, 0 for pinned ones.
        particle_scene: scene index per vertex.
        faces: triangles [face_count, 3] (global vertex ids).
        dm_inv: inverse rest shape matrix of every triangle in its material frame [1/m] (the
            built shape, its weft row scaled by the face's ``weft_scale``).
        tri_area: rest area [m²] (the built area times ``weft_scale``; mass is the built area's).
        tri_stiff: (k_u, k_v, k_uv, k_s) [N/m] per triangle.
        tri_lock: (1 + lock strain [-], lock stiffness [N/m]) per triangle (the material's lock).
        edges: [edge_count, 4]: hinge (0, 1) and opposite corners (2, 3; -1 on a boundary).
        rest_angle: rest dihedral angle [rad]; bend_k: 3 k_b |ē|²/(Ā₁+Ā₂) [N·m].
        colours: vertex ids per colour (no two vertices of one colour share a triangle or hinge).
    """

    device: str
    particle_count: int
    face_count: int
    edge_count: int
    scene_count: int
    body_vertex_count: int = 0
    host: dict = field(default_factory=dict)
    colours: list = field(default_factory=list)


class ClothModelBuilder:
    """Collects garments (one or more per scene) and builds a :class:`ClothModel`."""

    def __init__(self) -> None:
        self._parts: list[_ClothPart] = []
        self._bodies: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def add_body(self, vertices, faces, *, scene: int = 0, face_part=None) -> None:
        """The collider of ``scene``: a closed triangle mesh with outward normals; ``vertices`` is
        its start pose [m] (each frame's pose comes in a :class:`~datagen.sim.state.BodyControl`).

        ``face_part`` numbers the body part of every face [F] (0..7; default: one part), e.g.
        :func:`datagen.body.skeleton.face_parts`. A cloth vertex gets a contact plane from its
        closest point on the whole body and one from every other part near it, so cloth caught
        where a posed body overlaps itself (between arm and torso, hand and thigh) is held by both
        parts instead of being pushed by one into the other."""
        v, f = _checked_mesh(vertices, faces, "body")
        if scene in self._bodies:
            raise InputError(f"scene {scene} already has a body")
        part = np.zeros(len(f), dtype=np.int32) if face_part is None else np.asarray(face_part).reshape(-1)
        if part.shape != (len(f),) or not np.issubdtype(part.dtype, np.integer) or part.min() < 0 or part.max() >= 8:
            raise InputError(f"face_part must hold one part number in 0..7 per body face ({len(f)}), got shape "
                             f"{part.shape} and dtype {part.dtype}")
        self._bodies[int(scene)] = (v, f, part.astype(np.int32))

    def add_cloth(self, vertices, faces, *, material_name: Material | str = "cotton", scene: int = 0,
                  material_frames: np.ndarray | None = None, pinned: np.ndarray | None = None,
                  weft_scale: np.ndarray | None = None) -> int:
        """Add a cloth mesh to ``scene``; returns the id its first vertex will have in the model
        when cloths are added in scene order (``finalize`` groups them by scene).

        Args:
            vertices: rest (and start) positions [m], shape [V, 3].
            faces: triangles [F, 3].
            material_name: a preset name or a :class:`Material`.
            material_frames: unit weft/warp directions per face [F, 2, 3] (garments give them);
                without them the first edge of each face is the weft.
            pinned: indices of vertices held at their targets (tests: a hanging strip).
            weft_scale: rest length along the weft relative to ``vertices``, per face [F] (an
                elastic waistband: below 1, the face is stretched around the body as built).
        """
        v, f = _checked_mesh(vertices, faces, "cloth")
        if scene < 0:
            raise InputError(f"scene index must be >= 0, got {scene}")
        if weft_scale is not None:
            weft_scale = np.asarray(weft_scale, dtype=np.float64).reshape(-1)
            if weft_scale.shape != (len(f),) or not (np.isfinite(weft_scale).all() and (weft_scale > 0.5).all()
                                                      and (weft_scale <= 1.5).all()):
                raise InputError(f"weft_scale must hold one value in (0.5, 1.5] per face ({len(f)}), got shape "
                                 f"{weft_scale.shape}")
        first = sum(len(p.vertices) for p in self._parts)
        self._parts.append(_ClothPart(v, f, material(material_name), int(scene), material_frames,
                                      None if pinned is None else np.asarray(pinned, dtype=np.int64), weft_scale))
        return first

    def add_garment(self, garment, *, scene: int = 0, material_name: Material | str | None = None) -> int:
        """Add a :class:`~datagen.garment.mesh.GarmentMesh` (its material, material frames and
        waistband)."""
        return self.add_cloth(garment.vertices, garment.faces, material_name=material_name or garment.material,
                              scene=scene, material_frames=garment.material_frames(),
                              weft_scale=garment.weft_rest_scale())

    def finalize(self, device: str | None = None) -> ClothModel:
        import warp as wp

        if not self._parts:
            raise InputError("the model has no cloth: add a garment first")
        device = str(wp.get_device(device))
        self._parts.sort(key=lambda p: p.scene)  # stable: each scene's cloth contiguous
        verts, faces, scene_of, frames, mats, pins, face_mat, wscale = [], [], [], [], [], [], [], []
        base = 0
        for k, p in enumerate(self._parts):
            verts.append(p.vertices)
            faces.append(p.faces + base)
            scene_of.append(np.full(len(p.vertices), p.scene))
            frames.append(p.frames if p.frames is not None else _edge_frames(p.vertices, p.faces))
            mats.append(p.material)
            face_mat.append(np.full(len(p.faces), k))
            wscale.append(np.ones(len(p.faces)) if p.weft_scale is None else p.weft_scale)
            if p.pinned is not None:
                pins.append(p.pinned + base)
            base += len(p.vertices)
        X = np.concatenate(verts)
        F = np.concatenate(faces)
        scene = np.concatenate(scene_of).astype(np.int32)
        frames = np.concatenate(frames)
        fm = np.concatenate(face_mat)
        host = _topology(X, F)
        # membrane: rest shape matrix in the material frame
        e1, e2 = X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]
        weft = np.array(frames[:, 0], dtype=np.float64)
        nrm = np.cross(e1, e2)
        area = 0.5 * np.linalg.norm(nrm, axis=1)
        if (area < 1e-12).any():
            raise InputError(f"{int((area < 1e-12).sum())} cloth triangles have (almost) zero area: remesh the garment")
        nrm /= 2 * area[:, None]
        weft = weft - nrm * np.einsum("ij,ij->i", weft, nrm)[:, None]
        weft /= np.linalg.norm(weft, axis=1, keepdims=True)
        warp_dir = np.cross(nrm, weft)
        Dm = np.stack([np.stack([np.einsum("ij,ij->i", e1, weft), np.einsum("ij,ij->i", e2, weft)], 1),
                       np.stack([np.einsum("ij,ij->i", e1, warp_dir), np.einsum("ij,ij->i", e2, warp_dir)], 1)], 1)
        weft_scale = np.concatenate(wscale)
        Dm[:, 0, :] *= weft_scale[:, None]  # a shrunk weft: the rest shape is shorter around the body
        dm_inv = np.linalg.inv(Dm)  # F(x) = Ds Dm⁻¹ with Ds = [x1 - x0, x2 - x0]
        stiff = np.array([[m.stretch_weft, m.stretch_warp, m.poisson * np.sqrt(m.stretch_weft * m.stretch_warp), m.shear]
                          for m in mats])[fm]
        lock = np.array([[1.0 + m.lock_strain, m.lock_ratio * max(m.stretch_weft, m.stretch_warp)] for m in mats])[fm]
        dens = np.array([m.density for m in mats])[fm]
        mass = np.zeros(len(X))
        varea = np.zeros(len(X))
        for c in range(3):
            np.add.at(mass, F[:, c], dens * area / 3)
            np.add.at(varea, F[:, c], area / 3)
        vmat = np.zeros(len(X), dtype=np.int64)
        for c in range(3):
            vmat[F[:, c]] = fm
        damping = np.array([m.damping for m in mats])[vmat]
        friction = np.array([m.friction for m in mats])[vmat]
        thickness = np.array([m.thickness for m in mats])[vmat]
        # bending
        E = host["edges"]
        inner = (E[:, 2] >= 0) & (E[:, 3] >= 0)
        rest_angle = np.zeros(len(E))
        bend_k = np.zeros(len(E))
        if inner.any():
            x0, x1, x2, x3 = (X[E[inner, k]] for k in range(4))
            ed = x1 - x0
            N1, N2 = np.cross(ed, x2 - x0), np.cross(x3 - x0, ed)
            n1 = N1 / np.linalg.norm(N1, axis=1, keepdims=True)
            n2 = N2 / np.linalg.norm(N2, axis=1, keepdims=True)
            L = np.linalg.norm(ed, axis=1)
            rest_angle[inner] = np.arctan2(np.einsum("ij,ij->i", np.cross(n1, n2), ed / L[:, None]),
                                           np.einsum("ij,ij->i", n1, n2))
            a12 = 0.5 * (np.linalg.norm(N1, axis=1) + np.linalg.norm(N2, axis=1))
            kb = np.array([m.bending for m in mats])[vmat[E[inner, 0]]]
            bend_k[inner] = kb * 3.0 * L**2 / a12
        active = np.ones(len(X), dtype=np.int32)
        if pins:
            active[np.concatenate(pins)] = 0
        host.update(rest_positions=X, faces=F, particle_scene=scene, mass=mass, vertex_area=varea, dm_inv=dm_inv,
                    tri_area=area * weft_scale, tri_stiff=stiff, tri_lock=lock, rest_angle=rest_angle, bend_k=bend_k, active=active,
                    damping=damping, friction=friction, thickness=thickness)
        scene_count = max(int(scene.max()), max(self._bodies, default=0)) + 1
        missing = sorted(set(range(scene_count)) - set(self._bodies))
        bv, bf, bp, bs, bbase, body_ranges = [], [], [], [], 0, []
        for s in range(scene_count):
            if s in self._bodies:
                v, f, part = self._bodies[s]
            else:  # a scene without a body gets a tiny far-away triangle, so no query ever finds it
                v, f = np.array([[0.0, -1e4, 0.0], [1e-3, -1e4, 0.0], [0.0, -1e4, 1e-3]]), np.array([[0, 1, 2]])
                part = np.zeros(1, dtype=np.int32)
            bv.append(v)
            bf.append(f + bbase)
            bp.append(part)
            bs.append(np.full(len(v), s))
            body_ranges.append((bbase, bbase + len(v)))
            bbase += len(v)
        host.update(body_rest=np.concatenate(bv), body_faces=np.concatenate(bf), body_face_part=np.concatenate(bp),
                    body_vert_scene=np.concatenate(bs), body_ranges=np.array(body_ranges), scenes_without_body=missing)
        host.update(_body_parts(host["body_faces"], host["body_face_part"], bs, scene_count))
        without_cloth = sorted(set(range(scene_count)) - set(scene.tolist()))
        if without_cloth:
            raise InputError(f"scenes {without_cloth} have a body but no cloth: number scenes 0..N-1, each with cloth")
        bounds = lambda a: np.stack([np.searchsorted(a, np.arange(scene_count)),
                                     np.searchsorted(a, np.arange(scene_count), side="right")], 1)
        host["particle_range"] = bounds(scene)
        host["face_range"] = bounds(scene[F[:, 0]])
        host["edge_range"] = bounds(scene[E[:, 0]])
        host["body_face_range"] = bounds(host["body_vert_scene"][host["body_faces"][:, 0]])
        if (np.diff(scene[E[:, 0]]) < 0).any() or (np.diff(scene[F[:, 0]]) < 0).any():
            raise AssertionError("edges and faces must be grouped by scene")

        model = ClothModel(device=device, particle_count=len(X), face_count=len(F), edge_count=len(E),
                           scene_count=scene_count, host=host, body_vertex_count=len(host["body_rest"]))
        arr = {}
        with wp.ScopedDevice(device):
            f32 = lambda a, dt=float: wp.array(np.asarray(a, dtype=np.float32), dtype=dt)
            i32 = lambda a: wp.array(np.ascontiguousarray(a, dtype=np.int32))
            arr.update(rest_positions=f32(X, wp.vec3), mass=f32(mass), vertex_area=f32(varea), active=i32(active),
                       particle_scene=i32(scene), faces=i32(F), dm_inv=f32(dm_inv, wp.mat22), tri_area=f32(area),
                       tri_stiff=f32(stiff, wp.vec4), tri_lock=f32(lock, wp.vec2), edges=i32(E), rest_angle=f32(rest_angle), bend_k=f32(bend_k),
                       v2f_offsets=i32(host["v2f_offsets"]), v2f=i32(host["v2f"]),
                       v2e_offsets=i32(host["v2e_offsets"]), v2e=i32(host["v2e"]),
                       nbr_offsets=i32(host["nbr_offsets"]), nbr=i32(host["nbr"]), damping=f32(damping),
                       friction=f32(friction), thickness=f32(thickness),
                       face_base=i32(host["face_range"][:, 0]), edge_base=i32(host["edge_range"][:, 0]),
                       body_face_base=i32(host["body_face_range"][:, 0]),
                       edge_pairs=i32(E[:, :2]), body_rest=f32(host["body_rest"], wp.vec3),
                       body_faces=i32(host["body_faces"]), body_vert_scene=i32(host["body_vert_scene"]),
                       body_face_part=i32(host["body_face_part"]), part_faces=i32(host["part_faces"]),
                       part_edge_flags=i32(host["part_edge_flags"]),
                       part_face_base=i32(host["part_face_range"][:, 0]))
            colours: list[list[np.ndarray]] = []
            conf = host["conflicts"]
            for s_, (p0, p1) in enumerate(host["particle_range"]):
                mine = conf[scene[conf[:, 0]] == s_] - p0
                for k, c in enumerate(_colour(int(p1 - p0), mine)):
                    if k == len(colours):
                        colours.append([])
                    colours[k].append(c + p0)
            model.colours = [i32(np.concatenate(c)) for c in colours]
        for k, a in arr.items():
            object.__setattr__(model, k, a)
        return model


def _body_parts(body_faces: np.ndarray, face_part: np.ndarray, vert_scene: list, scene_count: int) -> dict:
    """Every scene's body faces grouped by part, slot ``scene * P + part`` (P = ``body_part_count``):
    ``part_faces`` (global face ids, slot by slot), ``part_face_range`` [S*P, 2] and
    ``part_edge_flags`` (bit k: the face's edge from corner k to corner k+1 is on the part's
    border, where it meets another part: a closest point there belongs to the other part)."""
    P = int(face_part.max()) + 1
    face_scene = np.concatenate(vert_scene)[body_faces[:, 0]]
    faces, flags, ranges = [], [], []
    start = 0
    for s in range(scene_count):
        for p in range(P):
            sel = np.flatnonzero((face_scene == s) & (face_part == p))
            F = body_faces[sel]
            e = np.sort(np.stack([F, np.roll(F, -1, axis=1)], 2).reshape(-1, 2), axis=1)
            _, inv, count = np.unique(e, axis=0, return_inverse=True, return_counts=True)
            border = (count[inv.ravel()] == 1).reshape(-1, 3)
            faces.append(sel)
            flags.append((border * np.array([1, 2, 4])).sum(1))
            ranges.append((start, start + len(sel)))
            start += len(sel)
    return {"body_part_count": P, "part_faces": np.concatenate(faces), "part_edge_flags": np.concatenate(flags),
            "part_face_range": np.array(ranges, dtype=np.int64)}


def _checked_mesh(vertices, faces, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [V, 3] (float64, finite) and faces [F, 3] (int64, in range), or an InputError."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or not np.isfinite(v).all():
        raise InputError(f"{what} vertices must be finite and of shape [V, 3], got {v.shape}")
    if f.ndim != 2 or f.shape[1] != 3 or len(f) == 0 or f.min() < 0 or f.max() >= len(v):
        raise InputError(f"{what} faces must be a non-empty [F, 3] array of indices into {len(v)} vertices")
    return v, f


def _edge_frames(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    e = v[f[:, 1]] - v[f[:, 0]]
    n = np.cross(e, v[f[:, 2]] - v[f[:, 0]])
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    return np.stack([e, np.cross(n / np.linalg.norm(n, axis=1, keepdims=True), e)], 1)


def _topology(X: np.ndarray, F: np.ndarray) -> dict:
    """Edges with their opposite corners, vertex-face and vertex-edge incidence, neighbours."""
    V = len(X)
    he = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    opp = np.concatenate([F[:, 2], F[:, 0], F[:, 1]])
    key = np.sort(he, axis=1)
    uniq, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    if counts.max() > 2:
        raise InputError(f"{int((counts > 2).sum())} cloth edges are shared by more than two triangles "
                         "(non-manifold): repair or remesh the garment")
    E = np.full((len(uniq), 4), -1, dtype=np.int64)
    order = np.argsort(inv, kind="stable")
    first = np.ones(len(he), dtype=bool)
    first[1:] = inv[order][1:] != inv[order][:-1]
    # the first half-edge of each edge gives the hinge direction and the corner x2; the second x3
    for is_first, slot in ((True, 2), (False, 3)):
        sel = order[first == is_first]
        E[inv[sel], slot] = opp[sel]
        if is_first:
            E[inv[sel], 0] = he[sel, 0]
            E[inv[sel], 1] = he[sel, 1]
    # vertex -> (face, corner)
    vf = np.stack([F.ravel(), np.repeat(np.arange(len(F)), 3), np.tile(np.arange(3), len(F))], 1)
    vf = vf[np.argsort(vf[:, 0], kind="stable")]
    v2f_off = np.concatenate([[0], np.cumsum(np.bincount(vf[:, 0], minlength=V))])
    # vertex -> (edge, stencil slot)
    ve = np.concatenate([np.stack([E[:, k], np.arange(len(E)), np.full(len(E), k)], 1) for k in range(4)])
    ve = ve[ve[:, 0] >= 0]
    ve = ve[np.argsort(ve[:, 0], kind="stable")]
    v2e_off = np.concatenate([[0], np.cumsum(np.bincount(ve[:, 0], minlength=V))])
    # neighbours (sorted per vertex)
    nb = np.concatenate([E[:, :2], E[:, 1::-1]])
    nb = nb[np.lexsort((nb[:, 1], nb[:, 0]))]
    nbr_off = np.concatenate([[0], np.cumsum(np.bincount(nb[:, 0], minlength=V))])
    # colouring conflicts: vertices sharing a triangle or a hinge stencil
    st = E[(E[:, 2] >= 0) & (E[:, 3] >= 0)]
    pairs = [E[:, :2], st[:, [0, 2]], st[:, [0, 3]], st[:, [1, 2]], st[:, [1, 3]], st[:, [2, 3]]]
    conflicts = np.unique(np.sort(np.concatenate(pairs), axis=1), axis=0)
    return {"edges": E, "v2f_offsets": v2f_off, "v2f": vf[:, 1:], "v2e_offsets": v2e_off, "v2e": ve[:, 1:],
            "nbr_offsets": nbr_off, "nbr": nb[:, 1], "conflicts": conflicts}


def _colour(n: int, conflicts: np.ndarray) -> list[np.ndarray]:
    """Vertex colours (warp's graph colouring), as lists of vertex ids."""
    import warp as wp

    colours = wp.zeros(n, dtype=wp.int32, device="cpu")
    wp.utils.graph_coloring_assign(wp.array(conflicts.astype(np.int32), dtype=wp.int32, device="cpu"), colours)
    c = colours.numpy()
    return [np.flatnonzero(c == k).astype(np.int32) for k in range(c.max() + 1)]
