"""Body measurements of drape's SMPL-format body, for fitting sewing patterns to any shape.

:func:`measure_body` measures one body shape on its T-pose rest mesh (metres, Y up, facing +Z,
arms along ±X) from two kinds of landmark: SMPL's joints (``model.rest_joints``) and extremes of
the mesh (the armpit, the bust point, the crotch, the widest hip, the narrowest waist), and plane
sections of the mesh, cut by :func:`plane_loops`. Girths are the perimeters of the convex hulls
of plane sections, as a tape measure pulled taut bridges the hollows (between the breasts, along
the spine); heights are above the floor (the lowest vertex, the soles).

Each section keeps one closed loop: the torso's is the loop whose hull contains the spine (so an
arm or a leg cut by the same plane is left out), a limb's is the loop whose hull contains the
limb's bone. The definitions of every field are in :class:`BodyMeasurements`; they follow
ISO 8559-1:2017 (anthropometric definitions for body measurement) where a T-pose allows.
"""

from __future__ import annotations

import logging
import time
import weakref
from dataclasses import asdict, dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError

from datagen.body.model import BodyModel
from datagen.body.skeleton import SMPL_JOINT_NAMES
from datagen.errors import InputError

logger = logging.getLogger(__name__)

_J = {name: i for i, name in enumerate(SMPL_JOINT_NAMES)}
_X = np.array([1.0, 0.0, 0.0])
_Y = np.array([0.0, 1.0, 0.0])
_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True, kw_only=True)
class BodyMeasurements:
    """Measurements of one body shape [m], on its T-pose rest mesh; heights above the floor.

    Girths are perimeters of the convex hull of one loop of a plane section (a taut tape; ISO
    8559-1:2017's names in brackets, taken in a T-pose rather than standing with arms down):
        chest: horizontal torso girth at the bust point's height (bust girth).
        underbust: horizontal torso girth at ``underbust_height``, where the front profile through
            the bust point bends most sharply inwards 2-12 cm below the bust point (underbust girth).
        waist: the smallest horizontal torso girth between the spine1 joint and halfway from the
            spine2 to the spine3 joint (natural waist girth). This is 2-8 cm above the spine2 joint
            on drape's body, not between the pelvis and spine2 joints.
        hip: the largest horizontal torso girth between 1 cm above the crotch and the pelvis joint
            (hip girth, over the buttocks).
        neck: girth in the plane through the back neck point and the front neck point that holds
            the X axis (neck base girth; at the sides this plane passes over the top of the
            trapezius, so it is larger than a tape laid along the neck base curve).
        neck_narrowest: the smallest girth across the neck's axis (planes normal to the line from
            the neck joint to the head joint, over the lower 80 % of it) (neck girth, collar size).
        armhole: girth of the arm's root above the armpit in the plane through the armpit and the
            left shoulder point that holds the Z axis (armscye girth).
        upper_arm: girth of the left arm across it (plane normal X) halfway from the shoulder joint
            to the elbow joint (upper arm girth).
        wrist: girth of the left arm across it at the wrist joint (wrist girth).
        thigh: horizontal girth of the left leg 2 cm below the crotch (thigh girth; the leg leans
            about 5 degrees in drape's T-pose, which lengthens a horizontal section by ~0.5 %).
        knee: horizontal girth of the left leg at the knee joint's height (knee girth).
        ankle: the smallest horizontal girth of the left leg from 1 to 15 cm above the ankle joint
            (minimum leg girth).

    Lengths:
        height: vertical extent of the mesh (stature).
        shoulder_width: from the left to the right shoulder point across the back: the back half
            of the convex hull of the section by the plane through both shoulder points and the
            back neck point (shoulder width, along the surface with hollows bridged).
        back_length: from the back neck point down to the waist's height along the midline back
            surface (the section x = 0) (back waist length).
        front_length: from the front neck point down to the waist's height along the midline
            front surface (front waist length, centre front).
        arm_length: straight from the left shoulder point to the left wrist joint (arm length;
            the arm is straight in a T-pose).
        crotch_depth: ``waist_height - crotch_height`` (body rise).
        inseam: ``crotch_height - ankle_height``, straight and vertical (inside leg length to the
            ankle; add ``ankle_height`` for the length to the floor).

    Landmarks (heights above the floor, the lowest vertex: the soles):
        chest_height: the bust point's: the most forward torso vertex off the midline
            (|x| > 2 cm), between halfway from the spine2 to the spine3 joint and the armpit.
        underbust_height, waist_height, hip_height: the levels of those girths.
        crotch_height: the lowest point of the midline section's loop around the torso.
        armpit_height: the armpit is the point of the body's outline in the frontal plane through
            the shoulder joints that lies nearest the left shoulder joint, below it and between
            the midline and the elbow.
        neck_height: the back neck point's (cervicale): the midline back surface at the neck
            joint's height.
        front_neck_height: the front neck point's (jugular notch): the most backward point of the
            midline front profile between the armpit and the neck joint.
        shoulder_height: the shoulder points' (acromion): the highest surface point of the
            section across each arm (plane normal X) through its shoulder joint, within 1.5 cm of
            the joint in z.
        knee_height, ankle_height: the left knee and ankle joints'.

    Half-widths (|x| from the midline, the body being left-right symmetric; the left side's):
        shoulder_x: the shoulder point's; armpit_x: the armpit's; bust_x: the bust point's.

    Placement (coordinates in the body's rest frame, not lengths; may be negative):
        floor_y: the floor's y (the lowest vertex's).
        centre_z: z of the area centroid of the waist section's convex hull (the torso's middle,
            front to back).
    """

    height: float
    chest: float
    underbust: float
    waist: float
    hip: float
    neck: float
    neck_narrowest: float
    armhole: float
    upper_arm: float
    wrist: float
    thigh: float
    knee: float
    ankle: float
    shoulder_width: float
    back_length: float
    front_length: float
    arm_length: float
    crotch_depth: float
    inseam: float
    waist_height: float
    hip_height: float
    crotch_height: float
    chest_height: float
    underbust_height: float
    armpit_height: float
    neck_height: float
    front_neck_height: float
    shoulder_height: float
    knee_height: float
    ankle_height: float
    shoulder_x: float
    armpit_x: float
    bust_x: float
    floor_y: float = 0.0
    centre_z: float = 0.0

    def __post_init__(self):
        coordinates = ("floor_y", "centre_z")
        bad = {k: v for k, v in asdict(self).items() if not np.isfinite(v) or (k not in coordinates and v <= 0)}
        if bad:
            raise InputError(f"body measurements must be positive and finite; got {bad}: "
                             "is the body a T-posed human mesh in metres, Y up?")

    def as_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}


