"""The projection's inside test skips only vertices that provably cannot have entered the body
(``projection_kernels.may_have_entered``): the result is bitwise that of testing every vertex."""

from __future__ import annotations

import numpy as np
import pytest

from datagen.sim.model import ClothModelBuilder
from datagen.sim.solver import SolverConfig, SolverVBD, _part_vertices, _reference_vertices
from datagen.sim.state import BodyControl, ClothState
from tests.sim.meshes import grid

FPS = 30


@pytest.fixture(scope="module")
def sphere():
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=3, radius=0.15)
    return np.asarray(s.vertices, dtype=np.float64), np.asarray(s.faces, dtype=np.int64)


def _devices():
    import warp as wp

    cuda = pytest.param("cuda", marks=pytest.mark.skipif(
        wp.get_cuda_device_count() == 0, reason="needs a CUDA device: its float atomics and graphs run only there"))
    return ["cpu", cuda]


def _run(sphere, skip: bool, frames: int = 12, device: str = "cpu"):
    """A 40 cm cotton square hanging still (no gravity) while a sphere flies up through it at
    3 m/s and swings sideways: vertices near the sphere are pushed in every substep and projected
    out, the rest of the square is far from it. Returns per frame the positions, the vertices
    projected and the vertices whose test was skipped."""
    v, f = grid(17, 17, 0.025, y=0.0)
    b = ClothModelBuilder()
    b.add_cloth(v, f, material_name="cotton")
    sv, sf = sphere
    b.add_body(sv + [0.0, -0.3, 0.0], sf)
    model = b.finalize(device)
    config = SolverConfig(gravity=(0.0, 0.0, 0.0), body_stiffness=1.0e-4, projection_skip=skip)
    solver = SolverVBD(model, config)
    s0, s1 = ClothState.from_model(model), ClothState.from_model(model)
    out = []
    for k in range(frames):
        t = (k + 1) / FPS
        centre = np.array([0.05 * np.sin(8.0 * t), -0.3 + 3.0 * t, 0.0])
        solver.step(s0, s1, BodyControl.from_numpy(model, sv + centre), 1.0 / FPS)
        s0, s1 = s1, s0
        out.append((s0.numpy()[0].copy(), int(solver.projected.numpy().sum()),
                    int(solver.projection_skipped.numpy().sum())))
    return out


@pytest.mark.parametrize("device", _devices())
def test_skipping_the_inside_test_changes_nothing(sphere, device):
    """With the skip and without: the same positions bitwise in every frame, while the projection
    moved vertices in some frames and, in some frame's last substep, the skip left more than a
    quarter of the square untested (the frames with the sphere beyond the 6 cm query distance test
    every vertex: that test finds no face and is cheap)."""
    with_skip, without = _run(sphere, True, device=device), _run(sphere, False, device=device)
    projected = [p for _, p, _ in with_skip]
    skipped = [s for _, _, s in with_skip]
    n = len(with_skip[0][0])
    print(f"\nprojection skip: vertices projected per frame {projected}; of {n} vertices, tests skipped in each "
          f"frame's last substep {skipped}")
    for k, ((a, _, _), (b, _, s)) in enumerate(zip(with_skip, without)):
        assert np.array_equal(a, b), f"frame {k}: the skip changed positions by up to {np.abs(a - b).max():.3e} m"
        assert s == 0  # off: every vertex tested
    assert sum(projected) > 0  # the sphere went through the cloth: the projection did work
    assert max(skipped) > n // 4  # and part of the square, far from the sphere, went untested


def test_reference_vertex_is_the_one_nearest_the_centroid():
    rest = np.array([[0, 0, 0], [2, 0, 0], [1, 0.1, 0], [5, 5, 5], [5, 5, 6], [5, 5, 5.4]], dtype=float)
    ref = _reference_vertices(rest, np.array([[0, 3], [3, 6], [6, 6]]), 3)
    assert ref.tolist() == [2, 5, -1]


def test_part_vertices_made_once_per_body_are_each_scenes_own(sphere):
    """Three scenes, two of them the same sphere split into two parts, one a sphere split otherwise:
    each (scene, part)'s list is the sorted set of that scene's part's face corners."""
    sv, sf = sphere
    halves = (sv[sf].mean(1)[:, 0] > 0).astype(np.int32)
    thirds = np.minimum((np.arange(len(sf)) * 3) // len(sf), 1).astype(np.int32)
    b = ClothModelBuilder()
    for s, parts in enumerate((halves, thirds, halves)):
        b.add_cloth(*grid(3, 3, 0.01), scene=s)
        b.add_body(sv, sf, scene=s, face_part=parts)
    h = b.finalize("cpu").host
    got, offsets = _part_vertices(h.body_faces, h.body_face_part, h.body_face_range, h.body_ranges, 2)
    assert got.dtype == np.int32 and len(offsets) == 3 * 2 + 1
    for s, (f0, f1) in enumerate(h.body_face_range):
        for p in range(2):
            want = np.unique(h.body_faces[f0:f1][h.body_face_part[f0:f1] == p])
            assert np.array_equal(got[offsets[2 * s + p]:offsets[2 * s + p + 1]], want)
