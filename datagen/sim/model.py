"""The cloth model: what does not change during a run, for one scene or a batch of scenes.

``ClothModelBuilder.add_cloth(...)`` adds one garment (a triangle mesh with its material) to a
scene with its own body; ``finalize(device)`` concatenates every scene into flat arrays, in named
parts: the membrane (rest shape matrices in the material frame, stiffnesses, lock, rest area,
mass), the bending hinges (rest angles, stiffnesses), the bodies (colliders, their parts, per-scene
ranges), the topology (vertex adjacency and a graph colouring for the vertex block descent solver),
all in numpy (:class:`ClothHostArrays`), then uploads them to warp (:class:`ClothModel`).
Scenes share no vertex, edge or contact;
each scene's vertices, faces and edges are contiguous, each scene has its own collision
structures and its own colouring (merged by colour index), so a scene's result does not depend
on what else is in its batch.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from datagen.errors import InputError
from datagen.geometry.topology import unique_edges
from datagen.materials import Material, material

if TYPE_CHECKING:
    import warp as wp


@dataclass
class _ClothPart:
    vertices: np.ndarray
    faces: np.ndarray
    material: Material
    scene: int
    frames: np.ndarray | None
    pinned: np.ndarray | None
    weft_scale: np.ndarray | None = None
    rest_corners: np.ndarray | None = None  # 2D rest coordinates of every face corner [F, 3, 2]
    grain: np.ndarray | None = None  # warp direction of every face in its 2D frame [F, 2]


@dataclass(frozen=True, kw_only=True, eq=False)
class ClothHostArrays:
    """The model as built, in numpy (float64 and int64): the one source of every array that
    :class:`ClothModel` holds on its device (same names, uploaded as float32 and int32), plus the
    per-scene ranges. N = particle_count, F = face_count, E = edge_count, S = scene_count,
    B = body_vertex_count, Fb = body faces, P = body_part_count."""

    # cloth vertices
    rest_positions: np.ndarray
    """Rest (and start) positions [m], [N, 3]."""
    mass: np.ndarray
    """Vertex mass [kg], [N]: a third of each adjacent face's built area x areal density."""
    vertex_area: np.ndarray
    """Vertex area [m²], [N]: a third of each adjacent face's built area (air drag, friction)."""
    active: np.ndarray
    """1 for a simulated vertex, 0 for a pinned one, [N]."""
    particle_scene: np.ndarray
    """Scene of every vertex, [N] (ascending: each scene's vertices contiguous)."""
    damping: np.ndarray
    """Stiffness-proportional damping of the vertex's material [s], [N]."""
    friction: np.ndarray
    """Coulomb friction coefficient of the vertex's material [-], [N]."""
    thickness: np.ndarray
    """Material thickness [m], [N] (the body contact distance less the solver's margin)."""
    max_strain: np.ndarray
    """The largest principal strain the vertex's material allows [-], [N] (the stretch gate)."""
    # membrane
    faces: np.ndarray
    """Triangles (global vertex ids), [F, 3]."""
    dm_inv: np.ndarray
    """Inverse rest shape matrix Dm⁻¹ of every face in its material frame [1/m], [F, 2, 2]; Dm's weft
    row is the built one x the face's weft scale, and F = Ds Dm⁻¹ with Ds = [x1 - x0, x2 - x0]."""
    tri_area: np.ndarray
    """Rest area [m²], [F]: the area of the reference shape, |det Dm|/2 = built area x weft scale;
    the membrane energy's weight (its integral over the reference shape). Mass is the built area's."""
    tri_stiff: np.ndarray
    """(k_u, k_v, k_uv, k_s [N/m], r [-]), [F, 5]: weft, warp, Poisson coupling, shear, and the
    buckling ratio (a compressed direction's stiffness, and the coupling, times r)."""
    tri_lock: np.ndarray
    """(1 + lock strain [-], lock stiffness [N/m]), [F, 2]: the material's lock."""
    # bending
    edges: np.ndarray
    """Hinges [E, 4]: the edge (0, 1) and the opposite corners (2, 3; -1 on a boundary)."""
    edge_pairs: np.ndarray
    """The edge's two vertices, [E, 2] (``edges[:, :2]``)."""
    rest_angle: np.ndarray
    """Rest dihedral angle [rad], [E] (0 on a boundary edge)."""
    bend_k: np.ndarray
    """Hinge stiffness 3 k_b |ē|²/(Ā₁+Ā₂) [N·m], [E] (0 on a boundary edge)."""
    # topology
    v2f_offsets: np.ndarray
    """Start of each vertex's entries in ``v2f``, [N + 1]."""
    v2f: np.ndarray
    """(face, corner) of every face corner, grouped by vertex, [3F, 2]."""
    v2e_offsets: np.ndarray
    """Start of each vertex's entries in ``v2e``, [N + 1]."""
    v2e: np.ndarray
    """(edge, stencil slot 0..3) of every hinge stencil a vertex is in, grouped by vertex, [*, 2]."""
    nbr_offsets: np.ndarray
    """Start of each vertex's neighbours in ``nbr``, [N + 1]."""
    nbr: np.ndarray
    """Vertices sharing an edge with each vertex, sorted per vertex, [2E]."""
    colours: tuple[np.ndarray, ...]
    """Vertex ids of every colour (no two vertices of one colour share a triangle or hinge stencil;
    each scene coloured on its own, merged by colour index)."""
    # per-scene ranges
    particle_range: np.ndarray
    """[first, end) vertex of every scene, [S, 2]."""
    face_range: np.ndarray
    """[first, end) face of every scene, [S, 2]."""
    edge_range: np.ndarray
    """[first, end) edge of every scene, [S, 2]."""
    # bodies
    body_rest: np.ndarray
    """Every scene's body in its start pose, concatenated in scene order [m], [B, 3]."""
    body_faces: np.ndarray
    """Body triangles (global body vertex ids), [Fb, 3]."""
    body_face_part: np.ndarray
    """Body part of every body face (0..P-1), [Fb]."""
    body_vert_scene: np.ndarray
    """Scene of every body vertex, [B]."""
    body_ranges: np.ndarray
    """[first, end) body vertex of every scene, [S, 2]."""
    body_face_range: np.ndarray
    """[first, end) body face of every scene, [S, 2]."""
    body_part_count: int
    """P: body parts (the largest part index + 1 over the batch)."""
    body_face_border: np.ndarray
    """Per body face: bit k set when the face's edge from corner k to k+1 is on its part's border
    (a closest point there belongs to the neighbouring part), [Fb]."""