# ---------------------------------------------------------------------------------- sections
@dataclass(frozen=True, eq=False)
class MeshTopology:
    """A triangle mesh's faces [F, 3], its unique edges [E, 2] and each face's edges in winding
    order [F, 3] (``face_edges[f, i]`` joins ``faces[f, i]`` and ``faces[f, (i + 1) % 3]``), for
    :func:`plane_loops`. :meth:`subset` keeps some faces (those a family of planes can cross)."""

    faces: np.ndarray
    edges: np.ndarray
    face_edges: np.ndarray

    @classmethod
    def of(cls, faces: np.ndarray) -> "MeshTopology":
        faces = np.asarray(faces, dtype=np.int64)
        if faces.ndim != 2 or faces.shape[1] != 3:
            raise InputError(f"faces must be [F, 3], got {faces.shape}")
        half = np.stack([faces, np.roll(faces, -1, axis=1)], axis=-1).reshape(-1, 2)
        edges, inverse = np.unique(np.sort(half, axis=1), axis=0, return_inverse=True)
        return cls(faces=faces, edges=edges, face_edges=inverse.reshape(-1, 3))

    def subset(self, keep: np.ndarray) -> "MeshTopology":
        return MeshTopology(faces=self.faces[keep], edges=self.edges, face_edges=self.face_edges[keep])


