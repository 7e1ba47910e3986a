"""The global step's per-scene dot products (``newton_kernels.scene_dot``, one block of threads per
scene) are the float64 dot product of each scene's vertices, with warp's blocks of one thread (the
CPU's default) and of ``DOT_LANES`` threads (``warp.config.enable_cpu_blocks``, the GPU's shape):
every vertex of the scene is added once, none of another scene."""

from __future__ import annotations

import numpy as np


def test_scene_dot_is_the_dot_product_of_each_scene():
    import warp as wp

    from datagen.sim import newton_kernels as N

    rng = np.random.default_rng(0)
    n = 1000
    ranges = np.array([[0, 0], [0, 1], [1, 300], [300, 1000]], dtype=np.int32)  # empty, one vertex, two long
    a_np, b_np = rng.normal(size=(n, 3)).astype(np.float32), rng.normal(size=(n, 3)).astype(np.float32)
    want = [float((a_np[p0:p1].astype(np.float64) * b_np[p0:p1]).sum()) for p0, p1 in ranges]
    a, b = wp.array(a_np, dtype=wp.vec3, device="cpu"), wp.array(b_np, dtype=wp.vec3, device="cpu")
    saved = wp.config.enable_cpu_blocks
    try:
        for blocks in (False, True):
            wp.config.enable_cpu_blocks = blocks
            out = wp.zeros(len(ranges), dtype=wp.float64, device="cpu")
            wp.launch_tiled(N.scene_dot, dim=[len(ranges)], block_dim=N.DOT_LANES, device="cpu",
                            inputs=[a, b, wp.array(ranges, dtype=wp.int32, device="cpu"), out])
            np.testing.assert_allclose(out.numpy(), want, rtol=1e-6, atol=1e-9)
    finally:
        wp.config.enable_cpu_blocks = saved