@dataclass(frozen=True, kw_only=True, eq=False)
class ClothModel:
    """Every scene's cloth and bodies as flat arrays: what does not change during a run.

    The warp arrays (on ``device``; float32 and int32) are uploaded from ``host``, which holds the
    same arrays as built (float64 and int64; see :class:`ClothHostArrays` for what each one means).
    N = particle_count, F = face_count, E = edge_count, S = scene_count, B = body_vertex_count,
    Fb = body faces, P = body_part_count.
    """

    device: str
    """The warp device of the arrays."""
    particle_count: int
    """N, cloth vertices of all scenes."""
    face_count: int
    """F, cloth triangles of all scenes."""
    edge_count: int
    """E, cloth edges (hinges) of all scenes."""
    scene_count: int
    """S, scenes (each its own cloth, body, collision structures and colouring)."""
    body_vertex_count: int
    """B, body vertices of all scenes."""
    body_part_count: int
    """P, body part slots per scene."""
    scenes_without_body: tuple[int, ...]
    """Scenes given no body (each has a tiny far-away triangle instead, which no query finds)."""
    host: ClothHostArrays
    """The numpy arrays these were uploaded from (host-side readers: metrics, mesh building)."""
    # cloth vertices
    rest_positions: wp.array
    """Rest positions [m], vec3 [N]."""
    mass: wp.array
    """Vertex mass [kg], float [N] (built area x density)."""
    vertex_area: wp.array
    """Vertex area [m²], float [N]."""
    active: wp.array
    """1 simulated, 0 pinned, int32 [N]."""
    particle_scene: wp.array
    """Scene of every vertex, int32 [N]."""
    damping: wp.array
    """Stiffness-proportional damping [s], float [N]."""
    friction: wp.array
    """Coulomb friction coefficient [-], float [N]."""
    # membrane
    faces: wp.array
    """Triangles, int32 [F, 3]."""
    dm_inv: wp.array
    """Inverse rest shape matrix in the material frame [1/m], mat22 [F] (weft row scaled)."""
    tri_area: wp.array
    """Rest (reference) area |det Dm|/2 = built area x weft scale [m²], float [F]: the membrane's weight."""
    tri_stiff: wp.array
    """(k_u, k_v, k_uv, k_s [N/m], buckling ratio r [-]), vec5 [F] (:data:`datagen.sim.kernels.vec5`)."""
    tri_lock: wp.array
    """(1 + lock strain [-], lock stiffness [N/m]), vec2 [F]."""
    # bending
    edges: wp.array
    """Hinges (edge 0, 1; opposite corners 2, 3 or -1), int32 [E, 4]."""
    edge_pairs: wp.array
    """The edge's two vertices, int32 [E, 2]."""
    rest_angle: wp.array
    """Rest dihedral angle [rad], float [E]."""
    bend_k: wp.array
    """Hinge stiffness 3 k_b |ē|²/(Ā₁+Ā₂) [N·m], float [E]."""
    # topology
    v2f_offsets: wp.array
    """Start of each vertex's entries in ``v2f``, int32 [N + 1]."""
    v2f: wp.array
    """(face, corner) grouped by vertex, int32 [3F, 2]."""
    v2e_offsets: wp.array
    """Start of each vertex's entries in ``v2e``, int32 [N + 1]."""
    v2e: wp.array
    """(edge, stencil slot) grouped by vertex, int32 [*, 2]."""
    nbr_offsets: wp.array
    """Start of each vertex's neighbours in ``nbr``, int32 [N + 1]."""
    nbr: wp.array
    """Edge neighbours, sorted per vertex, int32 [2E]."""
    # bodies
    body_rest: wp.array
    """Bodies in their start pose [m], vec3 [B]."""
    body_faces: wp.array
    """Body triangles (global body vertex ids), int32 [Fb, 3]."""
    body_face_part: wp.array
    """Body part of every body face, int32 [Fb]."""
    body_face_base: wp.array
    """First body face of every scene, int32 [S]."""
    body_face_border: wp.array
    """Part-border edge bits of every body face, int32 [Fb]."""


