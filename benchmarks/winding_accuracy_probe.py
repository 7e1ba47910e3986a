"""How far the winding number's accuracy β can drop before the projection's inside test changes.

warp's ``mesh_query_point_sign_winding_number(mesh, p, max_dist, accuracy, threshold)`` evaluates
the fast winding number (Barill et al. 2018): a subtree of the mesh's tree counts as its dipole when
the point is farther than β times the subtree's radius. drape's body projection asks it for every
cloth vertex near the body every substep (``projection_kernels.test_inside_body``); a smaller β visits
fewer nodes. This probe poses drape's default body in the motions whose poses press body parts
into each other (squat, sit_stand, lunge, box, dance_disco, kick, bend_forward, arm_circles; and the
walk), scatters points within ``--within`` metres of the posed surface (each a random body vertex
moved a random distance along a random direction), and compares the inside-or-out answer at each
β with β = 2 (warp's default and the penetration metric's), with the time of each on this device:

    python benchmarks/winding_accuracy_probe.py --betas 2,1.5,1.25,1,0.75 --within 0.01
    python benchmarks/winding_accuracy_probe.py --within 0.003 --device cuda

Prints per β: seconds, points whose answer differs from β = 2's.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import warp as wp

LABELS = ("walk", "squat", "sit_stand", "lunge", "box", "dance_disco", "kick", "bend_forward", "arm_circles")


@wp.kernel
def _signs(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), beta: float, max_dist: float,
           sign: wp.array(dtype=float)):
    i = wp.tid()
    q = wp.mesh_query_point_sign_winding_number(mesh, points[i], max_dist, beta, 0.5)
    sign[i] = 2.0  # no body face within max_dist
    if q.result:
        sign[i] = q.sign


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--betas", default="2,1.5,1.25,1,0.75")
    p.add_argument("--within", type=float, default=0.01, help="points within this distance of the surface [m]")
    p.add_argument("--points", type=int, default=100_000, help="points per posed body")
    p.add_argument("--poses", type=int, default=6, help="poses per motion (of 90 frames)")
    p.add_argument("--device", default="cpu")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)

    from datagen.body.cache import default_body
    from datagen.motion.library import make_motion

    wp.init()
    betas = [float(b) for b in args.betas.split(",")]
    body = default_body()
    faces = wp.array(np.asarray(body.faces, dtype=np.int32).reshape(-1), dtype=wp.int32, device=args.device)
    rng = np.random.default_rng(args.seed)
    seconds = dict.fromkeys(betas, 0.0)
    differ = dict.fromkeys(betas, 0)
    total = inside = 0
    for label in LABELS:
        motion = make_motion(label, seed=0, frames=90)
        for f in np.linspace(0, 89, args.poses).astype(int):
            v, _ = body.pose(pose=motion.poses[f][None], transl=motion.trans[f][None], dtype=np.float32)
            v = np.asarray(v, dtype=np.float32).reshape(-1, 3)
            mesh = wp.Mesh(wp.array(v, dtype=wp.vec3, device=args.device), faces, support_winding_number=True)
            base = v[rng.integers(0, len(v), args.points)]
            direction = rng.normal(size=base.shape)
            direction /= np.linalg.norm(direction, axis=1, keepdims=True)
            pts = base + (direction * rng.uniform(0.0, args.within, (len(base), 1))).astype(np.float32)
            points = wp.array(pts, dtype=wp.vec3, device=args.device)
            answers = {}
            for beta in betas:
                out = wp.zeros(len(pts), dtype=float, device=args.device)
                wp.synchronize_device(args.device)
                t0 = time.perf_counter()
                wp.launch(_signs, len(pts), inputs=[mesh.id, points, beta, 0.1, out], device=args.device)
                wp.synchronize_device(args.device)
                seconds[beta] += time.perf_counter() - t0
                answers[beta] = np.sign(out.numpy())
            reference = answers[2.0] if 2.0 in answers else answers[betas[0]]
            for beta in betas:
                differ[beta] += int(np.sum(answers[beta] != reference))
            total += len(pts)
            inside += int(np.sum(reference < 0))
    print(f"{total} points within {1000 * args.within:g} mm of the default body in {len(LABELS)} motions x "
          f"{args.poses} poses ({inside} inside), device {args.device}")
    print(f"{'beta':>6s} {'seconds':>9s} {'vs beta 2':>9s} {'answers differing from beta 2':>30s}")
    base_s = seconds.get(2.0, seconds[betas[0]])
    for beta in betas:
        print(f"{beta:6g} {seconds[beta]:9.2f} {seconds[beta] / base_s:8.2f}x {differ[beta]:30d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
