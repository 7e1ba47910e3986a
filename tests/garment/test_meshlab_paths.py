"""pymeshlab's results must not depend on the directory it is imported from.

Some pymeshlab filter defaults are read from uninitialised memory (isotropic remeshing's
``checksurfdist`` in 2025.7), so a default changed with the length of pymeshlab's install path, and
the same garment build gave different meshes in two virtual environments. Every filter is now
called with all of its parameters (:func:`datagen.garment.levelset.apply_meshlab_filter`).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

pymeshlab = pytest.importorskip("pymeshlab")

from datagen.garment.levelset import apply_meshlab_filter  # noqa: E402

_SCRIPT = r"""
import hashlib, json, sys
import numpy as np
import pymeshlab
from skimage import measure
from datagen.garment import levelset
# a bumpy sphere from marching cubes, opened at the top like a garment: rough enough that the
# surface-distance check changes the remeshed mesh (958 vertices with it, 941 without)
x = np.arange(-0.4, 0.4, 0.01)
X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
field = np.sqrt(X**2 + Y**2 + Z**2) - 0.3 - 0.02 * np.sin(25 * X) * np.sin(25 * Y)
v, f, _, _ = measure.marching_cubes(field, 0.0, spacing=(0.01, 0.01, 0.01))
v = v.astype(np.float64)
f = f[v[f].mean(1)[:, 2] < 0.6]
ms = pymeshlab.MeshSet()
ms.add_mesh(pymeshlab.Mesh(v, f.astype(np.int32)))
default = ms.filter_parameter_values("meshing_isotropic_explicit_remeshing")["checksurfdist"]
rv, rf = levelset.remesh(v, f, 0.035, iterations=5)
print(json.dumps({"where": pymeshlab.__file__, "default_checksurfdist": default, "vertices": len(rv),
                  "digest": hashlib.sha256(rv.tobytes() + rf.tobytes()).hexdigest()}))
"""


def test_remeshing_is_the_same_from_any_import_path(tmp_path):
    real = Path(pymeshlab.__file__).parent
    repo = Path(__file__).resolve().parents[2]
    # a short path (under /tmp, 13 characters) read checksurfdist's default as False on the
    # development machine, the long ones as True: the case that changed the garments
    short = Path(tempfile.mkdtemp(prefix=""))
    try:
        results = []
        for d in (short, tmp_path / ("b" * 9), tmp_path / ("c" * 23)):
            d.mkdir(exist_ok=True)
            (d / "pymeshlab").symlink_to(real, target_is_directory=True)
            env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(d), str(repo)]))
            out = subprocess.run([sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True, check=True)
            results.append(json.loads(out.stdout.strip().splitlines()[-1]))
    finally:
        shutil.rmtree(short)
    print("\n" + "\n".join(json.dumps(r) for r in results))
    defaults = {r["default_checksurfdist"] for r in results}
    print("pymeshlab's own default differed between the paths" if len(defaults) > 1 else
          "pymeshlab's own default was the same on these paths (the bug was not triggered here)")
    assert [Path(r["where"]).parent.parent for r in results] == [short, tmp_path / ("b" * 9), tmp_path / ("c" * 23)]
    assert len({(r["vertices"], r["digest"]) for r in results}) == 1, results


def test_a_filter_call_missing_a_parameter_is_refused():
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.eye(3), np.array([[0, 1, 2]], dtype=np.int32)))
    with pytest.raises(RuntimeError, match=r"\['vertdispratio'\] not given"):
        apply_meshlab_filter(ms, "meshing_repair_non_manifold_vertices")
    with pytest.raises(RuntimeError, match=r"\['nonsense'\] not known"):
        apply_meshlab_filter(ms, "meshing_repair_non_manifold_vertices", vertdispratio=0.1, nonsense=1)