@dataclass(frozen=True)
class _Gathered:
    """Every cloth part concatenated in scene order."""

    X: np.ndarray  # rest positions [N, 3]
    F: np.ndarray  # faces [F, 3]
    scene: np.ndarray  # scene per vertex, int32 [N]
    frames: np.ndarray  # weft, warp per face [F, 2, 3]
    face_material: np.ndarray  # index into ``materials`` per face [F]
    materials: list  # Material of every part
    weft_scale: np.ndarray  # per face [F]
    active: np.ndarray  # 1 simulated, 0 pinned, int32 [N]
    rest_corners: np.ndarray | None = None  # 2D rest coordinates per face corner [F, 3, 2] (None: no flat part)
    grain: np.ndarray | None = None  # warp direction per face in its 2D frame [F, 2] (flat faces)
    flat: np.ndarray | None = None  # per face: its rest state is flat 2D cloth [F] bool (None: no flat part)


@dataclass(frozen=True)
class _Membrane:
    """See :func:`_membrane` (the fields of :class:`ClothHostArrays` of the same names)."""

    dm_inv: np.ndarray
    tri_area: np.ndarray
    tri_stiff: np.ndarray
    tri_lock: np.ndarray
    mass: np.ndarray
    vertex_area: np.ndarray


@dataclass(frozen=True)
class _VertexMaterial:
    """See :func:`_vertex_materials`: the material index of every vertex and its properties."""

    material: np.ndarray
    damping: np.ndarray
    friction: np.ndarray
    thickness: np.ndarray
    max_strain: np.ndarray


@dataclass(frozen=True)
class _Bending:
    """See :func:`_bending`."""

    edge_pairs: np.ndarray
    rest_angle: np.ndarray
    bend_k: np.ndarray


@dataclass(frozen=True)
class _Topology:
    """See :func:`_topology`; ``conflicts`` [K, 2] are the vertex pairs the colouring separates."""

    edges: np.ndarray
    v2f_offsets: np.ndarray
    v2f: np.ndarray
    v2e_offsets: np.ndarray
    v2e: np.ndarray
    nbr_offsets: np.ndarray
    nbr: np.ndarray
    conflicts: np.ndarray


