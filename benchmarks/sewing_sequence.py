"""A sewing sequence picture: pattern garments placed around the body, sewn, and settled.

For each design (program and seed) on the regular body at rest: the panels as placed
(:func:`datagen.garment.pattern.garment.pattern_garment`), the welded garment at the end of sewing
(:func:`datagen.sim.sewing.sew`, no gravity) and after settling under gravity; front views, panels
coloured, with the sewing figures in the titles. Writes ``docs/patterns/sewing_sequence.png`` and
prints, per design, the frames to sew and to static, the largest strain at a seam corner and the
triangles folded over their neighbours, sewn and settled.

The cloth is drawn with the previews' depth bias over the body
(:data:`datagen.export.preview.GARMENT_DEPTH_BIAS`): matplotlib paints
triangles back to front by their centres, and a garment lying 8 mm off the body had body triangles
painted over its own (the speckles of the picture before 2026-11-28's seventh session; the
garment alone showed none, and none of its triangles was folded).

    python -m benchmarks sewing-sequence [--designs skirt_a_line:1367864806,top:161576974,trousers:0]
        [--edge-length 0.03] [--settle-frames 30] [--device cpu] [--out docs/patterns/sewing_sequence.png]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.common import preset_bodies


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--designs", default="skirt_a_line:1367864806,top:161576974,trousers:0", help="NAME:SEED,...")
    ap.add_argument("--body", default="regular")
    ap.add_argument("--placement", default="flat", choices=("flat", "wrap"), help="pattern_garment's placement mode")
    ap.add_argument("--edge-length", type=float, default=0.03)
    ap.add_argument("--settle-frames", type=int, default=30)
    ap.add_argument("--device", default="cpu", help="warp device of the simulation")
    ap.add_argument("--out", default="docs/patterns/sewing_sequence.png")
    args = ap.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from datagen.body.cache import default_body
    from datagen.body.render import MeshLayer, draw_meshes, view_limits
    from datagen.body.skeleton import face_parts
    from datagen.export.preview import GARMENT_DEPTH_BIAS
    from datagen.garment.pattern.garment import pattern_garment
    from datagen.garment.pattern.programs import make_pattern
    from datagen.garment.render import BODY_COLOUR
    from datagen.sim.sewing import SewConfig, sew

    model = default_body()
    bv, bf, meas, betas = preset_bodies(model)[args.body]
    parts = face_parts(model.weights, model.faces)
    designs = [(d.split(":")[0], int(d.split(":")[1])) for d in args.designs.split(",")]
    palette = plt.get_cmap("tab20")
    fig, axes = plt.subplots(len(designs), 3, figsize=(8.4, 3.4 * len(designs)), squeeze=False)
    for row, (prog, seed) in enumerate(designs):
        t0 = time.perf_counter()
        g = pattern_garment(make_pattern(prog, seed, meas), bv, bf, edge_length=args.edge_length, mode=args.placement,
                            seed=seed, betas=betas)
        r = sew(g, bv, bf, body_face_part=parts, config=SewConfig(settle_frames=args.settle_frames), device=args.device)
        colours = np.array([palette(i % 20)[:3] for i in range(len(g.region_names))])
        w = r.garment
        shots = [(g.vertices, g.faces, g.face_region, f"placed: gaps up to {1000 * r.gap[0]:.0f} mm"),
                 (r.sewn, w.faces, w.face_region, f"sewn in {r.sew_frames} frames, no gravity"),
                 (w.vertices, w.faces, w.face_region,
                  f"settled: {'static' if r.settle_frames >= 0 else 'moving'} after "
                  f"{r.settle_frames if r.settle_frames >= 0 else args.settle_frames} frames")]
        for col, (x, f, reg, title) in enumerate(shots):
            ax = axes[row, col]
            layers = [MeshLayer(bv, bf, BODY_COLOUR),
                      MeshLayer(x, f, colours[reg], two_sided=True, depth_bias=GARMENT_DEPTH_BIAS)]
            draw_meshes(ax, layers, 0.0, ambient=0.3, absolute=True, linewidth=0.2,
                        limits=view_limits([bv, g.vertices], 0.0, pad=1.03))
            ax.set_aspect("equal")
            ax.axis("off")
            ax.set_title(f"{prog}:{seed} {title}" if col == 0 else title, fontsize=7)
        k = min(max(r.sew_frames, 0) + SewConfig().relax_frames, len(r.folded)) - 1
        print(f"  {prog}:{seed}: sewn in {r.sew_frames} frames, static after {r.settle_frames}, largest strain at a seam "
              f"corner {r.corner_stretch[k]:.2f} sewn / {r.corner_stretch[-1]:.2f} settled, folded triangles "
              f"{r.folded[k]} / {r.folded[-1]}, crossings {r.self_intersections[k]} / {r.self_intersections[-1]}, "
              f"{r.failure or 'passed'}, {time.perf_counter() - t0:.1f} s", flush=True)
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=80)
    plt.close(fig)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
