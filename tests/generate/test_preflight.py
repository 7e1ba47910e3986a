"""``drape generate``'s checks before anything is written: host memory for a batch's posed bodies."""

from __future__ import annotations

import pytest

import datagen.sim.device as device
from datagen.errors import InputError
from datagen.generate.config import resolve_config, with_batch_size
from datagen.generate.plan import Plan
from datagen.generate.run import BODY_BYTES_PER_VERTEX_FRAME, POSING_BYTES_PER_VERTEX_FRAME, preflight, simulated_frames


def test_memory_for_posed_bodies_counts_each_body_motion_once(tmp_path, monkeypatch):
    """paper-motion in one batch of 252 scenes poses 84 motions on one body, not 252 bodies: the
    estimate is what those 84 keep plus the posings running at once, and a machine with less is
    refused with the figures and what to lower."""
    plan = Plan(with_batch_size(resolve_config(preset="paper-motion"), 252))
    frames, verts = simulated_frames(plan), int(plan.body_model.v_template.shape[0])
    monkeypatch.setattr("os.cpu_count", lambda: 16)
    import collections

    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr("shutil.disk_usage", lambda _p: usage(2**50, 0, 2**50))  # the disk check is another test's
    need = frames * verts * (84 * BODY_BYTES_PER_VERTEX_FRAME + 16 * POSING_BYTES_PER_VERTEX_FRAME)
    assert need < 10 * 2**30  # the old per-scene float64 estimate said 46.5 GiB
    monkeypatch.setattr(device, "available_ram", lambda: need + 1)
    preflight(plan, tmp_path / "ok.zarr", executor="local", device="cpu", workers=0)
    monkeypatch.setattr(device, "available_ram", lambda: need - 1)
    with pytest.raises(InputError, match=r"252 scenes of 309 simulated frames needs about .* simulation.batch_size"):
        preflight(plan, tmp_path / "no.zarr", executor="local", device="cpu", workers=0)
    assert not (tmp_path / "no.zarr").exists()