_TOPOLOGY: dict[int, tuple[object, MeshTopology]] = {}


def _topology(faces: np.ndarray) -> MeshTopology:
    """:class:`MeshTopology` of ``faces``, kept while the same array object lives (a body's
    faces do not change between shapes, so measuring many shapes builds it once)."""
    hit = _TOPOLOGY.get(id(faces))
    if hit is not None and hit[0]() is faces:
        return hit[1]
    topology = MeshTopology.of(faces)
    if len(_TOPOLOGY) > 8:
        _TOPOLOGY.clear()
    try:
        _TOPOLOGY[id(faces)] = (weakref.ref(faces), topology)
    except TypeError:  # not weak-referenceable: no cache
        pass
    return topology


def plane_loops(vertices: np.ndarray, topology: MeshTopology, origin, normal) -> list[np.ndarray]:
    """The connected pieces of a mesh's section by a plane, each as its points [n, 3] [m].

    ``vertices`` [V, 3]; the plane passes through ``origin`` [3] with normal ``normal`` [3]. A
    vertex exactly on the plane counts as above it, so every crossed triangle holds one segment
    between two crossed edges; a piece is a connected set of crossed edges and their triangles.
    """
    normal = np.asarray(normal, dtype=np.float64)
    origin = np.asarray(origin, dtype=np.float64)
    axis = np.flatnonzero(normal)
    if len(axis) == 1 and normal[axis[0]] == 1.0:  # a plane across an axis: no projection needed
        s = vertices[:, axis[0]] - origin[axis[0]]
    else:
        s = (vertices - origin) @ normal
    above = s >= 0
    fa = above[topology.faces]
    count = fa.sum(axis=1)
    hit = (count == 1) | (count == 2)
    if not hit.any():
        return []
    fa, fe, lone_above = fa[hit], topology.face_edges[hit], count[hit] == 1
    k = np.where(lone_above, fa.argmax(axis=1), fa.argmin(axis=1))  # the vertex alone on its side
    rows = np.arange(len(k))
    after, before = fe[rows, k], fe[rows, (k + 2) % 3]  # the crossed edges leaving and entering it
    # each crossed triangle's segment runs from the edge its winding crosses downwards to the one it
    # crosses upwards: neighbours share that edge in opposite directions, so segments chain into loops
    src = np.where(lone_above, after, before)
    dst = np.where(lone_above, before, after)
    ids = np.union1d(src, dst)
    n = len(ids)
    a, b = np.searchsorted(ids, src), np.searchsorted(ids, dst)
    if len(a) == n and len(np.unique(a)) == n and len(np.unique(b)) == n:
        # closed loops: pointer doubling, min label along each cycle
        label, step = np.arange(n), np.empty(n, dtype=np.int64)
        step[a] = b
        for _ in range(int(np.ceil(np.log2(max(n, 2)))) + 1):
            label = np.minimum(label, label[step])
            step = step[step]
    else:  # open pieces (a mesh with boundaries, or faces left out of a subset)
        graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
        label = connected_components(graph, directed=False)[1]
    e = topology.edges[ids]
    s0, s1 = s[e[:, 0]], s[e[:, 1]]
    t = s0 / (s0 - s1)
    p0, p1 = vertices[e[:, 0]], vertices[e[:, 1]]
    points = p0 + t[:, None] * (p1 - p0)
    order = np.argsort(label, kind="stable")
    _, starts = np.unique(label[order], return_index=True)
    return np.split(points[order], starts[1:])


def _basis(normal: np.ndarray) -> np.ndarray:
    """Two unit vectors [2, 3] spanning the plane of ``normal``."""
    n = np.asarray(normal, dtype=np.float64)
    if n[1] == 1.0 and not n[0] and not n[2]:
        return _BASIS_Y
    n = n / np.linalg.norm(n)
    helper = _Z if abs(n[2]) < 0.9 else _X
    u = np.cross(helper, n)
    u /= np.linalg.norm(u)
    return np.stack([u, np.cross(n, u)])


