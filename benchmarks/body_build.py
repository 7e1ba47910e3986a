"""Body build time from scratch, cache-hit load time and model file sizes.

Builds into a fresh temporary cache (Anny's own cache is left as it is: its first load on a new
machine adds ~60-90 s, reported separately by timing ``anny.Anny()``).

    python -m benchmarks body-build
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from benchmarks.common import Benchmark, timed


class BodyBuild(Benchmark):
    description = __doc__

    def run(self, args) -> dict:
        """Seconds of each build and load, and the files' sizes [MB], in a temporary cache."""
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["DRAPE_CACHE_DIR"] = tmp
            from datagen.body.anny_builder import AnnyBodyConfig, load_anny
            from datagen.body.cache import body_cache_path, default_body
            from datagen.body.io import save_body_file

            _, t_anny = timed(load_anny)
            model, t_build = timed(default_body)
            _, t_hit = timed(default_body)
            fine, t_sub = timed(lambda: default_body(subdivision_level=1))
            _, t_sub_hit = timed(lambda: default_body(subdivision_level=1))
            pkl = save_body_file(model, Path(tmp) / "body.pkl")
            pkl_sub = save_body_file(fine, Path(tmp) / "body-subdiv.pkl")
            mb = lambda p: Path(p).stat().st_size / 1e6  # noqa: E731
            return {"anny": t_anny, "build": t_build, "hit": t_hit, "sub": t_sub, "sub_hit": t_sub_hit,
                    "npz_mb": mb(body_cache_path(AnnyBodyConfig())), "pkl_mb": mb(pkl), "pkl_sub_mb": mb(pkl_sub),
                    "vertices": model.vertex_count, "sub_vertices": fine.vertex_count}

    def report(self, r: dict) -> None:
        print(f"Anny load (its own cache {'warm' if r['anny'] < 20 else 'cold'}): {r['anny']:.1f} s")
        print(f"build from scratch (incl. Anny load): {r['anny'] + r['build']:.1f} s; drape's part: {r['build']:.1f} s")
        print(f"cache-hit load: {r['hit']:.2f} s (base), {r['sub_hit']:.2f} s (subdivided); subdivision build "
              f"{r['sub']:.1f} s")
        print(f"files: cache npz {r['npz_mb']:.1f} MB, pkl {r['pkl_mb']:.1f} MB (base, {r['vertices']} v); "
              f"pkl {r['pkl_sub_mb']:.1f} MB (subdivided, {r['sub_vertices']} v)")


main = BodyBuild().main