@dataclass(frozen=True)
class _Bodies:
    """See :meth:`ClothModelBuilder._body_arrays` (the ``body_*`` and ``part_*`` fields of
    :class:`ClothHostArrays`), and the scenes given no body."""

    rest: np.ndarray
    faces: np.ndarray
    face_part: np.ndarray
    vert_scene: np.ndarray
    ranges: np.ndarray
    face_range: np.ndarray
    part_count: int
    face_border: np.ndarray
    missing: tuple[int, ...]


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
                  weft_scale: np.ndarray | None = None, rest_corners: np.ndarray | None = None,
                  grain: np.ndarray | None = None) -> int:
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
            rest_corners: the flat rest state of a sewing-pattern garment: the 2D panel coordinate
                [m] of every face corner [F, 3, 2] (corners, not vertices: a vertex welded on a
                seam has one coordinate per panel). Given, each face's reference shape and rest
                area come from it, its mass from the 2D area, and every hinge's rest angle is 0
                (flat cloth, across seams too: :func:`_bending`); ``vertices`` are then only the
                start positions. None: the rest state is ``vertices`` as built (shell garments).
            grain: with ``rest_corners``, the warp direction of every face in its 2D frame [F, 2]
                (unit; the weft is the warp turned by -90 degrees); default (0, 1).
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
        if rest_corners is not None:
            rest_corners = np.asarray(rest_corners, dtype=np.float64)
            if rest_corners.shape != (len(f), 3, 2) or not np.isfinite(rest_corners).all():
                raise InputError(f"rest_corners must hold finite 2D coordinates of every face corner, shape "
                                 f"[{len(f)}, 3, 2], got {rest_corners.shape}")
            grain = np.tile([0.0, 1.0], (len(f), 1)) if grain is None else np.asarray(grain, dtype=np.float64)
            norm = np.linalg.norm(grain, axis=1, keepdims=True) if grain.ndim == 2 else None
            if grain.shape != (len(f), 2) or not (np.isfinite(grain).all() and (norm > 1e-9).all()):
                raise InputError(f"grain must hold one nonzero 2D direction per face, shape [{len(f)}, 2], "
                                 f"got {grain.shape}")
            grain = grain / norm
        elif grain is not None:
            raise InputError("grain is the warp direction in the 2D rest state: give rest_corners with it")
        first = sum(len(p.vertices) for p in self._parts)
        self._parts.append(_ClothPart(v, f, material(material_name), int(scene), material_frames,
                                      None if pinned is None else np.asarray(pinned, dtype=np.int64), weft_scale,
                                      rest_corners, grain))
        return first

    def finalize(self, device: str | None = None) -> ClothModel:
        """Concatenate every scene into one :class:`ClothModel` on ``device`` (default: warp's)."""
        import warp as wp

        if not self._parts:
            raise InputError("the model has no cloth: add a garment first")
        device = str(wp.get_device(device))
        g = self._gather()
        topo = _parts_topology([(len(p.vertices), p.faces) for p in self._parts])
        membrane = _membrane(g)
        vertex = _vertex_materials(g)
        bending = _bending(g.X, topo.edges, g.materials, vertex.material, g)
        scene_count = max(int(g.scene.max()), max(self._bodies, default=0)) + 1
        bodies = self._body_arrays(scene_count)
        without_cloth = sorted(set(range(scene_count)) - set(g.scene.tolist()))
        if without_cloth:
            raise InputError(f"scenes {without_cloth} have a body but no cloth: number scenes 0..N-1, each with cloth")
        particle_range, face_range, edge_range = _scene_ranges(g.scene, g.F, topo.edges, scene_count)
        host = ClothHostArrays(
            rest_positions=g.X, mass=membrane.mass, vertex_area=membrane.vertex_area, active=g.active,
            particle_scene=g.scene, damping=vertex.damping, friction=vertex.friction, thickness=vertex.thickness,
            max_strain=vertex.max_strain, faces=g.F, dm_inv=membrane.dm_inv, tri_area=membrane.tri_area, tri_stiff=membrane.tri_stiff,
            tri_lock=membrane.tri_lock, edges=topo.edges, edge_pairs=bending.edge_pairs,
            rest_angle=bending.rest_angle, bend_k=bending.bend_k, v2f_offsets=topo.v2f_offsets, v2f=topo.v2f,
            v2e_offsets=topo.v2e_offsets, v2e=topo.v2e, nbr_offsets=topo.nbr_offsets, nbr=topo.nbr,
            colours=_scene_colours(topo.conflicts, g.scene, particle_range), particle_range=particle_range,
            face_range=face_range, edge_range=edge_range, body_rest=bodies.rest, body_faces=bodies.faces,
            body_face_part=bodies.face_part, body_vert_scene=bodies.vert_scene, body_ranges=bodies.ranges,
            body_face_range=bodies.face_range, body_part_count=bodies.part_count,
            body_face_border=bodies.face_border)
        return _upload(host, device, scene_count=scene_count, scenes_without_body=bodies.missing)

    def _gather(self) -> _Gathered:
        """Concatenate the cloth parts in scene order (stable: each scene's cloth contiguous, in the
        order it was added), their faces renumbered to global vertex ids; pinned vertices inactive."""
        self._parts.sort(key=lambda p: p.scene)
        verts, faces, scene_of, frames, face_mat, wscale, pins = [], [], [], [], [], [], []
        base = 0
        for k, p in enumerate(self._parts):
            verts.append(p.vertices)
            faces.append(p.faces + base)
            scene_of.append(np.full(len(p.vertices), p.scene))
            frames.append(p.frames if p.frames is not None else _edge_frames(p.vertices, p.faces))
            face_mat.append(np.full(len(p.faces), k))
            wscale.append(np.ones(len(p.faces)) if p.weft_scale is None else p.weft_scale)
            if p.pinned is not None:
                pins.append(p.pinned + base)
            base += len(p.vertices)
        active = np.ones(base, dtype=np.int32)
        if pins:
            active[np.concatenate(pins)] = 0
        corners = grain = flat = None
        if any(p.rest_corners is not None for p in self._parts):  # shells alone: no flat arrays at all
            corners = np.concatenate([np.zeros((len(p.faces), 3, 2)) if p.rest_corners is None else p.rest_corners
                                      for p in self._parts])
            grain = np.concatenate([np.tile([0.0, 1.0], (len(p.faces), 1)) if p.grain is None else p.grain
                                    for p in self._parts])
            flat = np.concatenate([np.full(len(p.faces), p.rest_corners is not None) for p in self._parts])
        return _Gathered(X=np.concatenate(verts), F=np.concatenate(faces),
                         scene=np.concatenate(scene_of).astype(np.int32), frames=np.concatenate(frames),
                         face_material=np.concatenate(face_mat), materials=[p.material for p in self._parts],
                         weft_scale=np.concatenate(wscale), active=active, rest_corners=corners, grain=grain,
                         flat=flat)

    def _body_arrays(self, scene_count: int) -> _Bodies:
        """Every scene's body concatenated in scene order (a scene without a body gets a tiny
        far-away triangle, so no query ever finds it), its ranges, its part count and the
        part-border edges of its faces (:func:`_part_borders`); and the scenes without a body."""
        missing = sorted(set(range(scene_count)) - set(self._bodies))
        bv, bf, bp, bs, bbase, body_ranges, borders, known = [], [], [], [], 0, [], [], {}
        for s in range(scene_count):
            if s in self._bodies:
                v, f, part = self._bodies[s]
            else:
                v, f = np.array([[0.0, -1e4, 0.0], [1e-3, -1e4, 0.0], [0.0, -1e4, 1e-3]]), np.array([[0, 1, 2]])
                part = np.zeros(1, dtype=np.int32)
            # the border bits depend on the faces and parts alone (local ids): once per distinct body
            key = (np.asarray(f).tobytes(), np.asarray(part).tobytes())
            if key not in known:
                known[key] = _part_borders(f, part)
            borders.append(known[key])
            bv.append(v)
            bf.append(f + bbase)
            bp.append(part)
            bs.append(np.full(len(v), s))
            body_ranges.append((bbase, bbase + len(v)))
            bbase += len(v)
        body_faces, body_face_part, vert_scene = np.concatenate(bf), np.concatenate(bp), np.concatenate(bs)
        return _Bodies(rest=np.concatenate(bv), faces=body_faces, face_part=body_face_part, vert_scene=vert_scene,
                       ranges=np.array(body_ranges), face_range=_bounds(vert_scene[body_faces[:, 0]], scene_count),
                       part_count=int(body_face_part.max()) + 1,
                       face_border=np.concatenate(borders),
                       missing=tuple(missing))


