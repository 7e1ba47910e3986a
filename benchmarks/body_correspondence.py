"""Which body resolution should the indicator matrix I (paper 000 §4.1) use?

I maps every garment vertex to its closest body vertex, and the paper assumes the body is dense
enough for that to be one-to-one. This measures it on proxy garments: a T-shirt-like region of
the regular body (torso and upper arms), offset 1.5 cm outward and sampled evenly at 2,000,
4,000 and 8,000 vertices (the garment sizes drape makes). For the base body (13,348 vertices)
and its 4-to-1 subdivision (53,386), it reports:

- shared: share of garment vertices whose closest body vertex is also another's (not one-to-one),
- excess: how much farther the closest body *vertex* is than the closest body *surface* point
  (mean and 95th percentile, mm): the error of describing the garment by I·M_b.

    python benchmarks/body_correspondence.py
"""

from __future__ import annotations

import numpy as np


def surface_distance(vertices, faces, points) -> np.ndarray:
    """Exact point-to-surface distance [m] with a Warp BVH query (CPU or CUDA)."""
    import warp as wp

    wp.config.quiet = True

    @wp.kernel
    def query(mesh: wp.uint64, pts: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
        i = wp.tid()
        q = wp.mesh_query_point_no_sign(mesh, pts[i], 10.0)
        out[i] = wp.length(pts[i] - wp.mesh_eval_position(mesh, q.face, q.u, q.v))

    mesh = wp.Mesh(points=wp.array(vertices, dtype=wp.vec3), indices=wp.array(faces.reshape(-1), dtype=int))
    out = wp.zeros(len(points), dtype=float)
    wp.launch(query, dim=len(points), inputs=[mesh.id, wp.array(points, dtype=wp.vec3), out])
    return out.numpy()


def main() -> None:
    import trimesh
    from scipy.spatial import cKDTree

    from datagen.body.cache import default_body
    from datagen.body.shapes import preset_betas
    from datagen.body.skeleton import SMPL_JOINT_NAMES

    base = default_body()
    fine = base.subdivided()
    betas = preset_betas(base, "regular")[None]
    v_base = base.shaped(betas)[0]
    v_fine = fine.shaped(betas)[0]
    surface = trimesh.Trimesh(v_fine, fine.faces, process=False)
    shirt_joints = [SMPL_JOINT_NAMES.index(n) for n in ("pelvis", "spine1", "spine2", "spine3", "left_collar", "right_collar",
                                                        "left_shoulder", "right_shoulder")]
    region = base.weights[:, shirt_joints].sum(1) > 0.5
    region &= v_base[:, 1] > base.rest_joints(betas)[0, 0, 1] - 0.05
    faces = base.faces[region[base.faces].all(1)]
    shirt = trimesh.Trimesh(v_base, faces, process=False)
    print(f"proxy garment region: {shirt.area:.2f} m^2 of the regular body, offset 15 mm")
    print(f"{'garment v':>9} {'body v':>7} {'shared':>8} {'excess mean':>12} {'excess p95':>11}")
    for count in (2000, 4000, 8000):
        pts, fid = trimesh.sample.sample_surface_even(shirt, count, seed=0)
        pts = pts + 0.015 * shirt.face_normals[fid]
        d_surface = surface_distance(surface.vertices, surface.faces, pts)
        for name, verts in (("base", v_base), ("subdiv", v_fine)):
            d_vertex, idx = cKDTree(verts).query(pts)
            shared = 1.0 - len(np.unique(idx)) / len(idx)
            excess = (d_vertex - d_surface) * 1000
            print(f"{len(pts):>9} {len(verts):>7} {100 * shared:>7.1f}% {excess.mean():>9.2f} mm {np.percentile(excess, 95):>8.2f} mm")


if __name__ == "__main__":
    main()
