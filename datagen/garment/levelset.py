"""Garment surfaces as level sets around the body, cut open and remeshed isotropically.

A garment's inside is ``{x : F(x) < 0}`` with ``F = smin(d_body(x) - ease(x), F_extra(x))``: the
body's signed distance (negative inside, from a warp mesh query with winding-number sign) minus a
clearance that varies over the body, smoothly united with shapes that leave the body (the cone of
a skirt). Its surface is extracted by marching cubes (scikit-image) on a grid covering only the
garment's extent, cut open by scalar fields (keep where ``c(x) > 0``; the cut runs exactly along
``c = 0``), reduced to its largest component, and remeshed to a target edge length by pymeshlab's
isotropic explicit remeshing, which reprojects onto the extracted surface and keeps the open
boundaries.
"""

from __future__ import annotations

import numpy as np

from datagen.geometry.topology import unique_edges

__all__ = ["apply_meshlab_filter", "body_sdf", "collapse_short_edges", "cut_mesh", "extract_surface",
           "largest_component", "remesh", "smin"]


def apply_meshlab_filter(ms, name: str, **params) -> None:
    """Run the pymeshlab filter ``name`` on ``ms`` with every one of its parameters given.

    A parameter left to pymeshlab's default is not safe: the default of ``checksurfdist`` in
    isotropic explicit remeshing (pymeshlab 2025.7) is read from uninitialised memory, so the same
    input remeshed to 935 vertices with pymeshlab imported from one directory and to 1,104 from
    another. A filter whose parameter is missing here is refused, so a pymeshlab release that adds
    one fails loudly instead of changing the garments.
    """
    wanted = set(ms.filter_parameter_values(name))
    missing, unknown = sorted(wanted - set(params)), sorted(set(params) - wanted)
    if missing or unknown:
        raise RuntimeError(f"pymeshlab filter {name}: parameter(s) {missing} not given and {unknown} not known to "
                           "this pymeshlab; every parameter is passed explicitly (its defaults are not reliable): "
                           "update the call in datagen/garment/levelset.py for this pymeshlab version")
    getattr(ms, name)(**params)


def body_sdf(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray, max_dist: float = 0.25) -> np.ndarray:
    """Signed distance [N] (m; negative inside) of ``points`` [N, 3] to the closed mesh
    (``vertices`` [V, 3], ``faces`` [F, 3]); points farther than ``max_dist`` get ``max_dist``.

    The sign comes from the generalised winding number of the nearest face found within
    ``max_dist``, so ``max_dist`` must exceed the depth of the deepest point inside the mesh
    (a human trunk: 0.11 m for the regular body, 0.15 m at BMI 31; default 0.25 m, which is about
    twice as fast on the garment grids as searching 0.5 m and gives the same signs there).
    """
    from datagen.geometry.queries import mesh_signed_distance, warp_mesh

    return mesh_signed_distance(warp_mesh(vertices, faces, "cpu"), points, max_dist).astype(np.float64)


