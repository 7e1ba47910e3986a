"""How many bytes one sweep launch (``sweep_kernels.solve_colour``, one colour) reads and writes,
counted from the model's topology, and the bandwidth that means at a measured launch time.

The count follows the kernel's accesses of the elastic part (the vertex's own arrays; its
triangles' corners, shapes and stiffnesses; its hinges' four vertices and constants; the
adjacency lists; the per-part body flags; the contact counts) and leaves out the contact lists
and body planes, which depend on the state (few vertices have them). Two figures per colour:
*requested*, every load as the kernel issues it (what the caches serve), and *unique sectors*,
the distinct 32-byte sectors touched (a lower bound on what must come from memory when nothing
stays in the L2 between launches). An estimate from the access pattern, not a hardware counter:
Nsight Compute's figures are what decides.

    python -m benchmarks sweep-traffic --inputs .simbench/sim_inputs.npz \
        --launch-us 64:95.4,256:290.6 --peak-tbs 4.8
"""

from __future__ import annotations

import argparse
from collections import defaultdict

import numpy as np

from benchmarks.common import prepared_batch

SECTOR = 32
"""Bytes of one DRAM/L2 sector."""


class Traffic:
    """Loads and stores per array: bytes requested and the set of sectors touched."""

    def __init__(self):
        self.requested = 0
        self.sectors: dict[str, set] = defaultdict(set)

    def touch(self, name: str, index, size: int) -> None:
        index = np.atleast_1d(np.asarray(index, dtype=np.int64))
        self.requested += int(index.size) * size
        start = index * size
        for s in np.unique(np.concatenate([start // SECTOR, (start + size - 1) // SECTOR])):
            self.sectors[name].add(int(s))

    def unique(self) -> int:
        return sum(len(v) for v in self.sectors.values()) * SECTOR


def colour_traffic(h, colour: np.ndarray, parts: int) -> Traffic:
    """The accesses of one launch over ``colour``'s vertices (host topology ``h``)."""
    t = Traffic()
    faces, edges = np.asarray(h.faces), np.asarray(h.edges)
    v2f_off, v2f = np.asarray(h.v2f_offsets), np.asarray(h.v2f)
    v2e_off, v2e = np.asarray(h.v2e_offsets), np.asarray(h.v2e)
    t.touch("colour", np.arange(len(colour)), 4)
    for name, size in (("active", 4), ("x", 12), ("mass", 4), ("inertia_target", 12), ("vt_count", 4),
                       ("damping", 4), ("body_radius", 4), ("centre", 12), ("bound", 4), ("x_prev", 12)):
        t.touch(name, colour, size)
    t.touch("v2f_offsets", np.concatenate([colour, colour + 1]), 4)
    t.touch("v2e_offsets", np.concatenate([colour, colour + 1]), 4)
    t.touch("body_has", (colour[:, None] * parts + np.arange(parts)).ravel(), 4)
    t.touch("x_out", colour, 12)  # the store
    fk = np.concatenate([np.arange(v2f_off[i], v2f_off[i + 1]) for i in colour])
    tri = v2f[fk, 0]
    for _ in range(2):  # the membrane loop, then the loop over triangles for their vertex contacts
        t.touch("v2f", fk, 8)
        t.touch("faces", tri, 12)
    t.touch("tv_count", tri, 4)
    corners = faces[tri].ravel()
    t.touch("x", corners, 12)
    t.touch("x_prev", corners, 12)
    for name, size in (("dm_inv", 16), ("tri_stiff", 20), ("tri_area", 4)):
        t.touch(name, tri, size)
    ek = np.concatenate([np.arange(v2e_off[i], v2e_off[i + 1]) for i in colour])
    e, local = v2e[ek, 0], v2e[ek, 1]
    t.touch("v2e", ek, 8)
    t.touch("edges", e, 16)
    hinge = (edges[e, 2] >= 0) & (edges[e, 3] >= 0)
    stencil = edges[e[hinge]].ravel()
    t.touch("x", stencil, 12)
    t.touch("x_prev", stencil, 12)
    t.touch("bend_k", e[hinge], 4)
    t.touch("rest_angle", e[hinge], 4)
    t.touch("ee_count", e[local < 2], 4)
    return t


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--inputs", default=".simbench/sim_inputs.npz", help="sim prepare's scene")
    ap.add_argument("--launch-us", default="64:95.4,256:290.6",
                    help="scenes:µs a launch, measured (default: an H200, self-collision off, bench_newton --profile)")
    ap.add_argument("--peak-tbs", type=float, default=4.8, help="the card's memory bandwidth [TB/s] (H200: 4.8)")
    args = ap.parse_args(argv)
    from datagen.sim.model import triangle_colours
    from datagen.sim.solver import SolverConfig

    m = prepared_batch(np.load(args.inputs), 1, "cpu", 0, SolverConfig())[0].model
    h = m.host
    parts = m.body_part_count
    cols = [np.asarray(c, dtype=np.int64) for c in triangle_colours(h)]
    print(f"{m.particle_count} vertices, {m.face_count} triangles, {m.edge_count} edges, {len(cols)} colours, "
          f"{parts} body parts; one scene")
    print(f"{'colour':>6} {'vertices':>8} {'requested KB':>13} {'unique KB':>10}")
    req, uni, nv = [], [], []
    for k, c in enumerate(cols):
        t = colour_traffic(h, c, parts)
        req.append(t.requested)
        uni.append(t.unique())
        nv.append(len(c))
        print(f"{k:>6} {len(c):>8} {t.requested / 1e3:>13.1f} {t.unique() / 1e3:>10.1f}")
    r, u = float(np.mean(req)), float(np.mean(uni))
    print(f"mean a launch: {r / 1e3:.1f} KB requested, {u / 1e3:.1f} KB in unique sectors a scene "
          f"({r / np.mean(nv):.0f} and {u / np.mean(nv):.0f} B a vertex)")
    for item in args.launch_us.split(","):
        scenes, us = item.split(":")
        scenes, us = int(scenes), float(us)
        rb, ub = r * scenes / (us * 1e-6) / 1e12, u * scenes / (us * 1e-6) / 1e12
        print(f"{scenes} scenes at {us:g} µs a launch: requested {rb:.2f} TB/s, unique sectors {ub:.2f} TB/s "
              f"= {100 * ub / args.peak_tbs:.0f} % of the card's {args.peak_tbs:g} TB/s")