_BASIS_Y = np.stack([np.cross(_Z, _Y), np.cross(_Y, np.cross(_Z, _Y))])


def _hull(points2d: np.ndarray) -> ConvexHull | None:
    if len(points2d) < 3:
        return None
    try:
        return ConvexHull(points2d)
    except QhullError:
        return None


def _hull_centroid(hull: ConvexHull) -> np.ndarray:
    """Area centroid [2] of a 2D convex hull."""
    p = hull.points[hull.vertices]
    q = np.roll(p, -1, axis=0)
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    return ((p + q) * cross[:, None]).sum(axis=0) / (3.0 * cross.sum())


def _contains(hull: ConvexHull, point2d: np.ndarray, tol: float = 1e-9) -> bool:
    return bool(np.all(hull.equations[:, :2] @ point2d + hull.equations[:, 2] <= tol))


def section_girth(vertices: np.ndarray, topology: MeshTopology, origin, normal, inside) -> float:
    """Perimeter [m] of the convex hull of the section loop whose hull contains ``inside`` [3]
    (a point of the plane inside the limb or torso to measure); NaN when no loop contains it."""
    found = _select_loop(plane_loops(vertices, topology, origin, normal), normal, inside)
    return float("nan") if found is None else float(found[1].area)


def _select_loop(loops: list[np.ndarray], normal, inside):
    """(points [n, 3], hull in the plane's 2D basis) of the loop around ``inside``, or None."""
    basis = _basis(np.asarray(normal, dtype=np.float64))
    p = basis @ np.asarray(inside, dtype=np.float64)
    for loop in loops:
        flat = loop @ basis.T
        if (flat.min(axis=0) > p).any() or (flat.max(axis=0) < p).any():
            continue
        hull = _hull(flat)
        if hull is not None and _contains(hull, p):
            return loop, hull
    return None


def _convex_chain_length(points2d: np.ndarray) -> float:
    """Perimeter [m] of the convex hull of ``points2d`` [n, 2] (0 when they span no area)."""
    hull = _hull(points2d)
    return 0.0 if hull is None else float(hull.area)


