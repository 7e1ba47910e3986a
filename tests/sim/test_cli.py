"""``drape simulate``: input errors (one line, exit status 2, before any simulation) and the file it writes."""

import numpy as np
import pytest

from datagen.cli import main


def test_simulate_rejects_bad_output_and_unknown_garment(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path / "run.txt")]) == 2
    assert "argument --out: " + str(tmp_path / "run.txt") + " must end in .npz" in capsys.readouterr().err
    assert main(["simulate", "--out", str(tmp_path / "missing" / "run.npz")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["simulate", "--frames", "0", "--out", str(tmp_path / "run.npz")]) == 2
    assert "argument --frames: 0 is out of range: give 1 or more" in capsys.readouterr().err


@pytest.mark.slow
def test_simulate_writes_an_animation_that_export_reads_as_it_is(tmp_path, capsys, default_body):
    """``drape simulate`` records the body it collided with, the poses and the garment's panels:
    the exporters read the file without making the garment or the motion again. The recorded body
    is the named body posed over the motion's recorded frames (those after the ramp)."""
    from datagen.body.shapes import resolve_betas
    from datagen.export.animation import from_npz
    from datagen.motion.library import make_motion
    from datagen.sim.scene import RunConfig

    out = tmp_path / "run.npz"
    code = main(["simulate", "--garment", "skirt", "--body", "thin", "--motion", "wave", "--motion-seed", "2",
                 "--frames", "3", "--substeps", "1", "--iterations", "1", "--no-self-collision", "--out", str(out)])
    assert code in (0, 1) and f"wrote {out}" in capsys.readouterr().out
    a = from_npz(out)
    T = 3
    motion_from = RunConfig().ramp_frames(30.0)[1]
    motion = make_motion("wave", seed=2, frames=RunConfig().motion_frames(T, 30.0), fps=30.0)
    betas = resolve_betas(default_body, body="thin")[0]
    expected, _ = default_body.pose(np.repeat(betas[None], T, 0), motion.poses[motion_from:].reshape(T, -1),
                                    motion.trans[motion_from:])
    assert a.garment_vertices.shape[0] == T and a.body_vertices.shape == expected.shape
    np.testing.assert_allclose(a.body_vertices, expected, atol=1e-5)
    np.testing.assert_allclose(a.skeleton.poses, motion.poses[motion_from:], atol=1e-6)
    assert a.region is not None and len(a.region_names) == 2 and a.garment_rest.shape == a.garment_vertices.shape[1:]
    assert a.metadata["garment_type"] == "skirt" and a.metadata["motion_seed"] == 2 and a.metadata["body"] == "thin"
    assert a.metadata["motion_from"] == motion_from
