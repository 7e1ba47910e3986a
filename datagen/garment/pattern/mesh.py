"""Flat meshing of a sewing pattern: every panel triangulated in 2D at a target edge length.

1. **Seams first.** Each stitch's two sides are resampled to the same number of points: the corners
   of both sides (their edges' ends, as fractions of the side's arc length in sewing order) are
   breakpoints, two corners closer than half the target length merge, and every interval
   between breakpoints gets ``round(length / edge_length)`` (>= 1) equal segments on both sides.
   So vertex ``k`` of one side is sewn to vertex ``k`` of the other (``N - k`` when the stitch is
   reversed). Free edges get ``round(length / edge_length)`` (>= 1) equal segments.
2. **Panels.** The boundary points and an equilateral (hex) lattice of interior points aligned with
   the panel's grain, trimmed to at least half an edge length inside the outline, are Delaunay-
   triangulated (scipy/Qhull, BSD; four far points keep the outline off the convex hull, so no
   collinear boundary point is dropped). Boundary segments the Delaunay triangulation lacks (the
   apex of a narrow dart) are recovered by edge flips (Sloan's method), the triangles outside the
   outline dropped, the interior points moved by damped Laplacian smoothing (connectivity fixed) and
   the whole triangulated again. Boundary segments shorter than 0.3 of the edge length (the
   1 mm edges GarmentCode's construction leaves) are collapsed to one vertex first.

Why this route: the permissive constrained meshers with quality guarantees (Triangle, CGAL, gmsh) are
not licence-clean (non-commercial/GPL); pymeshlab's isotropic remeshing moves and resamples the
boundary, which must stay exactly where the seams were resampled. A grain-aligned lattice is
near-equilateral by construction; only the band along the outline needs the smoothing. Measured
quality (``benchmarks/pattern_survey.py``, docs/patterns.md): minimum angle and edge-length spread
per garment.

Every vertex keeps its 2D panel coordinate (the rest state and a UV), its panel, and the vertices it
is sewn to (:attr:`FlatPatternMesh.stitch_pairs`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import Delaunay, cKDTree

from datagen.errors import InputError
from datagen.garment.pattern.model import Panel, Pattern

__all__ = ["FlatPatternMesh", "MeshQuality", "mesh_pattern", "mesh_quality", "triangulate_polygon"]

log = logging.getLogger(__name__)

MIN_EDGE_LENGTH = 0.003
"""Finest target edge length [m] (a garment of 3 mm edges has hundreds of thousands of vertices)."""

_MERGE = 0.5
"""Two seam corners closer than this share of the edge length become one breakpoint."""
_INSET = 0.5
"""Interior lattice points keep at least this share of the edge length from the outline."""
_SMOOTHING = 6
"""Laplacian smoothing passes of the interior points."""
_COLLAPSE = 0.3
"""Boundary segments shorter than this share of the edge length collapse to one vertex."""


@dataclass(frozen=True, eq=False)
class FlatPatternMesh:
    """The pattern's panels as one triangle mesh in panel space (panels not welded).

    Attributes:
        pattern: the :class:`Pattern` meshed.
        edge_length: the target edge length [m].
        rest_uv: 2D panel coordinate of every vertex [V, 2] [m] (the flat rest state).
        panel_id: panel index per vertex [V] (into ``pattern.panels``).
        faces: triangles [F, 3], counter-clockwise in panel space (normals out of the garment).
        face_panel: panel index per face [F].
        stitch_pairs: sewn vertex pairs [P, 2] (a vertex at a seam's corner can be in several).
        stitch_of_pair: which of ``pattern.stitches`` each pair belongs to [P].
        edge_vertices: ``(panel index, edge index) -> vertex ids`` along that edge, start to end.
    """

    pattern: Pattern
    edge_length: float
    rest_uv: np.ndarray
    panel_id: np.ndarray
    faces: np.ndarray
    face_panel: np.ndarray
    stitch_pairs: np.ndarray
    stitch_of_pair: np.ndarray
    edge_vertices: dict[tuple[int, int], np.ndarray]

    @property
    def vertex_count(self) -> int:
        return len(self.rest_uv)

    def stitch_partner(self) -> np.ndarray:
        """One vertex each vertex is sewn to, or -1 [V] (see ``stitch_pairs`` for all)."""
        out = np.full(len(self.rest_uv), -1, dtype=np.int64)
        out[self.stitch_pairs[:, 1]] = self.stitch_pairs[:, 0]
        out[self.stitch_pairs[:, 0]] = self.stitch_pairs[:, 1]
        return out

    def face_grain(self) -> np.ndarray:
        """The warp direction of every face in panel space [F, 2] (its panel's grain)."""
        grains = np.array([p.grain for p in self.pattern.panels], dtype=float)
        return grains[self.face_panel]


@dataclass(frozen=True, kw_only=True)
class MeshQuality:
    """Triangle quality of a flat mesh: angles [degrees], edge lengths relative to their median."""

    min_angle: float
    angle_p1: float             # 1st percentile of all angles
    edge_median: float          # [m]
    edge_spread: float          # (95th - 5th percentile) / median of the edge lengths
    edge_min_ratio: float       # shortest / median
    edge_max_ratio: float       # longest / median


def mesh_quality(rest_uv: np.ndarray, faces: np.ndarray) -> MeshQuality:
    """:class:`MeshQuality` of triangles ``faces`` [F, 3] on points ``rest_uv`` [V, 2]."""
    tri = rest_uv[faces]
    e = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1], tri[:, 0] - tri[:, 2]], axis=1)
    length = np.linalg.norm(e, axis=2)
    ang = []
    for k in range(3):
        a, b = -e[:, (k + 2) % 3], e[:, k]
        cos = np.einsum("ij,ij->i", a, b) / (length[:, (k + 2) % 3] * length[:, k] + 1e-30)
        ang.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    ang = np.concatenate(ang)
    key = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, first = np.unique(key, axis=0, return_index=True)
    lens = np.concatenate([length[:, 0], length[:, 1], length[:, 2]])[first]
    med = float(np.median(lens))
    p5, p95 = np.percentile(lens, [5, 95])
    return MeshQuality(min_angle=float(ang.min()), angle_p1=float(np.percentile(ang, 1)), edge_median=med,
                       edge_spread=float((p95 - p5) / med), edge_min_ratio=float(lens.min() / med),
                       edge_max_ratio=float(lens.max() / med))