# ---------------------------------------------------------------------------------- the body
class _Body:
    """One shaped rest mesh and its joints, with the sections and landmarks the measurements use."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, joints: np.ndarray):
        self.v = vertices
        self.topology = _topology(faces)
        self.j = joints
        self.floor = float(vertices[:, 1].min())
        chain = [_J[k] for k in ("pelvis", "spine1", "spine2", "spine3", "neck", "head")]
        self._axis_y = joints[chain, 1]
        self._axis_z = joints[chain, 2]
        f = self.topology.faces
        c0, c1, c2 = vertices[f[:, 0]], vertices[f[:, 1]], vertices[f[:, 2]]
        low = np.minimum(np.minimum(c0, c1), c2)
        high = np.maximum(np.maximum(c0, c1), c2)
        self._box_centre, self._box_half = 0.5 * (low + high), 0.5 * (high - low)  # faces' bounding boxes
        self._centre_y = np.ascontiguousarray(self._box_centre[:, 1])
        self._half_y = np.ascontiguousarray(self._box_half[:, 1])
        self._midline: np.ndarray | None = None

    def joint(self, name: str) -> np.ndarray:
        return self.j[_J[name]]

    def axis(self, y: float) -> np.ndarray:
        """The point of the spine's joint chain (pelvis to head) at height ``y``, x = 0."""
        return np.array([0.0, y, float(np.interp(y, self._axis_y, self._axis_z))])

    # -------------------------------------------------------------- sections
    def cut(self, origin, normal) -> list[np.ndarray]:
        """:func:`plane_loops` of the body, over the faces whose bounding boxes meet the plane."""
        origin = np.asarray(origin, dtype=np.float64)
        normal = np.asarray(normal, dtype=np.float64)
        if normal[1] == 1.0 and not normal[0] and not normal[2]:
            near = np.flatnonzero(np.abs(self._centre_y - origin[1]) <= self._half_y)
        else:
            near = np.flatnonzero(np.abs((self._box_centre - origin) @ normal) <= self._box_half @ np.abs(normal))
        return plane_loops(self.v, self.topology.subset(near), origin, normal)

    def loop(self, origin, normal, inside):
        return _select_loop(self.cut(origin, normal), normal, inside)

    def girth(self, origin, normal, inside) -> float:
        found = self.loop(origin, normal, inside)
        return float("nan") if found is None else float(found[1].area)

    def torso_loop(self, y: float):
        return self.loop((0.0, y, 0.0), _Y, self.axis(y))

    def torso_girth(self, y: float) -> float:
        found = self.torso_loop(y)
        return float("nan") if found is None else float(found[1].area)

    def horizontal_girth(self, y: float, inside) -> float:
        return self.girth((0.0, y, 0.0), _Y, inside)

    def extreme_level(self, girth, lo: float, hi: float, step: float, largest: bool, what: str) -> tuple[float, float]:
        """(level, girth) of the smallest or largest ``girth(level)`` for a level in [lo, hi]: a scan
        every ``step``, then the vertex of the parabola through the best level and its neighbours."""
        ys = np.linspace(lo, hi, max(3, int(np.ceil((hi - lo) / step)) + 1))
        g = np.array([girth(y) for y in ys])
        if not np.isfinite(g).any():
            raise InputError(f"no closed section around {what}: is this a T-posed human body in metres, Y up, facing +Z?")
        score = np.where(np.isfinite(g), g if largest else -g, -np.inf)
        k = int(np.argmax(score))
        if 0 < k < len(ys) - 1 and np.isfinite(g[k - 1 : k + 2]).all():
            a, b, c = g[k - 1 : k + 2]
            denom = a - 2 * b + c
            if denom != 0:
                shift = 0.5 * (a - c) / denom
                if abs(shift) < 1:
                    y = float(ys[k] + shift * (ys[1] - ys[0]))
                    gy = girth(y)
                    if np.isfinite(gy) and (gy >= g[k] if largest else gy <= g[k]):
                        return y, gy
        return float(ys[k]), float(g[k])

    def midline(self) -> np.ndarray:
        """Points [n, 3] of the midline (x = 0) section's loop around the spine."""
        if self._midline is None:
            found = self.loop((0.0, 0.0, 0.0), _X, self.joint("spine2"))
            if found is None:
                raise InputError("the body's midline section does not enclose its spine: is the body facing +Z, Y up?")
            self._midline = found[0]
        return self._midline

    def sagittal_profile(self, front: bool, lo: float, hi: float) -> np.ndarray:
        """The midline (x = 0) section's front or back surface between heights lo and hi, as
        points [n, 2] (y, z) sorted by y; front/back is z above/below the spine's joint chain."""
        pts = self.midline()
        axis_z = np.interp(pts[:, 1], self._axis_y, self._axis_z)
        side = pts[:, 2] > axis_z if front else pts[:, 2] < axis_z
        pts = pts[side & (pts[:, 1] >= lo) & (pts[:, 1] <= hi)][:, 1:]
        return pts[np.argsort(pts[:, 0], kind="stable")]


def _profile_length(profile: np.ndarray, lo: float, hi: float) -> float:
    """Length [m] of a (y, z) profile [n, 2] sorted by y, between heights lo and hi, its ends
    completed by the profile's nearest points' z."""
    if len(profile) < 2:
        raise InputError("the body's midline profile is too short to measure a length along it")
    ends = np.array([[lo, profile[0, 1]], [hi, profile[-1, 1]]])
    path = np.concatenate([ends[:1], profile, ends[1:]])
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())


