"""Point and segment queries against triangle meshes, written once in warp and shared by the
garment builder and checks, the motion quality filters, the previews and the simulator's metrics.

- :func:`signed_distance` (a ``wp.func``, for kernels of other modules): distance from a point to
  a closed mesh, negative inside, the sign from the generalised winding number of the nearest face.
- :func:`mesh_signed_distance`, :func:`mesh_closest_points`, :func:`segments_hit_mesh`: the same
  queries over numpy arrays, on any warp device.
- :func:`warp_mesh`: a ``wp.Mesh`` (with its BVH) from numpy vertices and faces.
- :class:`MovingMesh`: one topology posed again and again (a body over a motion): the points
  replaced and the BVH refitted instead of rebuilt, and points counted inside it, on any device.

Kernels are defined here at module level (warp compiles this module once, on first launch, and
caches it under ``~/.cache/warp``); importing this module imports warp, so the packages that use
it import it where the query runs.
"""

from __future__ import annotations

import numpy as np
import warp as wp

__all__ = ["MovingMesh", "mesh_closest_points", "mesh_signed_distance", "push_out", "segments_hit_mesh", "signed_distance",
           "warp_mesh"]

WINDING_ACCURACY = wp.constant(2.0)
"""``accuracy`` (beta) of warp's winding-number sign: the dipole expansion's far-field factor."""

WINDING_THRESHOLD = wp.constant(0.5)
"""Winding number above which a point is inside."""


@wp.func
def signed_distance(mesh: wp.uint64, p: wp.vec3, max_dist: float) -> float:
    """Distance [m] from ``p`` to the mesh, negative inside; ``max_dist`` when no face is nearer.

    The sign is the generalised winding number of the nearest face found within ``max_dist``, so
    ``max_dist`` must exceed the depth of the deepest point inside the mesh that is asked about."""
    q = wp.mesh_query_point_sign_winding_number(mesh, p, max_dist, WINDING_ACCURACY, WINDING_THRESHOLD)
    if q.result:
        return wp.length(p - wp.mesh_eval_position(mesh, q.face, q.u, q.v)) * q.sign
    return max_dist


@wp.kernel
def _signed_distance(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), max_dist: float, out: wp.array(dtype=float)):
    tid = wp.tid()
    out[tid] = signed_distance(mesh, points[tid], max_dist)


@wp.kernel
def _closest_points(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), max_dist: float,
                    out: wp.array(dtype=wp.vec3)):
    tid = wp.tid()
    q = wp.mesh_query_point_no_sign(mesh, points[tid], max_dist)
    out[tid] = wp.mesh_eval_position(mesh, q.face, q.u, q.v)


@wp.kernel
def _segments_hit(mesh: wp.uint64, a: wp.array(dtype=wp.vec3), b: wp.array(dtype=wp.vec3),
                  out: wp.array(dtype=wp.int32)):
    tid = wp.tid()
    d = b[tid] - a[tid]
    L = wp.length(d)
    q = wp.mesh_query_ray(mesh, a[tid], d / L, L)
    if q.result:
        out[tid] = 1


def warp_mesh(vertices: np.ndarray, faces: np.ndarray, device: str | None = "cpu") -> wp.Mesh:
    """A warp mesh of ``vertices`` [V, 3] (m) and ``faces`` [F, 3] on ``device``."""
    return wp.Mesh(points=wp.array(np.ascontiguousarray(vertices, dtype=np.float32), dtype=wp.vec3, device=device),
                   indices=wp.array(np.ascontiguousarray(faces, dtype=np.int32).ravel(), dtype=wp.int32,
                                    device=device),
                   support_winding_number=True)


def _points(points: np.ndarray, device) -> wp.array:
    return wp.array(np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 3), dtype=wp.vec3, device=device)


def mesh_signed_distance(mesh: wp.Mesh, points: np.ndarray, max_dist: float) -> np.ndarray:
    """:func:`signed_distance` of every point of ``points`` [N, 3] (m) to ``mesh``: [N] float32."""
    out = wp.zeros(len(points), dtype=float, device=mesh.device)
    wp.launch(_signed_distance, dim=len(points), inputs=[mesh.id, _points(points, mesh.device), float(max_dist), out],
              device=mesh.device)
    return out.numpy()


