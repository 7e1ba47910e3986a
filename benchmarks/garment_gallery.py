"""Pictures of every garment type on the default body (docs/garments/<type>.png and docs/garments.png).

    python -m benchmarks garment-gallery --seed 0
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from datagen.body.cache import default_body
from datagen.garment.render import render_garment
from datagen.garment.types import GARMENT_TYPES, make_garment


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="docs/garments")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt

    body = default_body()
    verts = np.asarray(body.shaped(np.zeros(body.shape_dim)))[0]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    for kind in GARMENT_TYPES:
        g = make_garment(kind, body, seed=args.seed)
        f = render_garment(g, verts, body.faces, out / f"{kind}.png", title=f"{kind} (seed {args.seed}, {g.vertex_count} vertices)")
        files.append(f)
        print(f"wrote {f}")
    cols = 3
    rows = (len(files) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(cols * 4.0, rows * 2.1))
    for ax in axes.ravel():
        ax.axis("off")
    for ax, f in zip(axes.ravel(), files):
        ax.imshow(mpimg.imread(f))
    fig.tight_layout()
    fig.savefig(out.parent / "garments.png", dpi=110)
    print(f"wrote {out.parent / 'garments.png'}")