def smin(a: np.ndarray, b: np.ndarray, k: float) -> np.ndarray:
    """Smooth minimum (polynomial, blend width ``k`` m): the union of two implicit shapes."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b * (1 - h) + a * h - k * h * (1 - h)


def extract_surface(field, lo: np.ndarray, hi: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Marching cubes of ``field(points [N, 3]) -> [N]`` at level 0 over the box [lo, hi] (m).

    Returns vertices [V, 3] (m) and faces [F, 3] with normals pointing toward positive ``field``
    (outward for an inside-negative field).
    """
    from skimage.measure import marching_cubes

    axes = [np.arange(lo[i], hi[i] + spacing, spacing) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    values = field(grid.reshape(-1, 3)).reshape(grid.shape[:3])
    # the box border counts as outside, so the surface closes where it meets the box (the cuts
    # that open the garment lie inside the box, so those caps are cut away)
    for axis in range(3):
        index = [slice(None)] * 3
        for end in (0, -1):
            index[axis] = end
            values[tuple(index)] = spacing
    verts, faces, _, _ = marching_cubes(values, level=0.0, spacing=(spacing, spacing, spacing))
    verts += lo
    # skimage's winding already faces increasing values (checked on a sphere: normals point out of
    # an inside-negative field), so the faces are kept as they come
    return verts, faces.astype(np.int64)


def cut_mesh(vertices: np.ndarray, faces: np.ndarray, keep: np.ndarray, snap: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Cut a triangle mesh along the zero level of a per-vertex scalar ``keep`` [V]; keep ``> 0``.

    Every edge whose ends have opposite signs gets one new vertex at the linear zero crossing
    (shared by both triangles of the edge), so the cut is watertight along its curve. Triangles
    with one kept corner become one triangle, with two kept corners two. A vertex within
    ``snap`` of the level counts as on it (the cut passes through it), which avoids slivers.
    """
    s = np.asarray(keep, dtype=np.float64).copy()
    on = np.abs(s) <= max(snap, 1e-12)
    s[on] = 0.0
    pos = s >= 0.0  # on-cut vertices are kept
    npos = pos[faces].sum(1)
    keep_all = faces[npos == 3]
    partial = faces[(npos == 1) | (npos == 2)]
    new_verts = [vertices]
    edge_vertex: dict[tuple[int, int], int] = {}
    count = len(vertices)

    def crossing(a: int, b: int) -> int:
        nonlocal count
        if s[a] == 0.0:
            return a
        if s[b] == 0.0:
            return b
        key = (a, b) if a < b else (b, a)
        idx = edge_vertex.get(key)
        if idx is None:
            t = s[a] / (s[a] - s[b])
            new_verts.append((vertices[a] + t * (vertices[b] - vertices[a]))[None])
            idx = edge_vertex[key] = count
            count += 1
        return idx

    out = [keep_all]
    tris = []
    for f in partial:
        p = pos[f]
        # rotate so the odd corner (the lone kept or the lone dropped one) comes first
        k = int(np.flatnonzero(p == (p.sum() == 1))[0])
        a, b, c = f[k], f[(k + 1) % 3], f[(k + 2) % 3]
        ab, ac = crossing(a, b), crossing(a, c)
        if p.sum() == 1:  # only a kept
            tris.append((a, ab, ac))
        else:  # a dropped, b and c kept
            tris.append((ab, b, c))
            tris.append((ab, c, ac))
    if tris:
        t = np.asarray(tris, dtype=np.int64)
        t = t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])]  # drop collapsed ones
        out.append(t)
    faces_out = np.concatenate(out)
    # a triangle whose corners are all on the cut lies in the cut itself: drop it
    faces_out = faces_out[~on[np.minimum(faces_out, len(on) - 1)].all(1) | (faces_out >= len(on)).any(1)]
    verts_out = np.concatenate(new_verts)
    used = np.unique(faces_out)
    remap = np.full(len(verts_out), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return verts_out[used], remap[faces_out]


def largest_component(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The connected component (by shared edges) with the most faces."""
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    parts = mesh.split(only_watertight=False)
    if len(parts) <= 1:
        return vertices, faces
    best = max(parts, key=lambda m: len(m.faces))
    return np.asarray(best.vertices), np.asarray(best.faces)


def close_small_holes(vertices: np.ndarray, faces: np.ndarray, max_edges: int) -> tuple[np.ndarray, np.ndarray]:
    """Fill holes bounded by at most ``max_edges`` edges (pymeshlab), the pin-holes a cut can leave
    where its field only grazes the surface; every opening of a garment is far longer."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int32)))
    apply_meshlab_filter(ms, "meshing_close_holes", maxholesize=int(max_edges), selected=False, newfaceselected=False,
                         selfintersection=False, refinehole=False, refineholeedgelen=pymeshlab.PercentageValue(3.0))
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), dtype=np.float64), np.asarray(m.face_matrix(), dtype=np.int64)


def split_pinched_vertices(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split every vertex where two fans of triangles meet (a boundary touching itself at a point,
    which a cut can leave), each copy moved a tenth of an edge into its own fan (pymeshlab)."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int32)))
    apply_meshlab_filter(ms, "meshing_repair_non_manifold_vertices", vertdispratio=0.1)
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), dtype=np.float64), np.asarray(m.face_matrix(), dtype=np.int64)


def remesh(vertices: np.ndarray, faces: np.ndarray, edge_length: float, iterations: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Isotropic explicit remeshing (pymeshlab) to ``edge_length`` (m), boundaries kept."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int32)))
    apply_meshlab_filter(ms, "meshing_isotropic_explicit_remeshing", iterations=iterations, adaptive=False,
                         selectedonly=False, targetlen=pymeshlab.PureValue(edge_length), featuredeg=180.0,
                         checksurfdist=True, maxsurfdist=pymeshlab.PureValue(edge_length * 0.1), splitflag=True,
                         collapseflag=True, swapflag=True, smoothflag=True, reprojectflag=True)
    apply_meshlab_filter(ms, "meshing_remove_unreferenced_vertices")
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), dtype=np.float64), np.asarray(m.face_matrix(), dtype=np.int64)


def collapse_short_edges(vertices: np.ndarray, faces: np.ndarray, min_length: float) -> tuple[np.ndarray, np.ndarray]:
    """Collapse edges shorter than ``min_length`` that touch an open boundary.

    Isotropic remeshing keeps the boundary as it is, so the cut's uneven spacing survives it: a
    boundary edge a tenth of the target long, or an inner edge ending on the boundary, gives a
    triangle that a millimetre of motion stretches by 100 %. A boundary edge collapses to its
    midpoint; an inner edge with one boundary end collapses onto that end (the boundary keeps its
    shape). A collapse is made only when it keeps the surface a manifold (the two ends share no
    neighbour but the corners of the triangles on the edge), leaves every boundary loop at least
    four vertices long and flips no triangle. Edges inside the surface are left to the remesher.
    """
    v = np.array(vertices, dtype=np.float64)
    f = np.array(faces, dtype=np.int64)
    alive = np.ones(len(f), dtype=bool)
    for _ in range(8):
        live = f[alive]
        uniq, count = unique_edges(live, return_counts=True)
        boundary_edges = uniq[count == 1]
        on_boundary = np.zeros(len(v), dtype=bool)
        on_boundary[boundary_edges.ravel()] = True
        length = np.linalg.norm(v[uniq[:, 0]] - v[uniq[:, 1]], axis=1)
        touches = on_boundary[uniq].any(1)
        candidates = np.flatnonzero((length < min_length) & touches)
        if len(candidates) == 0:
            break
        boundary_set = {tuple(x) for x in boundary_edges.tolist()}
        # vertex -> faces, built once per pass; a collapse marks its neighbourhood as touched
        vf: dict[int, list[int]] = {}
        for fi in np.flatnonzero(alive):
            for x in f[fi]:
                vf.setdefault(int(x), []).append(int(fi))
        touched: set[int] = set()
        loop_len = _boundary_loop_lengths(boundary_edges)
        made = 0
        for ci in candidates[np.argsort(length[candidates])]:
            a, b = (int(x) for x in uniq[ci])
            if a in touched or b in touched:
                continue
            is_boundary_edge = (a, b) in boundary_set
            if not is_boundary_edge and on_boundary[a] and on_boundary[b]:
                continue  # a chord between two boundary points: collapsing it pinches the surface
            if is_boundary_edge and loop_len.get(a, 0) <= 4:
                continue
            if not on_boundary[a]:
                a, b = b, a  # keep the boundary end ``a``
            target = 0.5 * (v[a] + v[b]) if is_boundary_edge else v[a]
            fa, fb = set(vf.get(a, ())), set(vf.get(b, ()))
            shared = fa & fb
            opposite = {int(x) for fi in shared for x in f[fi]} - {a, b}
            na = {int(x) for fi in fa for x in f[fi]} - {a}
            nb = {int(x) for fi in fb for x in f[fi]} - {b}
            if (na & nb) != opposite:
                continue  # the link condition: a collapse here would glue two sheets together
            ok = True
            for fi in (fa | fb) - shared:
                tri = f[fi]
                old = np.cross(v[tri[1]] - v[tri[0]], v[tri[2]] - v[tri[0]])
                p = v[tri].copy()
                p[(tri == a) | (tri == b)] = target
                new = np.cross(p[1] - p[0], p[2] - p[0])
                if np.dot(old, new) <= 0.2 * np.linalg.norm(old) * np.linalg.norm(new):
                    ok = False
                    break
            if not ok:
                continue
            v[a] = target
            for fi in fb - shared:
                f[fi][f[fi] == b] = a
            alive[list(shared)] = False
            touched |= na | nb | {a, b}
            made += 1
        if made == 0:
            break
    f = f[alive]
    used = np.unique(f)
    remap = np.full(len(v), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def _boundary_loop_lengths(boundary_edges: np.ndarray) -> dict[int, int]:
    """For each boundary vertex, the number of vertices of its boundary loop."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    if len(boundary_edges) == 0:
        return {}
    n = int(boundary_edges.max()) + 1
    g = sp.coo_matrix((np.ones(len(boundary_edges)), (boundary_edges[:, 0], boundary_edges[:, 1])), shape=(n, n))
    _, label = connected_components(g, directed=False)
    verts = np.unique(boundary_edges)
    size = np.bincount(label[verts])
    return {int(x): int(size[label[x]]) for x in verts}
