"""Body build time from scratch, cache-hit load time and model file sizes.

Builds into a fresh temporary cache (Anny's own cache is left as it is: its first load on a new
machine adds ~60-90 s, reported separately by timing ``anny.Anny()``).

    python benchmarks/bench_body_build.py
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["DRAPE_CACHE_DIR"] = tmp
        from datagen.body.anny_builder import load_anny
        from datagen.body.cache import body_cache_path, default_body
        from datagen.body.io import save_body_file

        t0 = time.perf_counter()
        load_anny()
        t_anny = time.perf_counter() - t0
        t0 = time.perf_counter()
        model = default_body()
        t_build = time.perf_counter() - t0
        t0 = time.perf_counter()
        default_body()
        t_hit = time.perf_counter() - t0
        t0 = time.perf_counter()
        fine = default_body(subdivision_level=1)
        t_sub = time.perf_counter() - t0
        t0 = time.perf_counter()
        default_body(subdivision_level=1)
        t_sub_hit = time.perf_counter() - t0
        pkl = save_body_file(model, Path(tmp) / "body.pkl")
        pkl_sub = save_body_file(fine, Path(tmp) / "body-subdiv.pkl")
        size = lambda p: f"{Path(p).stat().st_size / 1e6:.1f} MB"  # noqa: E731
        print(f"Anny load (its own cache {'warm' if t_anny < 20 else 'cold'}): {t_anny:.1f} s")
        print(f"build from scratch (incl. Anny load): {t_anny + t_build:.1f} s; drape's part: {t_build:.1f} s")
        print(f"cache-hit load: {t_hit:.2f} s (base), {t_sub_hit:.2f} s (subdivided); subdivision build {t_sub:.1f} s")
        print(f"files: cache npz {size(body_cache_path(__import__('datagen.body.anny_builder', fromlist=['x']).AnnyBodyConfig()))}, "
              f"pkl {size(pkl)} (base, {model.vertex_count} v); pkl {size(pkl_sub)} (subdivided, {fine.vertex_count} v)")


if __name__ == "__main__":
    main()
