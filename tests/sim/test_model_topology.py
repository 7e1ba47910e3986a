"""The cloth model's topology of a batch, made once per distinct garment and shifted, against the
topology of the whole concatenation (``datagen.sim.model``)."""

from __future__ import annotations

import numpy as np

from datagen.sim.model import ClothModelBuilder, _parts_topology, _scene_colours, _topology, triangle_colours
from tests.sim.meshes import grid


def _parts():
    """Three garments, repeated and interleaved as a batch repeats them, one scene with two parts."""
    a, b = grid(4, 5, 0.02), grid(6, 3, 0.02)
    c_v, c_f = grid(5, 5, 0.02)
    c_f = c_f[np.random.default_rng(0).permutation(len(c_f))]  # faces in no particular order
    return [(a[0], a[1]), (b[0], b[1]), (c_v, c_f), (a[0], a[1]), (c_v, c_f), (b[0], b[1]), (a[0], a[1])]


def test_batch_topology_equals_that_of_the_concatenation():
    parts = _parts()
    base = np.cumsum([0] + [len(v) for v, _ in parts])
    X = np.concatenate([v for v, _ in parts])
    F = np.concatenate([f + base[k] for k, (_, f) in enumerate(parts)])
    whole = _topology(X, F)
    tiled = _parts_topology([(len(v), f) for v, f in parts])
    for name in ("edges", "v2f_offsets", "v2f", "v2e_offsets", "v2e", "nbr_offsets", "nbr", "conflicts"):
        assert np.array_equal(getattr(whole, name), getattr(tiled, name)), name


def test_colours_made_once_per_garment_are_those_made_per_scene():
    """Colouring each distinct conflict graph once gives every scene the colours its own graph
    gets; the model built from the batch uses them (scene 3 holds two parts)."""
    from datagen.sim.model import _colour

    parts = _parts()
    scenes = [0, 1, 2, 3, 3, 4, 5]
    b = ClothModelBuilder()
    for (v, f), s in zip(parts, scenes, strict=True):
        b.add_cloth(v, f, scene=s)
    h = b.finalize("cpu").host
    topo = _topology(h.rest_positions, h.faces)
    per_scene: list[list[np.ndarray]] = []
    for s, (p0, p1) in enumerate(h.particle_range):
        mine = topo.conflicts[h.particle_scene[topo.conflicts[:, 0]] == s] - p0
        for k, c in enumerate(_colour(int(p1 - p0), mine)):
            if k == len(per_scene):
                per_scene.append([])
            per_scene[k].append(c + p0)
    expected = [np.concatenate(c) for c in per_scene]
    got = _scene_colours(topo.conflicts, h.particle_scene, h.particle_range)
    assert len(got) == len(expected) == len(h.colours)
    for g, e, m in zip(got, expected, h.colours, strict=True):
        assert np.array_equal(g, e) and np.array_equal(m, e)


def test_triangle_colours_separate_every_triangle_and_need_fewer_colours():
    """``SolverConfig(colour_hinge_wings=False)``'s colouring: every vertex in exactly one colour, no
    two corners of a triangle in the same colour, each scene coloured on its own (no colour mixes
    what scenes need), and no more colours than the model's, which also separates hinge wings."""
    parts = _parts()
    b = ClothModelBuilder()
    for s, (v, f) in enumerate(parts):
        b.add_cloth(v, f, scene=s)
    h = b.finalize("cpu").host
    colours = triangle_colours(h)
    colour_of = np.full(len(h.rest_positions), -1)
    for k, c in enumerate(colours):
        assert (colour_of[c] == -1).all()
        colour_of[c] = k
    assert (colour_of >= 0).all()
    f = np.asarray(h.faces)
    for a, b_ in ((0, 1), (1, 2), (2, 0)):
        assert (colour_of[f[:, a]] != colour_of[f[:, b_]]).all()
    assert len(colours) <= len(h.colours)
    stencils = np.asarray(h.edges)
    stencils = stencils[(stencils[:, 2] >= 0) & (stencils[:, 3] >= 0)]
    shared = int((colour_of[stencils[:, 2]] == colour_of[stencils[:, 3]]).sum())
    print(f"\n{len(h.colours)} colours with hinge wings, {len(colours)} by the triangles alone; "
          f"{shared} of {len(stencils)} hinges have both wings in one colour")