def _membrane(g: _Gathered) -> _Membrane:
    """Per face: the inverse rest shape matrix in the material frame (weft row scaled by the face's
    weft scale), the rest area (of that reference shape: built area x weft scale), the stiffnesses
    and the lock; per vertex: mass and area.

    The membrane energy is the integral of ψ(F) over the reference shape, so its weight is the
    reference area |det Dm|/2. Mass and vertex area are the built area's: a waistband's weft scale
    pre-stretches the fabric as built, it does not add or remove fabric (the garment weighs what
    its pattern does), and drag and friction act on the surface as it is.

    A face with a flat rest state (``g.flat``: a sewing-pattern garment) takes Dm from its corners'
    2D coordinates in the (weft, warp) frame of its grain (:func:`flat_rest_shape`), its rest area
    from that, and its mass and vertex area from the 2D area (the fabric as cut; the 3D start
    positions are only where the cloth starts). Faces without one are computed as before."""
    X, F, mats, fm = g.X, g.F, g.materials, g.face_material
    e1, e2 = X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]
    weft = np.array(g.frames[:, 0], dtype=np.float64)
    nrm = np.cross(e1, e2)
    area = 0.5 * np.linalg.norm(nrm, axis=1)
    shell = np.ones(len(F), dtype=bool) if g.flat is None else ~g.flat
    if (area[shell] < 1e-12).any():
        raise InputError(f"{int((area[shell] < 1e-12).sum())} cloth triangles have (almost) zero area: remesh the garment")
    if g.flat is not None:  # a flat face placed degenerate in 3D: its 3D frame is unused, keep it finite
        area = np.where(shell, area, np.maximum(area, 1e-30))
    nrm /= 2 * area[:, None]
    weft = weft - nrm * np.einsum("ij,ij->i", weft, nrm)[:, None]
    weft /= np.linalg.norm(weft, axis=1, keepdims=True)
    warp_dir = np.cross(nrm, weft)
    Dm = np.stack([np.stack([np.einsum("ij,ij->i", e1, weft), np.einsum("ij,ij->i", e2, weft)], 1),
                   np.stack([np.einsum("ij,ij->i", e1, warp_dir), np.einsum("ij,ij->i", e2, warp_dir)], 1)], 1)
    if g.flat is not None:
        dm_flat, area_flat = flat_rest_shape(g.rest_corners[g.flat], g.grain[g.flat])
        if (area_flat < 1e-12).any():
            raise InputError(f"{int((area_flat < 1e-12).sum())} cloth triangles have (almost) zero area in their "
                             "2D rest state: remesh the pattern")
        Dm[g.flat] = dm_flat
        area = area.copy()
        area[g.flat] = area_flat
    Dm[:, 0, :] *= g.weft_scale[:, None]  # a shrunk weft: the rest shape is shorter around the body
    dm_inv = np.linalg.inv(Dm)  # F(x) = Ds Dm⁻¹ with Ds = [x1 - x0, x2 - x0]
    stiff = np.array([[m.stretch_weft, m.stretch_warp, m.poisson_coupling, m.shear, m.buckling_ratio]
                      for m in mats])[fm]
    lock = np.array([[1.0 + m.lock_strain, m.lock_ratio * max(m.stretch_weft, m.stretch_warp)] for m in mats])[fm]
    dens = np.array([m.density for m in mats])[fm]
    mass = np.zeros(len(X))
    varea = np.zeros(len(X))
    for c in range(3):
        np.add.at(mass, F[:, c], dens * area / 3)
        np.add.at(varea, F[:, c], area / 3)
    return _Membrane(dm_inv=dm_inv, tri_area=area * g.weft_scale, tri_stiff=stiff, tri_lock=lock, mass=mass,
                     vertex_area=varea)


