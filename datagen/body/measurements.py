"""Body measurements of drape's SMPL-format body, for fitting sewing patterns to any shape.

:func:`measure_body` measures one body shape on its T-pose rest mesh (metres, Y up, facing +Z,
arms along ±X) from two kinds of landmark: SMPL's joints (``model.rest_joints``) and extremes of
the mesh (the armpit, the crotch, the widest hip, the narrowest waist), and plane sections of the
mesh. Girths are the perimeters of the convex hulls of plane sections, as a tape measure pulled
taut bridges the hollows (between the breasts, along the spine); heights are above the floor
(the lowest vertex, the soles).

Each section keeps one closed loop: the torso's is the loop whose hull contains the spine (so an
arm or a leg cut by the same plane is left out), a limb's is the loop whose hull contains the
limb's bone. The definitions of every field are in :class:`BodyMeasurements`; they follow
ISO 8559-1:2017 (anthropometric definitions for body measurement) where a T-pose allows.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np
from scipy.sparse import csr_matrix
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

    Girths (perimeter of the convex hull of a plane section, the length of a taut tape):
        chest: horizontal torso girth at ``chest_height``, the level of the largest torso girth
            below the armpits (ISO 8559-1 5.3.4 chest girth / 5.3.5 bust girth; arms excluded).
        underbust: horizontal torso girth at ``underbust_height``, below the breasts.
        waist: the smallest horizontal torso girth between the chest and the hip levels
            (the natural waist, ISO 8559-1 5.3.10).
        hip: the largest horizontal girth of the pelvis loop between the pelvis joint and the
            crotch (over the buttocks, ISO 8559-1 5.3.13).
        neck: the smallest horizontal girth of the neck between the neck and head joints.
        armhole: girth of the arm's root in the plane through the armpit and the shoulder point
            that holds the front-back axis (armscye, ISO 8559-1 5.3.16 in a T-pose).
        upper_arm: girth of the left arm in the plane across it (normal X) halfway from the
            shoulder joint to the elbow joint.
        wrist: girth of the left arm across it at the wrist joint.
        thigh: horizontal girth of the left leg 2 cm below the crotch.
        knee: horizontal girth of the left leg at the knee joint.
        ankle: the smallest horizontal girth of the left leg between the ankle joint and 15 cm
            above it.

    Lengths:
        height: vertical extent of the mesh (stature).
        shoulder_width: from one shoulder point to the other across the back, along the taut
            (convex) back curve of the section through both shoulder points and the back neck point.
        back_length: from the back neck point (C7: the midline back surface at the neck joint's
            height) down to the waist level, along the midline back surface.
        front_length: from the front neck point (the midline front surface at the neck joint's
            height, lowered to the jugular notch, see ``front_neck_height``) to the waist level,
            along the midline front surface.
        arm_length: straight distance from the shoulder point to the wrist joint (the arm is
            straight in a T-pose).
        crotch_depth: ``waist_height - crotch_height``.
        inseam: ``crotch_height - ankle_height`` (straight, vertical).

    Landmarks (heights above the floor; the shoulder point is the highest surface point above
    the shoulder joint):
        waist_height, hip_height, crotch_height (the lowest point of the torso between the legs:
        of the midline section's loop around the pelvis), chest_height, underbust_height,
        armpit_height (the highest level at which a horizontal section separates the torso from
        the arms), neck_height (the neck joint's), front_neck_height, shoulder_height (the
        shoulder point's), knee_height and ankle_height (the joints').
    """

    height: float
    chest: float
    underbust: float
    waist: float
    hip: float
    neck: float
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

    def __post_init__(self):
        bad = {k: v for k, v in asdict(self).items() if not (np.isfinite(v) and v > 0)}
        if bad:
            raise InputError(f"body measurements must be positive and finite; got {bad}: "
                             "is the body a T-posed human mesh in metres, Y up?")

    def as_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}


