"""Where a check run's cloth crosses itself: for every saved frame (every 10th recorded frame) the
edge-triangle crossings of the garment, which panels the crossing edge and triangle belong to, and
how many of them are pinched by the body (both the edge and the triangle closer to the body than
``--pinch`` x the cloth's contact distance, their nearest body points on different body parts:
cloth caught where two parts of the body meet, as under an arm pressed to the torso).

    python -m benchmarks sim run-scenes --inputs .simbench/runs.pkl --out-dir DIR [--device cuda]
    python -m benchmarks crossing-regions .simbench/runs.pkl DIR [--runs tshirt/dance_disco]
"""

from __future__ import annotations

import argparse
import pickle
from collections import Counter
from pathlib import Path

import numpy as np
import warp as wp

from datagen.sim.metrics import crossings

MAX_PER_EDGE = 8


def frame_crossings(x: np.ndarray, faces: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """[K, 2] (edge, triangle) crossing pairs of one frame (positions [V, 3])."""
    xs = wp.array(x.astype(np.float32), dtype=wp.vec3, device="cpu")
    tri = x[faces]
    lo = wp.array(tri.min(1).astype(np.float32), dtype=wp.vec3, device="cpu")
    hi = wp.array(tri.max(1).astype(np.float32), dtype=wp.vec3, device="cpu")
    bvh = wp.Bvh(lo, hi, groups=wp.zeros(len(faces), dtype=wp.int32, device="cpu"))  # one scene
    count = wp.zeros(len(edges), dtype=wp.int32, device="cpu")
    out = wp.full((len(edges), MAX_PER_EDGE), -1, dtype=wp.int32, device="cpu")
    wp.launch(crossings, len(edges), device="cpu",
              inputs=[bvh.id, xs, wp.zeros(len(x), dtype=wp.int32, device="cpu"),
                      wp.array(faces.astype(np.int32), device="cpu"), wp.array(edges.astype(np.int32), device="cpu"),
                      count, out, wp.array(np.arange(len(edges), dtype=np.int32), device="cpu")])
    o = out.numpy()
    e, k = np.nonzero(o >= 0)
    return np.stack([e, o[e, k]], 1)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", help="the prepared runs (sim prepare-runs)")
    ap.add_argument("out_dir", help="the run's --out-dir (positions and body of every 10th recorded frame)")
    ap.add_argument("--runs", default="", help="comma-separated run names (default: every run with an output)")
    ap.add_argument("--pinch", type=float, default=2.0, help="pinched: within this many contact distances of the body")
    args = ap.parse_args(argv)
    import trimesh

    from datagen.body.skeleton import face_parts

    wp.init()
    with open(args.inputs, "rb") as fh:  # our own objects, from our own prepare step
        d = pickle.load(fh)
    wanted = set(filter(None, args.runs.split(",")))
    for name, scene in zip(d["names"], d["scenes"]):
        path = Path(args.out_dir) / f"{name.replace('/', '_')}.npz"
        if not path.is_file() or (wanted and name not in wanted):
            continue
        run = np.load(path)
        if "body" not in run:
            print(f"{name}: {path} has no body frames (made before run-scenes saved them); run it again")
            continue
        g = scene.garment
        faces = np.asarray(g.faces)
        e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        edges = np.unique(np.sort(e, 1), axis=0)
        region = np.asarray(g.vertex_region)
        face_region = np.asarray(g.face_region)
        body_faces = np.asarray(scene.body.faces)
        parts = face_parts(scene.body.weights, body_faces)
        reach = args.pinch * (g.material.thickness + 0.002)
        print(f"{name}: {g.vertex_count} vertices; saved frames {len(run['positions'])} (every 10th recorded)")
        for f, (x, body) in enumerate(zip(run["positions"].astype(np.float64), run["body"].astype(np.float64))):
            pairs = frame_crossings(x, faces, edges)
            if len(pairs) == 0:
                continue
            mesh = trimesh.Trimesh(body, body_faces, process=False)
            ev = edges[pairs[:, 0]]
            tv = faces[pairs[:, 1]]
            mid_e = x[ev].mean(1)
            mid_t = x[tv].mean(1)
            pe, de, fe = trimesh.proximity.closest_point(mesh, mid_e)
            pt, dt, ft = trimesh.proximity.closest_point(mesh, mid_t)
            pinched = (de < reach) & (dt < reach) & (parts[fe] != parts[ft])
            names = g.region_names
            kinds = Counter(tuple(sorted((names[region[a]], names[face_region[t]])))
                            for (a, _b), t in zip(ev, pairs[:, 1]))
            top = ", ".join(f"{a}/{b} {n}" for (a, b), n in kinds.most_common(4))
            print(f"  frame {10 * f:3d}: {len(pairs):3d} crossings, pinched between body parts {int(pinched.sum()):3d}, "
                  f"edge within reach of the body {int((de < reach).sum()):3d}; panels {top}; "
                  f"median distance to the body {1000 * np.median(np.minimum(de, dt)):.1f} mm")