def flat_rest_shape(corners: np.ndarray, grain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The reference shape of flat cloth: Dm [F, 2, 2] (rows weft, warp; columns the edges c1 - c0,
    c2 - c0) and the area [m²] [F] of triangles given by their corners' 2D panel coordinates
    ``corners`` [F, 3, 2] [m], with the warp ``grain`` [F, 2] (unit) and the weft the warp turned by
    -90 degrees, (g_y, -g_x) (as :func:`datagen.garment.pattern.garment._grain_uv`). The deformation
    gradient F = Ds Dm⁻¹ then maps the cut cloth to its 3D shape: its energy is zero wherever the
    cloth lies in space as it was cut (any rigid motion, or a mirror of it: the membrane reads
    FᵀF). A face listed clockwise in 2D has det Dm < 0; the area is |det Dm|/2."""
    c = np.asarray(corners, dtype=np.float64)
    g = np.asarray(grain, dtype=np.float64)
    e1, e2 = c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]
    weft = np.stack([g[:, 1], -g[:, 0]], 1)
    dm = np.stack([np.stack([np.einsum("ij,ij->i", e1, weft), np.einsum("ij,ij->i", e2, weft)], 1),
                   np.stack([np.einsum("ij,ij->i", e1, g), np.einsum("ij,ij->i", e2, g)], 1)], 1)
    return dm, 0.5 * np.abs(np.linalg.det(dm))


def _vertex_materials(g: _Gathered) -> _VertexMaterial:
    """The material of every vertex (that of the last face listing it) and its damping, friction,
    thickness and strain limit."""
    vmat = np.zeros(len(g.X), dtype=np.int64)
    for c in range(3):
        vmat[g.F[:, c]] = g.face_material
    return _VertexMaterial(material=vmat, damping=np.array([m.damping for m in g.materials])[vmat],
                           friction=np.array([m.friction for m in g.materials])[vmat],
                           thickness=np.array([m.thickness for m in g.materials])[vmat],
                           max_strain=np.array([m.max_strain for m in g.materials])[vmat])


def _bending(X: np.ndarray, E: np.ndarray, mats: list, vertex_material: np.ndarray, g: _Gathered | None = None
             ) -> _Bending:
    """Rest dihedral angle and stiffness 3 k_b |ē|²/(Ā₁+Ā₂) of every interior hinge (0 on the
    boundary), from the built shape; k_b is the material of the hinge's first vertex.

    A hinge of flat cloth (a face with a 2D rest state on either side, ``g.flat``) rests at angle 0,
    inside a panel and across a seam alike, and takes |ē| and the areas from the 2D rest state
    (:func:`_flat_hinges`). Across a seam, 0 is the choice of a seam that was pressed open: the
    angle at which two panels meet once sewn depends on the body they were sewn on and on how
    far the sewing got, so it is not a property of the cloth; a rest angle taken from it would
    hold the body's shape in a garment on every other body. A seam's real stiffness (the seam
    allowance) is not modelled."""
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
        kb = np.array([m.bending for m in mats])[vertex_material[E[inner, 0]]]
        if g is not None and g.flat is not None:
            flat, L2, a2 = _flat_hinges(g, E[inner])
            L, a12 = np.where(flat, L2, L), np.where(flat, a2, a12)
            ra = rest_angle[inner]
            ra[flat] = 0.0
            rest_angle[inner] = ra
        bend_k[inner] = kb * 3.0 * L**2 / a12
    return _Bending(edge_pairs=E[:, :2], rest_angle=rest_angle, bend_k=bend_k)


def _flat_hinges(g: _Gathered, hinges: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For interior hinges [H, 4]: whether a face on either side has a flat rest state [H], the
    edge's 2D rest length [m] [H] (the mean of its two faces' lengths where both are flat: a seam
    joins two panels' edges, equal to their ease) and the sum of the two faces' 2D areas [m²] [H]
    (a shell face on one side: its built area), as the built shape's Ā₁+Ā₂."""
    F = g.F
    he = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    face = np.tile(np.arange(len(F)), 3)
    corner = np.repeat(np.arange(3), len(F))
    c = g.rest_corners
    he_len = np.linalg.norm(c[face, (corner + 1) % 3] - c[face, corner], axis=1)
    e1, e2 = c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]
    area2d = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    area3d = 0.5 * np.linalg.norm(np.cross(g.X[F[:, 1]] - g.X[F[:, 0]], g.X[F[:, 2]] - g.X[F[:, 0]]), axis=1)
    face_area = np.where(g.flat, area2d, area3d)
    n = len(g.X)
    key = np.minimum(he[:, 0], he[:, 1]) * n + np.maximum(he[:, 0], he[:, 1])
    order = np.argsort(key, kind="stable")
    hkey = np.minimum(hinges[:, 0], hinges[:, 1]) * n + np.maximum(hinges[:, 0], hinges[:, 1])
    pos = np.searchsorted(key[order], hkey)
    a, b = order[pos], order[pos + 1]  # an interior edge has exactly two half-edges, adjacent once sorted
    fa, fb = face[a], face[b]
    flat = g.flat[fa] | g.flat[fb]
    wa, wb = g.flat[fa].astype(float), g.flat[fb].astype(float)
    length = (wa * he_len[a] + wb * he_len[b]) / np.maximum(wa + wb, 1.0)
    return flat, length, face_area[fa] + face_area[fb]


