"""Gallery of sewing-pattern garments: designs sampled across the programs on the thin, regular and fat
bodies, each as its flat panels (stitches numbered) beside the panels placed around the body (front
and side), before any sewing. Writes docs/patterns/gallery_N.png (six designs a sheet).

    python -m benchmarks pattern-gallery [--designs 24] [--seed 0] [--out docs/patterns]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.common import PRESET_BODIES as BODIES
from benchmarks.common import preset_bodies

PER_SHEET = 6


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--designs", type=int, default=24)
    ap.add_argument("--seed", type=int, default=0, help="draws the designs' seeds")
    ap.add_argument("--edge-length", type=float, default=0.02)
    ap.add_argument("--out", default="docs/patterns")
    args = ap.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from datagen.body.cache import default_body
    from datagen.body.render import MeshLayer, draw_meshes, view_limits
    from datagen.garment.pattern.garment import pattern_garment
    from datagen.garment.pattern.programs import PROGRAMS, make_pattern
    from datagen.garment.pattern.svg import draw_pattern_axes
    from datagen.garment.render import BODY_COLOUR

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    model = default_body()
    bodies = preset_bodies(model)
    rng = np.random.default_rng(args.seed)
    names = list(PROGRAMS)
    # every program on every body in turn (the body shifts by one each round of the programs)
    items = [(names[i % len(names)], int(rng.integers(0, 10_000)), BODIES[(i + i // len(names)) % len(BODIES)])
             for i in range(args.designs)]
    palette = plt.get_cmap("tab20")
    sheets = []
    for s in range(0, len(items), PER_SHEET):
        chunk = items[s:s + PER_SHEET]
        fig, axes = plt.subplots(len(chunk), 3, figsize=(11, 3.2 * len(chunk)),
                                 gridspec_kw={"width_ratios": [2.2, 1, 1]}, squeeze=False)
        for row, (prog, seed, body) in enumerate(chunk):
            bv, bf, meas, betas = bodies[body]
            t0 = time.perf_counter()
            pattern = make_pattern(prog, seed, meas)
            g = pattern_garment(pattern, bv, bf, edge_length=args.edge_length, seed=seed, betas=betas)
            draw_pattern_axes(axes[row, 0], pattern)
            axes[row, 0].set_title(f"{prog} seed {seed} on {body}: {len(pattern.panels)} panels, "
                                   f"{len(pattern.stitches)} stitches, {g.vertex_count} vertices", fontsize=7)
            colours = np.array([palette(i % 20)[:3] for i in range(len(pattern.panels))])[g.face_region]
            layers = [MeshLayer(bv, bf, BODY_COLOUR), MeshLayer(g.vertices, g.faces, colours, two_sided=True)]
            for col, deg in ((1, 0.0), (2, 90.0)):
                ax = axes[row, col]
                limits = view_limits([bv, g.vertices], deg, pad=1.03)
                draw_meshes(ax, layers, deg, ambient=0.3, absolute=True, linewidth=0.2, limits=limits)
                ax.set_aspect("equal")
                ax.axis("off")
            print(f"  {prog} seed {seed} on {body}: {g.vertex_count} vertices, {time.perf_counter() - t0:.1f} s",
                  flush=True)
        fig.tight_layout()
        path = out / f"gallery_{s // PER_SHEET + 1}.png"
        fig.savefig(path, dpi=80)
        plt.close(fig)
        sheets.append(path)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