# ---------------------------------------------------------------- seams: equal counts on both sides

def _side_corners(pattern: Pattern, side) -> tuple[np.ndarray, float]:
    """Cumulative arc-length fractions [len(edges) + 1] of a side's edge ends, and its length [m]."""
    p = pattern.panel(side.panel)
    lengths = np.array([p.edge_length(i) for i in side.edges])
    total = float(lengths.sum())
    return np.concatenate([[0.0], np.cumsum(lengths) / total]), total


def _seam_fractions(pattern: Pattern, stitch, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Matching arc-length fractions [N + 1] along side a and side b (b in sewing order)."""
    ca, la = _side_corners(pattern, stitch.a)
    cb, lb = _side_corners(pattern, stitch.b)
    if stitch.reversed:
        cb = 1.0 - cb[::-1]
    mean_len = (la + lb) / 2
    # breakpoints: (fraction on a, fraction on b, is a corner of a, is a corner of b)
    pts = [(f, f, True, False) for f in ca[1:-1]] + [(f, f, False, True) for f in cb[1:-1]]
    pts.sort(key=lambda x: x[0])
    merged: list[list] = [[0.0, 0.0, True, True]]
    for fa, fb, is_a, is_b in pts:
        last = merged[-1]
        close = (fa - last[0]) * mean_len < _MERGE * h
        if close and ((is_a and not last[2]) or (is_b and not last[3])):
            if is_a:
                last[0], last[2] = fa, True
            else:
                last[1], last[3] = fb, True
        else:
            merged.append([fa, fb, is_a, is_b])
    merged.append([1.0, 1.0, True, True])
    fa_out, fb_out = [0.0], [0.0]
    for (a0, b0, *_), (a1, b1, *_) in zip(merged[:-1], merged[1:]):
        seg = ((a1 - a0) * la + (b1 - b0) * lb) / 2
        n = max(1, int(round(seg / h)))
        t = np.arange(1, n + 1) / n
        fa_out += list(a0 + (a1 - a0) * t)
        fb_out += list(b0 + (b1 - b0) * t)
    fa, fb = np.array(fa_out), np.array(fb_out)
    if np.any(np.diff(fa) <= 0) or np.any(np.diff(fb) <= 0):
        raise InputError(f"pattern '{pattern.name}': {stitch.describe()}: its corners cannot be matched at edge "
                         f"length {h:g} m; try a smaller edge length")
    if stitch.reversed:
        fb = 1.0 - fb[::-1]  # back to b's loop order
    return fa, fb


def _split_side(corners: np.ndarray, fractions: np.ndarray, edges: tuple[int, ...]) -> dict[int, np.ndarray]:
    """Side fractions -> per-edge local fractions (each including 0 and 1)."""
    out = {}
    for k, e in enumerate(edges):
        lo, hi = corners[k], corners[k + 1]
        i0 = int(np.argmin(np.abs(fractions - lo)))
        i1 = int(np.argmin(np.abs(fractions - hi)))
        local = (fractions[i0:i1 + 1] - lo) / (hi - lo)
        local[0], local[-1] = 0.0, 1.0
        out[e] = local
    return out


def _edge_fractions(pattern: Pattern, h: float) -> dict[tuple[int, int], np.ndarray]:
    """Arc-length fractions of the vertices on every edge, seams matched across their stitches."""
    fr: dict[tuple[int, int], np.ndarray] = {}
    for stitch in pattern.stitches:
        fa, fb = _seam_fractions(pattern, stitch, h)
        for side, f in ((stitch.a, fa), (stitch.b, fb)):
            corners, _ = _side_corners(pattern, side)
            pi = pattern.panel_index(side.panel)
            for e, local in _split_side(corners, f, side.edges).items():
                fr[(pi, e)] = local
    for pi, p in enumerate(pattern.panels):
        for e in range(len(p.edges)):
            if (pi, e) not in fr:
                n = max(1, int(round(p.edge_length(e) / h)))
                fr[(pi, e)] = np.linspace(0.0, 1.0, n + 1)
    return fr


# ---------------------------------------------------------------- 2D triangulation of one panel

def _orient(a, b, c) -> np.ndarray:
    return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])


def _inside(poly: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Crossing-number point-in-polygon for points [M, 2] and a closed polygon [N, 2]."""
    a, b = poly, np.roll(poly, -1, axis=0)
    x, y = pts[:, 0:1], pts[:, 1:2]
    cond = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
    return (np.count_nonzero(cond & (x < xc), axis=1) % 2) == 1


def _distance_to_polygon(poly: np.ndarray, pts: np.ndarray, h: float) -> np.ndarray:
    """Distance from points [M, 2] to the closed polygon [N, 2], to within h / 16."""
    a, b = poly, np.roll(poly, -1, axis=0)
    n = np.maximum(np.ceil(np.linalg.norm(b - a, axis=1) / (h / 8)).astype(int), 1)
    t = np.concatenate([np.arange(k) / k for k in n])
    seg = np.repeat(np.arange(len(a)), n)
    dense = a[seg] + t[:, None] * (b - a)[seg]
    return cKDTree(dense).query(pts)[0]


def _hex_lattice(poly: np.ndarray, h: float, grain: np.ndarray) -> np.ndarray:
    """Points of an equilateral lattice of spacing ``h`` aligned with ``grain``, covering ``poly``'s box."""
    warp = grain / np.linalg.norm(grain)
    weft = np.array([warp[1], -warp[0]])
    c = poly.mean(axis=0)
    local = (poly - c) @ np.stack([weft, warp], axis=1)
    lo, hi = local.min(axis=0) - h, local.max(axis=0) + h
    row = h * math.sqrt(3) / 2
    js = np.arange(math.floor(lo[1] / row), math.ceil(hi[1] / row) + 1)
    is_ = np.arange(math.floor(lo[0] / h) - 1, math.ceil(hi[0] / h) + 2)
    I, J = np.meshgrid(is_, js)
    u = (I + 0.5 * (J % 2)) * h
    v = J * row
    pts = np.stack([u.ravel(), v.ravel()], axis=1)
    return c + pts[:, 0:1] * weft + pts[:, 1:2] * warp


def _recover_segments(tri: np.ndarray, pts: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Flip edges until every segment (u, v) is an edge of the triangulation (Sloan 1993)."""
    tris = [list(t) for t in tri]
    edge_tris: dict[tuple[int, int], set[int]] = {}

    def key(a, b):
        return (a, b) if a < b else (b, a)

    def add(ti):
        t = tris[ti]
        for k in range(3):
            edge_tris.setdefault(key(t[k], t[(k + 1) % 3]), set()).add(ti)

    def remove(ti):
        t = tris[ti]
        for k in range(3):
            edge_tris[key(t[k], t[(k + 1) % 3])].discard(ti)

    for ti in range(len(tris)):
        add(ti)

    def crosses(a, b, u, v):
        if len({a, b, u, v}) < 4:
            return False
        pa, pb, pu, pv = pts[a], pts[b], pts[u], pts[v]
        return (_orient(pu, pv, pa) * _orient(pu, pv, pb) < 0) and (_orient(pa, pb, pu) * _orient(pa, pb, pv) < 0)

    for u, v in segments:
        u, v = int(u), int(v)
        if edge_tris.get(key(u, v)):
            continue
        crossing = [e for e, ts in edge_tris.items() if ts and crosses(e[0], e[1], u, v)]
        guard = 0
        while crossing:
            guard += 1
            if guard > 20 * len(crossing) + 1000:
                raise InputError("a panel's outline could not be recovered in its triangulation (the outline "
                                 "nearly touches itself); try a smaller edge length")
            a, b = crossing.pop(0)
            ts = list(edge_tris.get(key(a, b), ()))
            if len(ts) != 2:
                continue
            t0, t1 = ts
            c = [x for x in tris[t0] if x not in (a, b)][0]
            d = [x for x in tris[t1] if x not in (a, b)][0]
            # the quad a-c-b-d is convex iff c and d lie on opposite sides of ab and a and b of cd
            if not (_orient(pts[a], pts[b], pts[c]) * _orient(pts[a], pts[b], pts[d]) < 0
                    and _orient(pts[c], pts[d], pts[a]) * _orient(pts[c], pts[d], pts[b]) < 0):
                crossing.append((a, b))
                continue
            remove(t0)
            remove(t1)
            # new triangles (c, d, a) and (d, c, b), counter-clockwise
            n0 = [c, d, a] if _orient(pts[c], pts[d], pts[a]) > 0 else [d, c, a]
            n1 = [c, d, b] if _orient(pts[c], pts[d], pts[b]) > 0 else [d, c, b]
            tris[t0], tris[t1] = n0, n1
            add(t0)
            add(t1)
            if crosses(c, d, u, v):
                crossing.append(key(c, d))
    return np.array(tris, dtype=np.int64)


def _triangulate(points: np.ndarray, nb: int) -> np.ndarray:
    """Triangles inside the outline made of the first ``nb`` points (a closed CCW loop)."""
    poly = points[:nb]
    span = float(np.ptp(points, axis=0).max())
    c = points.mean(axis=0)
    far = c + 10 * span * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    allp = np.concatenate([points, far])
    tri = Delaunay(allp, qhull_options="Qbb Qc Qz").simplices.astype(np.int64)
    # counter-clockwise
    flip = _orient(allp[tri[:, 0]], allp[tri[:, 1]], allp[tri[:, 2]]) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    seg = np.stack([np.arange(nb), (np.arange(nb) + 1) % nb], axis=1)
    m = len(allp)
    have = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    want = np.sort(seg, axis=1)
    missing = ~np.isin(want[:, 0] * m + want[:, 1], have[:, 0] * m + have[:, 1])
    if missing.any():
        tri = _recover_segments(tri, allp, seg[missing])
    tri = tri[(tri < len(points)).all(axis=1)]
    # every outline segment is an edge now, so no triangle straddles the outline: its centroid decides
    centroid = allp[tri].mean(axis=1)
    return tri[_inside(poly, centroid)]


def triangulate_polygon(boundary: np.ndarray, h: float, grain=(0.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate the closed counter-clockwise ``boundary`` [nb, 2] keeping its points and segments.

    Returns points [V, 2] (the boundary first, in order, then the interior) and CCW faces [F, 3]."""
    boundary = np.asarray(boundary, dtype=float)
    nb = len(boundary)
    lattice = _hex_lattice(boundary, h, np.asarray(grain, float))
    lattice = lattice[_inside(boundary, lattice)]
    if len(lattice):
        lattice = lattice[_distance_to_polygon(boundary, lattice, h) >= _INSET * h]
    pts = np.concatenate([boundary, lattice])
    faces = _triangulate(pts, nb)
    if len(lattice) and _SMOOTHING:
        e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        e = np.concatenate([e, e[:, ::-1]])
        deg = np.maximum(np.bincount(e[:, 0], minlength=len(pts)), 1)[:, None]
        for _ in range(_SMOOTHING):
            acc = np.zeros_like(pts)
            np.add.at(acc, e[:, 0], pts[e[:, 1]])
            moved = pts.copy()
            moved[nb:] = 0.5 * pts[nb:] + 0.5 * (acc / deg)[nb:]  # damped Laplacian, interior points only
            ok = np.ones(len(pts), bool)
            ok[nb:] = _inside(boundary, moved[nb:]) & (_distance_to_polygon(boundary, moved[nb:], h) >= 0.3 * h)
            pts = np.where(ok[:, None], moved, pts)
        faces = _triangulate(pts, nb)
    # drop interior points no triangle uses (cannot happen for a valid triangulation, kept as a guard)
    used = np.zeros(len(pts), bool)
    used[faces.ravel()] = True
    if not used[:nb].all():
        raise InputError("a panel's outline is not fully triangulated (the outline nearly touches itself); "
                         "try a smaller edge length")
    if not used.all():
        remap = np.cumsum(used) - 1
        pts, faces = pts[used], remap[faces]
    return pts, faces


def _collapse_short(boundary: np.ndarray, corners: set[int], limit: float) -> tuple[np.ndarray, np.ndarray]:
    """Merge consecutive boundary points closer than ``limit`` (onto the pattern corner if one is).

    Returns the new boundary and the map old index -> new index."""
    n = len(boundary)
    group = np.arange(n)
    keep_pos = boundary.copy()
    for i in range(n):
        j = (i + 1) % n
        if j == 0 or n - len(set(group.tolist())) >= n - 3:
            break
        if np.linalg.norm(boundary[j] - boundary[i]) < limit and np.linalg.norm(keep_pos[group[i]] - boundary[j]) < limit:
            g = group[i]
            group[j] = g
            if j in corners and g not in corners:
                keep_pos[g] = boundary[j]
            elif j in corners and g in corners:
                keep_pos[g] = (boundary[j] + keep_pos[g]) / 2
    # the last point may be close to the first
    if n > 3 and group[n - 1] != group[0] and np.linalg.norm(boundary[n - 1] - boundary[0]) < limit:
        g_last = group[n - 1]
        group[group == g_last] = 0
    uniq, remap = np.unique(group, return_inverse=True)
    return keep_pos[uniq], remap


def _panel_mesh(panel: Panel, fracs: dict[int, np.ndarray], h: float) -> tuple[np.ndarray, np.ndarray, dict[int, np.ndarray]]:
    """Points [V, 2], faces and per-edge vertex ids (local) of one panel."""
    parts, edge_ids, n = [], {}, 0
    for e, edge in enumerate(panel.edges):
        pts = edge.points_at(panel, fracs[e])
        parts.append(pts[:-1])
        edge_ids[e] = np.arange(n, n + len(pts))
        n += len(pts) - 1
    boundary = np.concatenate(parts)
    nb = len(boundary)
    for e in edge_ids:
        edge_ids[e] = edge_ids[e] % nb  # the last edge ends at vertex 0
    boundary, remap = _collapse_short(boundary, {int(ids[0]) for ids in edge_ids.values()}, _COLLAPSE * h)
    edge_ids = {e: remap[ids] for e, ids in edge_ids.items()}
    try:
        pts, faces = triangulate_polygon(boundary, h, panel.grain)
    except InputError as exc:
        raise InputError(f"panel '{panel.name}': {exc}") from None
    return pts, faces, edge_ids


def mesh_pattern(pattern: Pattern, edge_length: float = 0.02) -> FlatPatternMesh:
    """Triangulate every panel of ``pattern`` at ``edge_length`` [m] with its seams matched (module doc)."""
    h = float(edge_length)
    if not (math.isfinite(h) and MIN_EDGE_LENGTH <= h <= 0.2):
        raise InputError(f"a pattern is meshed at an edge length between {MIN_EDGE_LENGTH} and 0.2 m, got {edge_length!r}")
    fracs = _edge_fractions(pattern, h)
    uv, pid, faces, fpanel, edge_vertices = [], [], [], [], {}
    offset = 0
    for pi, panel in enumerate(pattern.panels):
        pts, f, eids = _panel_mesh(panel, {e: fracs[(pi, e)] for e in range(len(panel.edges))}, h)
        uv.append(pts)
        pid.append(np.full(len(pts), pi, dtype=np.int32))
        faces.append(f + offset)
        fpanel.append(np.full(len(f), pi, dtype=np.int32))
        for e, ids in eids.items():
            edge_vertices[(pi, e)] = ids + offset
        offset += len(pts)
    pairs, owner = [], []
    for k, st in enumerate(pattern.stitches):
        sides = []
        for side in (st.a, st.b):
            pi = pattern.panel_index(side.panel)
            ids = np.concatenate([edge_vertices[(pi, e)][:-1] for e in side.edges]
                                 + [edge_vertices[(pi, side.edges[-1])][-1:]])
            sides.append(ids)
        a, b = sides
        if st.reversed:
            b = b[::-1]
        if len(a) != len(b):  # the seam resampling guarantees equal counts
            raise InputError(f"pattern '{pattern.name}': {st.describe()}: {len(a)} and {len(b)} vertices")
        pair = np.stack([a, b], axis=1)
        pair = pair[pair[:, 0] != pair[:, 1]]  # a dart's apex is sewn to itself
        pair = np.unique(pair, axis=0)  # a collapsed short edge repeats its pair
        pairs.append(pair)
        owner.append(np.full(len(pair), k, dtype=np.int32))
    return FlatPatternMesh(
        pattern=pattern, edge_length=h, rest_uv=np.concatenate(uv), panel_id=np.concatenate(pid),
        faces=np.concatenate(faces).astype(np.int64), face_panel=np.concatenate(fpanel),
        stitch_pairs=np.concatenate(pairs).astype(np.int64) if pairs else np.zeros((0, 2), np.int64),
        stitch_of_pair=np.concatenate(owner) if owner else np.zeros(0, np.int32), edge_vertices=edge_vertices)