def measure_mesh(vertices: np.ndarray, faces: np.ndarray, joints: np.ndarray) -> BodyMeasurements:
    """:class:`BodyMeasurements` of a T-posed, closed human mesh.

    Args:
        vertices: rest-pose vertices [V, 3] [m], Y up, facing +Z, arms along ±X, left at +X.
        faces: triangles [F, 3] (a closed surface).
        joints: SMPL's 24 rest joints [24, 3] [m] of that mesh.
    """
    v = np.asarray(vertices, dtype=np.float64)
    joints = np.asarray(joints, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 3 or joints.shape != (len(SMPL_JOINT_NAMES), 3):
        raise InputError(f"measure_mesh needs vertices [V, 3] and SMPL's 24 joints [24, 3]; got {v.shape} and {joints.shape}")
    body = _Body(v, faces, joints)
    floor = body.floor
    jy = {name: float(body.joint(name)[1]) for name in ("pelvis", "spine1", "spine2", "spine3", "neck", "head",
                                                         "left_shoulder", "left_knee", "left_ankle", "left_hip")}
    shoulder = body.joint("left_shoulder")
    elbow = body.joint("left_elbow")
    wrist = body.joint("left_wrist")

    # armpit: the point of the body's outline in the frontal plane through the shoulder joints that
    # lies nearest the left shoulder joint, below it, between the midline and the elbow
    pieces = body.cut(shoulder, _Z)
    outline = np.concatenate(pieces) if pieces else np.zeros((0, 3))
    outline = outline[(outline[:, 0] > 0.0) & (outline[:, 0] < elbow[0]) & (outline[:, 1] < shoulder[1])]
    if len(outline) == 0:
        raise InputError("no surface below the shoulder joint in the frontal plane: is the body in a T-pose, facing +Z?")
    armpit = outline[np.argmin(np.linalg.norm(outline - shoulder, axis=1))]
    armpit_y = float(armpit[1])

    # bust point: the most prominent front point of the torso off the midline, below the armpits
    chest_lo = 0.5 * (jy["spine2"] + jy["spine3"])
    sel = ((v[:, 1] >= chest_lo) & (v[:, 1] <= armpit_y) & (np.abs(v[:, 0]) > 0.02)
           & (np.abs(v[:, 0]) < 0.8 * shoulder[0]))
    if not sel.any():
        raise InputError("no torso vertex between the chest joint and the armpits: is this a T-posed human body?")
    bust = v[sel][np.argmax(v[sel, 2])]
    chest_y = float(bust[1])
    chest = body.torso_girth(chest_y)

    # underbust: the sharpest concave bend of the front profile through the bust point, 2-12 cm below it
    found = body.loop((bust[0], 0.0, 0.0), _X, np.array([bust[0], chest_y, bust[2] - 0.03]))
    underbust_y = chest_y - 0.05
    if found is not None:
        pts = found[0]
        front = pts[(pts[:, 2] > bust[2] - 0.08) & (pts[:, 1] > chest_y - 0.15) & (pts[:, 1] <= chest_y)]
        if len(front) > 5:
            front = front[np.argsort(front[:, 1])]
            ys = np.arange(chest_y - 0.14, chest_y + 1e-9, 0.005)
            z = np.interp(ys, front[:, 1], front[:, 2])
            bend = z[:-2] - 2 * z[1:-1] + z[2:]
            window = (ys[1:-1] >= chest_y - 0.12) & (ys[1:-1] <= chest_y - 0.02)
            underbust_y = float(ys[1:-1][window][np.argmax(bend[window])])
    underbust = body.torso_girth(underbust_y)

    # crotch: the lowest point of the midline section's loop around the torso
    crotch_y = float(body.midline()[:, 1].min())

    # hip: the largest girth between the crotch and the pelvis joint
    hip_y, hip = body.extreme_level(body.torso_girth, crotch_y + 0.01, jy["pelvis"], 0.02, largest=True, what="the hips")

    # natural waist: the smallest torso girth between the spine1 joint and halfway to the chest joint
    waist_y, waist = body.extreme_level(body.torso_girth, jy["spine1"], chest_lo, 0.02, largest=False, what="the waist")
    waist_hull = body.torso_loop(waist_y)[1]
    centre_z = float(_hull_centroid(waist_hull)[1])

    # front neck point: the most posterior point of the midline front profile between armpits and neck joint
    front = body.sagittal_profile(True, armpit_y, jy["neck"])
    if len(front) < 3:
        raise InputError("the body's midline front profile between the armpits and the neck is empty")
    front_neck = np.array([0.0, *front[np.argmin(front[:, 1])]])
    front_neck_y = float(front_neck[1])
    back_neck = body.sagittal_profile(False, jy["neck"] - 0.02, jy["neck"] + 0.02)
    c7 = np.array([0.0, jy["neck"], float(np.interp(jy["neck"], back_neck[:, 0], back_neck[:, 1]))])
    front_length = _profile_length(body.sagittal_profile(True, waist_y, front_neck_y), waist_y, front_neck_y)
    back_length = _profile_length(body.sagittal_profile(False, waist_y, jy["neck"]), waist_y, jy["neck"])

    # neck base: the plane through the back and front neck points that holds the X axis
    normal = np.cross(_X, front_neck - c7)
    normal /= np.linalg.norm(normal)
    neck = body.girth(c7, normal, 0.5 * (c7 + front_neck))

    # narrowest neck: planes across the neck's axis (neck joint to head joint)
    neck_j, head_j = body.joint("neck"), body.joint("head")
    neck_axis = (head_j - neck_j) / np.linalg.norm(head_j - neck_j)

    def across_neck(t: float) -> float:
        point = neck_j + t * (head_j - neck_j)
        return body.girth(point, neck_axis, point)

    _, neck_narrowest = body.extreme_level(across_neck, 0.0, 0.8, 0.2, largest=False, what="the neck")

    # shoulder points: the top of the surface above each shoulder joint
    points = []
    for name in ("left_shoulder", "right_shoulder"):
        sj = body.joint(name)
        found = body.loop((sj[0], 0.0, 0.0), _X, sj)
        if found is None:
            raise InputError(f"no closed section around the {name.replace('_', ' ')} joint: is the body in a T-pose?")
        pts = found[0]
        near = pts[np.abs(pts[:, 2] - sj[2]) < 0.015]
        points.append(near[np.argmax(near[:, 1])])
    acromion_l, acromion_r = points
    shoulder_y = 0.5 * (acromion_l[1] + acromion_r[1])


    # shoulder width: across the back in the plane through both shoulder points and the back neck point
    normal = np.cross(acromion_l - c7, acromion_r - c7)
    normal /= np.linalg.norm(normal)
    basis = _basis(normal)
    pieces = body.cut(c7, normal)
    across = np.concatenate(pieces) if pieces else np.zeros((0, 3))
    half_x = 0.5 * (acromion_l[0] - acromion_r[0])
    mid_z = 0.5 * (acromion_l[2] + acromion_r[2])
    back_pts = across[(np.abs(across[:, 0]) <= half_x) & (across[:, 2] <= mid_z)]
    ends = np.stack([acromion_l, acromion_r])
    straight = float(np.linalg.norm(acromion_l - acromion_r))
    shoulder_width = _convex_chain_length(np.concatenate([back_pts, ends]) @ basis.T) - straight
    if not shoulder_width > straight:
        shoulder_width = straight

    # armhole: around the arm's root in the plane through the armpit and the shoulder point holding Z
    normal = np.cross(acromion_l - armpit, _Z)
    normal /= np.linalg.norm(normal)
    inside = 0.5 * (armpit + acromion_l)
    inside[2] = shoulder[2]
    found = body.loop(armpit, normal, inside)
    if found is None:
        raise InputError("no closed section around the arm's root: is the body in a T-pose?")
    root = found[0][found[0][:, 1] >= armpit[1] - 1e-3]
    armhole = _convex_chain_length(root @ _basis(normal).T)

    # limbs
    ua_x = 0.5 * (shoulder[0] + elbow[0])
    ua_inside = shoulder + (elbow - shoulder) * (ua_x - shoulder[0]) / (elbow[0] - shoulder[0])
    upper_arm = body.girth(ua_inside, _X, ua_inside)
    wrist_g = body.girth(wrist, _X, wrist)
    hip_j, knee_j, ankle_j = body.joint("left_hip"), body.joint("left_knee"), body.joint("left_ankle")

    def on_leg(y: float) -> np.ndarray:
        a, b = (hip_j, knee_j) if y >= knee_j[1] else (knee_j, ankle_j)
        return a + (b - a) * (y - a[1]) / (b[1] - a[1])

    thigh_y = crotch_y - 0.02
    thigh = body.horizontal_girth(thigh_y, on_leg(thigh_y))
    knee = body.horizontal_girth(knee_j[1], knee_j)
    _, ankle = body.extreme_level(lambda y: body.horizontal_girth(y, on_leg(y)), ankle_j[1] + 0.01,
                                  ankle_j[1] + 0.15, 0.03, largest=False, what="the ankle")
    arm_length = float(np.linalg.norm(acromion_l - wrist))

    h = lambda y: float(y - floor)  # noqa: E731
    return BodyMeasurements(
        height=float(v[:, 1].max() - floor),
        chest=chest, underbust=underbust, waist=waist, hip=hip, neck=neck, neck_narrowest=neck_narrowest, armhole=armhole,
        upper_arm=upper_arm, wrist=wrist_g, thigh=thigh, knee=knee, ankle=ankle,
        shoulder_width=shoulder_width, back_length=back_length, front_length=front_length,
        arm_length=arm_length, crotch_depth=waist_y - crotch_y, inseam=crotch_y - ankle_j[1],
        waist_height=h(waist_y), hip_height=h(hip_y), crotch_height=h(crotch_y), chest_height=h(chest_y),
        underbust_height=h(underbust_y), armpit_height=h(armpit_y), neck_height=h(jy["neck"]),
        front_neck_height=h(front_neck_y), shoulder_height=h(shoulder_y), knee_height=h(knee_j[1]),
        ankle_height=h(ankle_j[1]),
        shoulder_x=float(acromion_l[0]), armpit_x=float(armpit[0]), bust_x=float(abs(bust[0])),
        floor_y=floor, centre_z=centre_z,
    )


def measure_body(model: BodyModel, betas=None) -> BodyMeasurements:
    """:class:`BodyMeasurements` of ``model``'s body of shape ``betas`` ([S] or [1, S]; None:
    the mean shape), measured on its T-pose rest mesh (``model.shaped``) and joints
    (``model.rest_joints``). Deterministic; a few tens of ms (see docs/body.md)."""
    b = None if betas is None else np.asarray(betas, dtype=np.float64)
    if b is not None:
        if b.ndim > 2 or (b.ndim == 2 and b.shape[0] != 1):
            raise InputError(f"measure_body measures one shape: pass β as [S] or [1, S], got {b.shape}")
        b = b.reshape(1, -1)
        if b.shape[1] > model.shape_dim:
            raise InputError(f"{b.shape[1]} β values given; this body has {model.shape_dim}")
    if model.joint_count != len(SMPL_JOINT_NAMES):
        raise InputError(f"measure_body needs SMPL's 24 joints; this model has {model.joint_count}")
    rest = model.meta.get("rest_pose", "t-pose")
    if rest != "t-pose":
        raise InputError(f"measure_body measures T-posed bodies; this model's rest pose is '{rest}'")
    t0 = time.perf_counter()
    out = measure_mesh(model.shaped(b)[0], model.faces, model.rest_joints(b)[0])
    logger.debug("measured a body shape in %.0f ms", 1e3 * (time.perf_counter() - t0))
    return out