def _bounds(scene_of: np.ndarray, scene_count: int) -> np.ndarray:
    """[first, end) of every scene in an array of ascending scene ids, [S, 2]."""
    return np.stack([np.searchsorted(scene_of, np.arange(scene_count)),
                     np.searchsorted(scene_of, np.arange(scene_count), side="right")], 1)


def _scene_ranges(scene: np.ndarray, F: np.ndarray, E: np.ndarray,
                  scene_count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The vertex, face and edge range of every scene, [S, 2] each (each scene's faces and edges
    contiguous)."""
    if (np.diff(scene[E[:, 0]]) < 0).any() or (np.diff(scene[F[:, 0]]) < 0).any():
        raise AssertionError("edges and faces must be grouped by scene")
    return _bounds(scene, scene_count), _bounds(scene[F[:, 0]], scene_count), _bounds(scene[E[:, 0]], scene_count)


def _scene_colours(conflicts: np.ndarray, scene: np.ndarray, particle_range: np.ndarray) -> tuple[np.ndarray, ...]:
    """Colour every scene on its own (:func:`_colour`, once per distinct conflict graph: a batch
    repeats a few garments) and merge the colours by index."""
    colours: list[list[np.ndarray]] = []
    bounds = np.searchsorted(scene[conflicts[:, 0]], np.arange(len(particle_range) + 1))  # conflicts are sorted
    known: dict[tuple, list[np.ndarray]] = {}
    for s, (p0, p1) in enumerate(particle_range):
        mine = conflicts[bounds[s]:bounds[s + 1]] - p0
        key = (int(p1 - p0), mine.tobytes())
        if key not in known:
            known[key] = _colour(int(p1 - p0), mine)
        for k, c in enumerate(known[key]):
            if k == len(colours):
                colours.append([])
            colours[k].append(c + p0)
    return tuple(np.concatenate(c) for c in colours)


def triangle_colours(host: ClothHostArrays) -> tuple[np.ndarray, ...]:
    """The colours when only vertices that share a triangle must differ (the model's own ``colours``
    also separate a hinge's two wing vertices; ``SolverConfig.colour_hinge_wings`` picks): each
    scene coloured on its own and the colours merged by index, as :func:`_scene_colours` does."""
    pairs = np.unique(np.sort(np.asarray(host.edges)[:, :2], axis=1), axis=0)
    return _scene_colours(pairs, np.asarray(host.particle_scene), np.asarray(host.particle_range))


def _upload(host: ClothHostArrays, device: str, *, scene_count: int, scenes_without_body: tuple[int, ...]) -> ClothModel:
    """The :class:`ClothModel` on ``device``: every warp array uploaded from ``host`` (float32, int32)."""
    import warp as wp

    from datagen.sim.kernels import vec5

    h = host
    with wp.ScopedDevice(device):
        f32 = lambda a, dt=float: wp.array(np.asarray(a, dtype=np.float32), dtype=dt)
        i32 = lambda a: wp.array(np.ascontiguousarray(a, dtype=np.int32))
        return ClothModel(
            device=device, particle_count=len(h.rest_positions), face_count=len(h.faces), edge_count=len(h.edges),
            scene_count=scene_count, body_vertex_count=len(h.body_rest),
            body_part_count=h.body_part_count, scenes_without_body=scenes_without_body, host=h,
            rest_positions=f32(h.rest_positions, wp.vec3), mass=f32(h.mass), vertex_area=f32(h.vertex_area),
            active=i32(h.active), particle_scene=i32(h.particle_scene), damping=f32(h.damping),
            friction=f32(h.friction), faces=i32(h.faces), dm_inv=f32(h.dm_inv, wp.mat22), tri_area=f32(h.tri_area),
            tri_stiff=f32(h.tri_stiff, vec5), tri_lock=f32(h.tri_lock, wp.vec2), edges=i32(h.edges),
            edge_pairs=i32(h.edge_pairs), rest_angle=f32(h.rest_angle), bend_k=f32(h.bend_k),
            v2f_offsets=i32(h.v2f_offsets), v2f=i32(h.v2f), v2e_offsets=i32(h.v2e_offsets), v2e=i32(h.v2e),
            nbr_offsets=i32(h.nbr_offsets), nbr=i32(h.nbr),
            body_rest=f32(h.body_rest, wp.vec3), body_faces=i32(h.body_faces), body_face_part=i32(h.body_face_part),
            body_face_base=i32(h.body_face_range[:, 0]), body_face_border=i32(h.body_face_border))


def _part_borders(body_faces: np.ndarray, face_part: np.ndarray) -> np.ndarray:
    """Per body face [Fb] (int32): bit k set when its edge from corner k to corner k+1 is on its
    part's border (where it meets another part, or the mesh's own boundary): no other face of the
    same part shares it."""
    F = np.asarray(body_faces, dtype=np.int64)
    e = np.sort(np.stack([F, np.roll(F, -1, axis=1)], 2), axis=2)  # [Fb, 3, 2]
    part = np.repeat(np.asarray(face_part, dtype=np.int64), 3)
    keys = np.concatenate([part[:, None], e.reshape(-1, 2)], axis=1)
    _, inv, count = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    border = (count[inv.ravel()] == 1).reshape(-1, 3)
    return (border * np.array([1, 2, 4])).sum(1).astype(np.int32)


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


def _topology(X: np.ndarray, F: np.ndarray) -> _Topology:
    """Edges with their opposite corners, vertex-face and vertex-edge incidence, neighbours, and the
    colouring conflicts (vertex pairs that share a triangle or a hinge stencil)."""
    V = len(X)
    he = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    opp = np.concatenate([F[:, 2], F[:, 0], F[:, 1]])
    uniq, inv, counts = unique_edges(F, return_inverse=True, return_counts=True)
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
    return _Topology(edges=E, v2f_offsets=v2f_off, v2f=vf[:, 1:], v2e_offsets=v2e_off, v2e=ve[:, 1:],
                     nbr_offsets=nbr_off, nbr=nb[:, 1], conflicts=conflicts)


def _parts_topology(parts: list[tuple[int, np.ndarray]]) -> _Topology:
    """:func:`_topology` of cloth parts laid end to end ((vertex count, faces in local ids) each,
    in the model's order), made once per distinct part and shifted: the same arrays as
    :func:`_topology` of the concatenation (every part's vertices, faces and edges are contiguous
    and sort before the next part's), in a fraction of the time for a batch that repeats a few
    garments (13 s for 252 scenes of three garments on two cores)."""
    known: dict[tuple, _Topology] = {}
    pieces = []
    for nv, faces in parts:
        f = np.asarray(faces, dtype=np.int64)
        key = (int(nv), f.tobytes())
        if key not in known:
            known[key] = _topology(np.zeros((int(nv), 3)), f)
        pieces.append((int(nv), len(f), known[key]))
    edges, v2f_off, v2f, v2e_off, v2e, nbr_off, nbr, conflicts = ([] for _ in range(8))
    vb = fb = eb = 0  # vertices, faces and edges before the part
    nf_, ne_, nn_ = 0, 0, 0  # incidence entries before the part
    for nv, nf, t in pieces:
        edges.append(np.where(t.edges >= 0, t.edges + vb, -1))
        v2f_off.append(t.v2f_offsets[:-1] + nf_)
        v2f.append(t.v2f + [fb, 0])
        v2e_off.append(t.v2e_offsets[:-1] + ne_)
        v2e.append(t.v2e + [eb, 0])
        nbr_off.append(t.nbr_offsets[:-1] + nn_)
        nbr.append(t.nbr + vb)
        conflicts.append(t.conflicts + vb)
        vb, fb, eb = vb + nv, fb + nf, eb + len(t.edges)
        nf_, ne_, nn_ = nf_ + len(t.v2f), ne_ + len(t.v2e), nn_ + len(t.nbr)
    return _Topology(edges=np.concatenate(edges), v2f_offsets=np.concatenate(v2f_off + [[nf_]]),
                     v2f=np.concatenate(v2f), v2e_offsets=np.concatenate(v2e_off + [[ne_]]), v2e=np.concatenate(v2e),
                     nbr_offsets=np.concatenate(nbr_off + [[nn_]]), nbr=np.concatenate(nbr),
                     conflicts=np.concatenate(conflicts))


def _colour(n: int, conflicts: np.ndarray) -> list[np.ndarray]:
    """Vertex colours (warp's graph colouring), as lists of vertex ids."""
    import warp as wp

    colours = wp.zeros(n, dtype=wp.int32, device="cpu")
    wp.utils.graph_coloring_assign(wp.array(conflicts.astype(np.int32), dtype=wp.int32, device="cpu"), colours)
    c = colours.numpy()
    return [np.flatnonzero(c == k).astype(np.int32) for k in range(c.max() + 1)]


MORTON_BITS = 10
"""Bits per axis of :func:`launch_order`'s Morton codes (1,024 cells along a scene's longest side)."""


def launch_order(points: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """An order in which to launch one thread per point so that neighbouring threads hold points
    near each other: within each scene's range ``[first, end)`` the points sorted by the Morton
    code (Z-order) of their position in the scene's bounding box, ties by index; ranges stay where
    they are, so the order of a scene does not depend on its batch. Garment meshes number their
    vertices in no spatial order (32 consecutive vertices of the walking T-shirt span 594 mm of its
    700; in this order 186 mm), so the threads of a warp in a tree query walk different branches.
    Returns int32 indices, a permutation of ``range(ranges[-1, 1])`` when the ranges tile it."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.arange(len(pts), dtype=np.int64)
    for first, end in np.asarray(ranges, dtype=np.int64).reshape(-1, 2):
        if end - first < 2:
            continue
        p = pts[first:end]
        lo, span = p.min(0), float((p.max(0) - p.min(0)).max())
        q = np.zeros_like(p, dtype=np.int64) if span <= 0 else np.minimum(
            ((p - lo) / span * (1 << MORTON_BITS)).astype(np.int64), (1 << MORTON_BITS) - 1)
        code = np.zeros(len(p), dtype=np.int64)
        for bit in range(MORTON_BITS):
            for axis in range(3):
                code |= ((q[:, axis] >> bit) & 1) << (3 * bit + axis)
        out[first:end] = first + np.argsort(code, kind="stable")
    return out.astype(np.int32)
