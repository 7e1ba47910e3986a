"""The long-run check scenes under variants of the solver settings and materials, in one batch per
solver setting (a scene's result does not depend on its batch): the sweep that chose the material
lock and the waistband grip (``docs/simulator.md``; outputs in ``docs/bench/variants/``).

    python benchmarks/bench_sim.py prepare-runs --out .simbench/runs.pkl --frames 300
    python benchmarks/sim_variants.py '{"globals": [{}, {"friction_pressure": 3000}],
        "materials": [{}, {"lock_ratio": 30}, {"grip": 0.9}], "out": "variants.npz"}'

The JSON argument: ``globals``, a list of ``SolverConfig`` keyword sets (one batch each);
``materials``, a list of ``Material`` field overrides applied to every scene's material (``grip``:
the waistband's rest girth as a share of the body's, in place of ``WAISTBAND_GRIP``); ``out``, the
.npz for every scene's per-frame metrics; optional ``inputs`` (default ``.simbench/runs.pkl``),
``device`` (default cuda), ``only`` (scene names), ``max_frames`` and ``run`` (``RunConfig``
fields) for short trials. Prints each scene's failure, largest and mean stretch, most
self-intersections, frames with penetration and largest slip.
"""
import dataclasses
import json
import pickle
import sys
import time

import numpy as np
from datagen.garment.types import WAISTBAND_GRIP
from datagen.sim.scene import RunConfig, scene_arrays, simulate
from datagen.sim.solver import SolverConfig

spec = json.loads(sys.argv[1])  # {"globals": [{solver kwargs}], "materials": [{material kwargs}], "out": path}
with open(spec.get("inputs", ".simbench/runs.pkl"), "rb") as fh:  # our own pickle (bench_sim.py prepare-runs)
    d = pickle.load(fh)
base = [scene_arrays(s, RunConfig().lead_in) for s in d["scenes"]]
if spec.get("max_frames"):
    base = [dataclasses.replace(a, body_frames=a.body_frames[:spec["max_frames"]]) for a in base]
out = {}
for gi, gkw in enumerate(spec["globals"]):
    arrays, names = [], []
    for mi, mkw in enumerate(spec["materials"]):
        for name, a in zip(d["names"], base):
            if spec.get("only") and name not in spec["only"]:
                continue
            kw = dict(mkw)
            grip = kw.pop("grip", None)
            ws = a.weft_scale if grip is None else np.where(a.weft_scale < 1, a.weft_scale * grip / WAISTBAND_GRIP,
                                                            a.weft_scale)
            arrays.append(dataclasses.replace(a, material=dataclasses.replace(a.material, **kw), weft_scale=ws))
            names.append(f"g{gi}m{mi}:{name}")
    cfg = RunConfig(solver=SolverConfig(**gkw), **spec.get("run", {}))
    t0 = time.perf_counter()
    res = simulate(arrays, cfg, device=spec.get("device", "cuda"))
    print(f"globals {gkw}: {len(arrays)} scenes, {time.perf_counter() - t0:.0f} s", flush=True)
    for n, r in zip(names, res):
        s = r.summary()
        mkw = spec["materials"][int(n.split("m")[1].split(":")[0])]
        print(f"{n} {mkw}: fail={r.failure_frame}:{r.failure} stretch {s['stretch_max']:.2f}/{s['stretch_mean']:.3f} "
              f"self-x {s['self_intersections_max']} pen {s['frames_with_penetration']} slip {np.max(r.metrics['slip']):.3f}",
              flush=True)
        for k, v in r.metrics.items():
            out[f"{n}|{k}"] = v
    np.savez_compressed(spec["out"], **out)
