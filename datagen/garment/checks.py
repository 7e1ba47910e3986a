"""Checks that a garment can be simulated: topology, mesh quality, self-intersections, placement.

Each check returns plain numbers; :func:`check_garment` gathers them with a pass/fail verdict.
"""

from __future__ import annotations

import numpy as np

from datagen.geometry.topology import unique_edges

__all__ = ["check_garment", "orientation", "placement", "quality", "self_intersections", "topology"]


def topology(vertices: np.ndarray, faces: np.ndarray) -> dict:
    """Edge- and vertex-manifoldness, components, orientation, boundary loop count (trimesh)."""
    import trimesh

    from datagen.garment.mesh import boundary_loops

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    _, counts = unique_edges(faces, return_counts=True)
    non_manifold_edges = int((counts > 2).sum())
    loops = boundary_loops(faces)
    boundary_vertices = sum(len(lp) for lp in loops)
    unique_boundary = len(np.unique(np.concatenate(loops))) if loops else 0
    return {"non_manifold_edges": non_manifold_edges,
            "non_manifold_vertices": int(boundary_vertices - unique_boundary),  # a vertex on two boundary runs
            "components": len(mesh.split(only_watertight=False)),
            "winding_consistent": bool(mesh.is_winding_consistent),
            "boundary_loops": len(loops)}


def quality(vertices: np.ndarray, faces: np.ndarray) -> dict:
    """Minimum triangle angle (degrees) and edge-length spread (std / mean)."""
    v = vertices[faces]
    angles = []
    for k in range(3):
        a = v[:, (k + 1) % 3] - v[:, k]
        b = v[:, (k + 2) % 3] - v[:, k]
        cos = np.sum(a * b, 1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        angles.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    e = np.linalg.norm(np.concatenate([v[:, 1] - v[:, 0], v[:, 2] - v[:, 1], v[:, 0] - v[:, 2]]), axis=1)
    ang = np.concatenate(angles)
    return {"min_angle_deg": float(ang.min()), "angle_p1_deg": float(np.percentile(ang, 1)),
            "edge_mean": float(e.mean()), "edge_spread": float(e.std() / e.mean())}


def self_intersections(vertices: np.ndarray, faces: np.ndarray) -> int:
    """Number of faces that intersect another face of the same mesh (pymeshlab)."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.ascontiguousarray(vertices), np.ascontiguousarray(faces, dtype=np.int32)))
    from datagen.garment.levelset import apply_meshlab_filter

    apply_meshlab_filter(ms, "compute_selection_by_self_intersections_per_face")
    return int(ms.current_mesh().selected_face_number())


def placement(vertices: np.ndarray, faces: np.ndarray, body_vertices: np.ndarray, body_faces: np.ndarray) -> dict:
    """Garment vertices inside the body, garment/body triangles crossing, and the minimum clearance (m).

    Two triangle meshes intersect exactly where an edge of one passes through a triangle of the
    other, so crossing is tested both ways with warp ray queries along every edge.
    """
    from datagen.geometry.queries import mesh_signed_distance, segments_hit_mesh, warp_mesh

    body = warp_mesh(body_vertices, body_faces)
    cloth = warp_mesh(vertices, faces)
    sd = mesh_signed_distance(body, vertices, 10.0)
    crossings = 0
    for (va, fa), mesh in (((vertices, faces), body), ((body_vertices, body_faces), cloth)):
        e = unique_edges(fa)
        va = np.asarray(va, np.float32)
        crossings += int(segments_hit_mesh(mesh, va[e[:, 0]], va[e[:, 1]]).sum())
    return {"vertices_inside": int((sd < 0).sum()), "edge_crossings": crossings, "min_clearance": float(sd.min())}


def orientation(vertices: np.ndarray, faces: np.ndarray, body_vertices: np.ndarray, body_faces: np.ndarray) -> dict:
    """Share of the garment's area whose face normal points away from the body: the normal of each
    face against the direction from the closest body point to the face's centre (1.0: all outward)."""
    from datagen.geometry.queries import mesh_closest_points, warp_mesh

    tri = np.asarray(vertices)[np.asarray(faces)]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(n, axis=1)
    centre = tri.mean(axis=1)
    closest = mesh_closest_points(warp_mesh(body_vertices, body_faces), centre.astype(np.float32))
    away = np.einsum("ij,ij->i", n, centre - closest.astype(np.float64)) > 0
    return {"outward_area_fraction": float(area[away].sum() / max(area.sum(), 1e-30))}


def check_garment(garment, body_vertices: np.ndarray, body_faces: np.ndarray) -> dict:
    """Every check on ``garment`` (a :class:`~datagen.garment.mesh.GarmentMesh`) and a verdict."""
    v, f = garment.vertices, garment.faces
    out = {**topology(v, f), **quality(v, f), "self_intersecting_faces": self_intersections(v, f),
           **placement(v, f, body_vertices, body_faces), **orientation(v, f, body_vertices, body_faces)}
    failures = []
    if out["non_manifold_edges"] or out["non_manifold_vertices"]:
        failures.append("non-manifold")
    if out["components"] != 1:
        failures.append(f"{out['components']} components")
    if not out["winding_consistent"]:
        failures.append("inconsistent winding")
    expected = garment.metadata.expected_boundary_loops
    if expected is not None and out["boundary_loops"] != expected:
        failures.append(f"{out['boundary_loops']} boundary loops, expected {expected}")
    if out["outward_area_fraction"] < 0.9:
        failures.append(f"normals face the body ({100 * (1 - out['outward_area_fraction']):.0f}% of the area points inwards)")
    if out["self_intersecting_faces"]:
        failures.append(f"{out['self_intersecting_faces']} self-intersecting faces")
    if out["vertices_inside"] or out["edge_crossings"]:
        failures.append(f"penetrates the body ({out['vertices_inside']} vertices inside, {out['edge_crossings']} crossings)")
    out["failures"] = failures
    out["ok"] = not failures
    return out