def mesh_closest_points(mesh: wp.Mesh, points: np.ndarray, max_dist: float = 10.0) -> np.ndarray:
    """The closest point of ``mesh`` to every point of ``points`` [N, 3] (m): [N, 3] float32."""
    out = wp.zeros(len(points), dtype=wp.vec3, device=mesh.device)
    wp.launch(_closest_points, dim=len(points), inputs=[mesh.id, _points(points, mesh.device), float(max_dist), out],
              device=mesh.device)
    return out.numpy()


def segments_hit_mesh(mesh: wp.Mesh, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether each segment ``a[i]``-``b[i]`` ([N, 3] each, m) passes through a face of ``mesh``: [N] bool."""
    out = wp.zeros(len(a), dtype=wp.int32, device=mesh.device)
    wp.launch(_segments_hit, dim=len(a), inputs=[mesh.id, _points(a, mesh.device), _points(b, mesh.device), out],
              device=mesh.device)
    return out.numpy().astype(bool)


class MovingMesh:
    """A closed triangle mesh of fixed topology whose vertices move (a body posed frame by frame):
    one ``wp.Mesh`` on ``device``, its points replaced and its BVH refitted (with the winding
    numbers' data) by :meth:`pose` instead of a new mesh built per frame (the same answers: tested).

    >>> body = MovingMesh(faces, device="cuda")  # doctest: +SKIP
    >>> body.pose(body_vertices_of_frame); body.inside_count(garment_vertices)  # doctest: +SKIP
    """

    def __init__(self, faces: np.ndarray, device: str | None = "cpu"):
        self.faces = np.ascontiguousarray(faces, dtype=np.int32)
        self.device = device
        self.mesh: wp.Mesh | None = None

    def pose(self, vertices: np.ndarray) -> MovingMesh:
        """Move the mesh to ``vertices`` [V, 3] (m)."""
        v = np.ascontiguousarray(vertices, dtype=np.float32)
        if self.mesh is None or self.mesh.points.shape[0] != len(v):
            self.mesh = warp_mesh(v, self.faces, self.device)
        else:
            self.mesh.points.assign(v)
            self.mesh.refit()
        return self

    def signed_distance(self, points: np.ndarray, max_dist: float = 1.0) -> np.ndarray:
        """:func:`mesh_signed_distance` of ``points`` [N, 3] to the posed mesh: [N] float32."""
        if self.mesh is None:
            raise RuntimeError("MovingMesh.pose(vertices) must come before a query")
        return mesh_signed_distance(self.mesh, points, max_dist)

    def inside_count(self, points: np.ndarray, max_dist: float = 1.0) -> int:
        """How many of ``points`` [N, 3] are inside the posed mesh (signed distance below 0)."""
        return int((self.signed_distance(points, max_dist) < 0).sum())


def push_out(points: np.ndarray, body_vertices: np.ndarray, body_faces: np.ndarray, clearance: float) -> np.ndarray:
    """``points`` [N, 3] (m) with every point inside the closed mesh (``body_vertices`` [V, 3],
    ``body_faces`` [F, 3]) or closer than ``clearance`` [m] to it moved to its closest point plus
    ``clearance`` outward (a point on the surface: along the face normal there); the others as given."""
    body = warp_mesh(np.asarray(body_vertices, dtype=np.float64), np.asarray(body_faces))
    sd = mesh_signed_distance(body, points, 10.0)
    close = sd < clearance
    if not close.any():
        return points
    closest = mesh_closest_points(body, points[close], 10.0)
    away = points[close] - closest
    dist = np.linalg.norm(away, axis=1, keepdims=True)
    outward = np.where(sd[close, None] < 0, -away, away) / np.maximum(dist, 1e-12)
    # a vertex exactly on the surface has no direction: use the body's vertex normal at the closest point
    flat = dist[:, 0] < 1e-9
    if flat.any():
        import trimesh

        tm = trimesh.Trimesh(body_vertices, body_faces, process=False)
        tri = tm.nearest.on_surface(closest[flat])[2]
        outward[flat] = tm.face_normals[tri]
    out = points.copy()
    out[close] = closest + outward * clearance
    return out