# ---------------------------------------------------------------------------------- sections
@dataclass(frozen=True)
class MeshTopology:
    """A triangle mesh's unique edges [E, 2] and the (up to) two faces of each edge [E, 2]
    (-1 where an edge has one face), for :func:`plane_loops`."""

    edges: np.ndarray
    edge_faces: np.ndarray

    @classmethod
    def of(cls, faces: np.ndarray) -> "MeshTopology":
        faces = np.asarray(faces, dtype=np.int64)
        F = len(faces)
        half = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        edges, inverse = np.unique(np.sort(half, axis=1), axis=0, return_inverse=True)
        inverse = inverse.ravel()
        owner = np.tile(np.arange(F), 3)
        order = np.argsort(inverse, kind="stable")
        counts = np.bincount(inverse, minlength=len(edges))
        first = np.concatenate([[0], np.cumsum(counts)[:-1]])
        edge_faces = np.full((len(edges), 2), -1, dtype=np.int64)
        edge_faces[:, 0] = owner[order[first]]
        two = counts >= 2
        edge_faces[two, 1] = owner[order[first[two] + 1]]
        return cls(edges=edges, edge_faces=edge_faces)


_TOPOLOGY: dict[int, tuple[object, MeshTopology]] = {}


def _topology(faces: np.ndarray) -> MeshTopology:
    """:class:`MeshTopology` of ``faces``, kept while the same array object lives (a body's
    faces do not change between shapes, so measuring many shapes builds it once)."""
    import weakref

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
    s = (vertices - np.asarray(origin, dtype=np.float64)) @ normal
    above = s >= 0
    e = topology.edges
    ids = np.flatnonzero(above[e[:, 0]] != above[e[:, 1]])
    if len(ids) == 0:
        return []
    n = len(ids)
    faces = topology.edge_faces[ids]
    keep = faces >= 0
    face_ids, face_node = np.unique(faces[keep], return_inverse=True)
    indptr = np.concatenate([[0], np.cumsum(keep.sum(axis=1)), np.full(len(face_ids), keep.sum())])
    graph = csr_matrix((np.ones(len(face_node)), n + face_node.ravel(), indptr), shape=(n + len(face_ids),) * 2)
    count, label = connected_components(graph, directed=False)
    label = label[:n]
    s0, s1 = s[e[ids, 0]], s[e[ids, 1]]
    t = s0 / (s0 - s1)
    p0, p1 = vertices[e[ids, 0]], vertices[e[ids, 1]]
    points = p0 + t[:, None] * (p1 - p0)
    order = np.argsort(label, kind="stable")
    splits = np.cumsum(np.bincount(label, minlength=count))[:-1]
    return [piece for piece in np.split(points[order], splits) if len(piece)]


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


def _contains(hull: ConvexHull, point2d: np.ndarray, tol: float = 1e-9) -> bool:
    return bool(np.all(hull.equations[:, :2] @ point2d + hull.equations[:, 2] <= tol))


def section_girth(vertices: np.ndarray, topology: _Topology, origin, normal, inside) -> float:
    """Perimeter [m] of the convex hull of the section loop whose hull contains ``inside`` [3]
    (a point of the plane inside the limb or torso to measure); NaN when no loop contains it."""
    loop = _loop_containing(vertices, topology, origin, normal, inside)
    return float("nan") if loop is None else float(loop[1].area)


