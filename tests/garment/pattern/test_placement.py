"""Placement around the body: nothing inside it, wrapping isometric and closer to sewn than flat."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from datagen.errors import InputError
from datagen.garment.pattern.mesh import mesh_pattern
from datagen.garment.pattern.placement import CLEARANCE, place, placement_report
from datagen.garment.pattern.spec import read_spec

SHIRT = Path(__file__).parent / "fixtures" / "garmentcode_hoody_mean_specification.json"


@pytest.fixture(scope="module")
def fat_body(default_body):
    from datagen.body.shapes import resolve_betas

    betas = resolve_betas(default_body, body="fat")[0]
    return np.asarray(default_body.shaped(betas))[0], np.asarray(default_body.faces)


@pytest.fixture(scope="module")
def hoody_mesh(fat_body):
    pat = read_spec(SHIRT)
    floor = float(fat_body[0][:, 1].min())  # GarmentCode's frame stands on y = 0
    pat = dataclasses.replace(pat, panels=tuple(
        dataclasses.replace(p, translation=(p.translation[0], p.translation[1] + floor, p.translation[2]))
        for p in pat.panels))
    return mesh_pattern(pat, 0.03)


def test_flat_placement_is_the_patterns_own(hoody_mesh, fat_body):
    pos = place(hoody_mesh, *fat_body, mode="flat")
    r = placement_report(hoody_mesh, pos, *fat_body)
    assert r.vertices_inside == 0 and r.min_clearance >= CLEARANCE - 1e-4
    # away from the body every vertex is exactly where the panel's rotation and translation put it
    panel = hoody_mesh.pattern.panels[0]
    sel = hoody_mesh.panel_id == 0
    ref = panel.to_3d(hoody_mesh.rest_uv[sel])
    moved = np.linalg.norm(pos[sel] - ref, axis=1) > 1e-9
    assert moved.mean() < 0.5
    np.testing.assert_allclose(pos[sel][~moved], ref[~moved])


def test_wrap_is_isometric_outside_the_body_and_sews_closer(hoody_mesh, fat_body):
    flat = placement_report(hoody_mesh, place(hoody_mesh, *fat_body, mode="flat"), *fat_body)
    wrap = placement_report(hoody_mesh, place(hoody_mesh, *fat_body, mode="wrap"), *fat_body)
    assert wrap.vertices_inside == 0 and wrap.min_clearance >= CLEARANCE - 1e-4
    assert wrap.stitch_gap_mean < 0.9 * flat.stitch_gap_mean
    # bending keeps the flat rest lengths (up to chords of the cylinder); the push out of the fat
    # body stretches where a panel cut into it
    bent = placement_report(hoody_mesh, place(hoody_mesh, *fat_body, mode="wrap", push=False), *fat_body)
    assert bent.stretch_max < 0.01


def test_bad_mode_and_body_are_refused(hoody_mesh, fat_body):
    with pytest.raises(InputError, match="'flat' or 'wrap'"):
        place(hoody_mesh, *fat_body, mode="drape")
    with pytest.raises(InputError, match=r"vertices \[V, 3\]"):
        place(hoody_mesh, fat_body[0][:, :2], fat_body[1])


def test_placed_panels_keep_apart_from_each_other(hoody_mesh, fat_body):
    """No two panels start closer than SEPARATION (but at the vertices sewn to each other), in either
    mode: the simulator's cloth-cloth contact (4 mm, queried at 10 mm) would burst them apart."""
    from scipy.spatial import cKDTree

    from datagen.garment.pattern.placement import SEPARATION

    sewn = np.zeros(hoody_mesh.vertex_count, dtype=bool)
    sewn[hoody_mesh.stitch_pairs.ravel()] = True
    free = np.flatnonzero(~sewn)
    for mode in ("flat", "wrap"):
        pos = place(hoody_mesh, *fat_body, mode=mode)
        pairs = cKDTree(pos[free]).query_pairs(0.9 * SEPARATION, output_type="ndarray")
        pid = hoody_mesh.panel_id[free]
        close = pid[pairs[:, 0]] != pid[pairs[:, 1]] if len(pairs) else np.zeros(0, bool)
        assert not close.any(), f"{mode}: {int(close.sum())} vertex pairs of two panels closer than {SEPARATION} m"


def test_trouser_legs_are_bent_round_their_own_leg(default_body):
    """A trouser leg's front and back panels (``Panel.limb``) are bent into half tubes round their own
    leg: bending keeps the flat rest lengths, the left leg's panels lie left of the right leg's at
    the hem (laid flat in front of both legs, the front panels overlapped by their crotch extensions
    and crossed each other when sewn), and a leg's inside-leg seam starts closer than flat."""
    from datagen.body.measurements import measure_body
    from datagen.body.shapes import resolve_betas
    from datagen.garment.pattern.programs import make_pattern

    betas = resolve_betas(default_body, body="regular")[0]
    bv, bf = np.asarray(default_body.shaped(betas))[0], np.asarray(default_body.faces)
    pat = make_pattern("trousers", 0, measure_body(default_body, betas))
    assert [p.limb for p in pat.panels[:4]] == [True] * 4
    mesh = mesh_pattern(pat, 0.03)
    bent = place(mesh, bv, bf, mode="flat", push=False)
    # each limb panel on its own cylinder: lengths kept (chords aside)
    limb = np.isin(mesh.panel_id, [0, 1, 2, 3])
    e = np.unique(np.sort(np.concatenate([mesh.faces[:, [0, 1]], mesh.faces[:, [1, 2]]]), axis=1), axis=0)
    e = e[limb[e[:, 0]]]
    rest = np.linalg.norm(mesh.rest_uv[e[:, 0]] - mesh.rest_uv[e[:, 1]], axis=1)
    now = np.linalg.norm(bent[e[:, 0]] - bent[e[:, 1]], axis=1)
    assert np.abs(now / rest - 1).max() < 0.01
    pos = place(mesh, bv, bf, mode="flat")
    names = [p.name for p in pat.panels]
    hem = pos[:, 1] < np.percentile(pos[limb, 1], 20)
    left = hem & np.isin(mesh.panel_id, [names.index("front_left"), names.index("back_left")])
    right = hem & np.isin(mesh.panel_id, [names.index("front_right"), names.index("back_right")])
    assert pos[left, 0].min() > pos[right, 0].max()
    assert placement_report(mesh, pos, bv, bf).vertices_inside == 0
    flat = place(dataclasses.replace(mesh, pattern=dataclasses.replace(pat, panels=tuple(
        dataclasses.replace(p, limb=False) for p in pat.panels))), bv, bf, mode="flat")
    fl = names.index("front_left")
    inseam = mesh.edge_vertices[(fl, pat.panels[fl].edge_groups["inseam"][0])]
    pairs = mesh.stitch_pairs[np.isin(mesh.stitch_pairs, inseam).any(1)]
    gap = lambda x: np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1).mean()  # noqa: E731
    assert gap(pos) < 0.8 * gap(flat)