def _loop_containing(vertices, topology, origin, normal, inside):
    """(points [n, 3], hull in the plane's 2D basis) of the loop around ``inside``, or None."""
    normal = np.asarray(normal, dtype=np.float64)
    basis = _basis(normal)
    p = basis @ np.asarray(inside, dtype=np.float64)
    for loop in plane_loops(vertices, topology, origin, normal):
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
        self._bands: dict[tuple[float, float], MeshTopology] = {}

    def joint(self, name: str) -> np.ndarray:
        return self.j[_J[name]]

    def axis(self, y: float) -> np.ndarray:
        """The point of the spine's joint chain (pelvis to head) at height ``y``, x = 0."""
        return np.array([0.0, y, float(np.interp(y, self._axis_y, self._axis_z))])

    def band(self, lo: float, hi: float) -> MeshTopology:
        """The topology restricted to edges that reach into [lo, hi] in y (faster horizontal cuts)."""
        key = (lo, hi)
        if key not in self._bands:
            e = self.topology.edges
            y0, y1 = self.v[e[:, 0], 1], self.v[e[:, 1], 1]
            keep = (np.maximum(y0, y1) >= lo) & (np.minimum(y0, y1) <= hi)
            self._bands[key] = MeshTopology(edges=e[keep], edge_faces=self.topology.edge_faces[keep])
        return self._bands[key]

    # -------------------------------------------------------------- sections
    def loop(self, origin, normal, inside, topology: MeshTopology | None = None):
        return _loop_containing(self.v, topology or self.topology, origin, normal, inside)

    def torso_loop(self, y: float, topology: MeshTopology | None = None):
        return self.loop((0.0, y, 0.0), _Y, self.axis(y), topology)

    def torso_girth(self, y: float, topology: MeshTopology | None = None) -> float:
        found = self.torso_loop(y, topology)
        return float("nan") if found is None else float(found[1].area)

    def horizontal_girth(self, y: float, inside, topology: MeshTopology | None = None) -> float:
        found = self.loop((0.0, y, 0.0), _Y, inside, topology)
        return float("nan") if found is None else float(found[1].area)

    def extreme_level(self, girth, lo: float, hi: float, step: float, largest: bool) -> tuple[float, float]:
        """(height, girth) of the smallest or largest ``girth(y)`` for y in [lo, hi]: a scan every
        ``step`` [m], then the vertex of the parabola through the best level and its neighbours."""
        ys = np.linspace(lo, hi, max(3, int(np.ceil((hi - lo) / step)) + 1))
        g = np.array([girth(y) for y in ys])
        if not np.isfinite(g).any():
            raise InputError(f"no closed section found between heights {lo - self.floor:.3f} and {hi - self.floor:.3f} m "
                             "above the floor: is this a T-posed human body in metres, Y up?")
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

    def sagittal_profile(self, front: bool, lo: float, hi: float) -> np.ndarray:
        """The midline (x = 0) section's front or back surface between heights lo and hi, as
        points [n, 2] (y, z) sorted by y; front/back is z above/below the spine's joint chain."""
        found = self.loop((0.0, 0.0, 0.0), _X, self.joint("spine2"))
        if found is None:
            raise InputError("the body's midline section does not enclose its spine: is the body facing +Z, Y up?")
        pts = found[0]
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

    # armpit: the highest level at which the torso's loop does not run out along the arms
    reach = 0.5 * (shoulder[0] + elbow[0])
    upper = body.band(jy["spine3"] - 0.01, jy["left_shoulder"] + 0.01)

    def separated(y: float) -> bool:
        found = body.torso_loop(y, upper)
        return found is not None and float(np.abs(found[0][:, 0]).max()) < reach

    lo, hi = jy["spine3"], jy["left_shoulder"]
    if not separated(lo):
        raise InputError("the torso's section at the chest joint already reaches the arms: is the body in a T-pose?")
    while hi - lo > 5e-4:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if separated(mid) else (lo, mid)
    armpit_y = lo
    torso_below = body.torso_loop(armpit_y, upper)[0]
    armpit = torso_below[np.argmax(torso_below[:, 0])]

    # bust point: the most prominent front point of the torso off the midline, below the armpits
    chest_lo = 0.5 * (jy["spine2"] + jy["spine3"])
    sel = ((v[:, 1] >= chest_lo) & (v[:, 1] <= armpit_y) & (np.abs(v[:, 0]) > 0.02)
           & (np.abs(v[:, 0]) < 0.8 * shoulder[0]))
    if not sel.any():
        raise InputError("no torso vertex between the chest joint and the armpits: is this a T-posed human body?")
    bust = v[sel][np.argmax(v[sel, 2])]
    chest_y = float(bust[1])
    chest = body.torso_girth(chest_y, body.band(chest_y - 0.01, chest_y + 0.01))

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
    underbust = body.torso_girth(underbust_y, body.band(underbust_y - 0.01, underbust_y + 0.01))

    # crotch: the lowest point of the midline section's loop around the torso
    mid_loop = body.loop((0.0, 0.0, 0.0), _X, body.joint("spine2"))
    if mid_loop is None:
        raise InputError("the body's midline section does not enclose its spine: is the body facing +Z, Y up?")
    crotch_y = float(mid_loop[0][:, 1].min())

    # hip: the largest girth between the crotch and the pelvis joint
    lower = body.band(crotch_y, jy["spine3"])
    hip_y, hip = body.extreme_level(lambda y: body.torso_girth(y, lower), crotch_y + 0.01, jy["pelvis"], 0.01, largest=True)

    # natural waist: the smallest torso girth between the spine1 joint and halfway to the chest joint
    waist_y, waist = body.extreme_level(lambda y: body.torso_girth(y, lower), jy["spine1"], chest_lo, 0.015, largest=False)

    # neck: the smallest girth between the neck and head joints
    neck_band = body.band(jy["neck"], jy["head"])
    _, neck = body.extreme_level(lambda y: body.torso_girth(y, neck_band), jy["neck"], jy["head"], 0.01, largest=False)

    # front neck point: the most posterior point of the midline front profile between armpits and neck joint
    front = body.sagittal_profile(True, armpit_y, jy["neck"])
    if len(front) < 3:
        raise InputError("the body's midline front profile between the armpits and the neck is empty")
    front_neck_y = float(front[np.argmin(front[:, 1]), 0])
    front_length = _profile_length(body.sagittal_profile(True, waist_y, front_neck_y), waist_y, front_neck_y)
    back_length = _profile_length(body.sagittal_profile(False, waist_y, jy["neck"]), waist_y, jy["neck"])

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
    back_neck = body.sagittal_profile(False, jy["neck"] - 0.02, jy["neck"] + 0.02)
    c7 = np.array([0.0, jy["neck"], float(np.interp(jy["neck"], back_neck[:, 0], back_neck[:, 1]))])
    normal = np.cross(acromion_l - c7, acromion_r - c7)
    normal /= np.linalg.norm(normal)
    basis = _basis(normal)
    pieces = plane_loops(v, body.topology, c7, normal)
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
    upper_arm = section_girth(v, body.topology, ua_inside, _X, ua_inside)
    wrist_g = section_girth(v, body.topology, wrist, _X, wrist)
    hip_j, knee_j, ankle_j = body.joint("left_hip"), body.joint("left_knee"), body.joint("left_ankle")

    def on_leg(y: float) -> np.ndarray:
        a, b = (hip_j, knee_j) if y >= knee_j[1] else (knee_j, ankle_j)
        return a + (b - a) * (y - a[1]) / (b[1] - a[1])

    thigh_y = crotch_y - 0.02
    thigh = body.horizontal_girth(thigh_y, on_leg(thigh_y))
    knee = body.horizontal_girth(knee_j[1], knee_j)
    legs = body.band(ankle_j[1], ankle_j[1] + 0.16)
    _, ankle = body.extreme_level(lambda y: body.horizontal_girth(y, on_leg(y), legs), ankle_j[1] + 0.01,
                                  ankle_j[1] + 0.15, 0.02, largest=False)
    arm_length = float(np.linalg.norm(acromion_l - wrist))

    h = lambda y: float(y - floor)  # noqa: E731
    return BodyMeasurements(
        height=float(v[:, 1].max() - floor),
        chest=chest, underbust=underbust, waist=waist, hip=hip, neck=neck, armhole=armhole,
        upper_arm=upper_arm, wrist=wrist_g, thigh=thigh, knee=knee, ankle=ankle,
        shoulder_width=shoulder_width, back_length=back_length, front_length=front_length,
        arm_length=arm_length, crotch_depth=waist_y - crotch_y, inseam=crotch_y - ankle_j[1],
        waist_height=h(waist_y), hip_height=h(hip_y), crotch_height=h(crotch_y), chest_height=h(chest_y),
        underbust_height=h(underbust_y), armpit_height=h(armpit_y), neck_height=h(jy["neck"]),
        front_neck_height=h(front_neck_y), shoulder_height=h(shoulder_y), knee_height=h(knee_j[1]),
        ankle_height=h(ankle_j[1]),
    )


def measure_body(model: BodyModel, betas=None) -> BodyMeasurements:
    """:class:`BodyMeasurements` of ``model``'s body of shape ``betas`` ([S] or [1, S]; None:
    the mean shape), measured on its T-pose rest mesh (``model.shaped``) and joints
    (``model.rest_joints``). Deterministic; a few tens of ms (see docs/body.md)."""
    b = None if betas is None else np.asarray(betas, dtype=np.float64).reshape(1, -1)
    if b is not None and b.shape[1] > model.shape_dim:
        raise InputError(f"{b.shape[1]} β values given; this body has {model.shape_dim}")
    if model.joint_count != len(SMPL_JOINT_NAMES):
        raise InputError(f"measure_body needs SMPL's 24 joints; this model has {model.joint_count}")
    rest = model.meta.get("rest_pose", "t-pose")
    if rest != "t-pose":
        raise InputError(f"measure_body measures T-posed bodies; this model's rest pose is '{rest}'")
    return measure_mesh(model.shaped(b)[0], model.faces, model.rest_joints(b)[0])
