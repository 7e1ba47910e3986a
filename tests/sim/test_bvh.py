"""warp's grouped BVH, as the solver and the metrics use it (one tree for a batch's scenes, each
query starting at its scene's group root): queries return exactly the brute-force overlaps of
their own group, after the build and after a refit."""

from __future__ import annotations

import numpy as np
import warp as wp


@wp.kernel
def _query(bvh: wp.uint64, lo: wp.array(dtype=wp.vec3), hi: wp.array(dtype=wp.vec3), group: wp.array(dtype=wp.int32),
           same: wp.array(dtype=wp.int32), other: wp.array(dtype=wp.int32)):
    i = wp.tid()
    q = wp.bvh_query_aabb(bvh, lo[i], hi[i], wp.bvh_get_group_root(bvh, group[i]))
    t = int(0)  # noqa: UP018, RUF046 (warp: a mutable int in the loop)
    n = int(0)  # noqa: UP018, RUF046
    m = int(0)  # noqa: UP018, RUF046
    while wp.bvh_query_next(q, t):
        if group[t] == group[i]:
            n += 1
        else:
            m += 1
    same[i] = n
    other[i] = m


def _expected(lo, hi, group):
    overlap = np.all((lo[:, None] <= hi[None]) & (hi[:, None] >= lo[None]), axis=-1)
    return (overlap & (group[:, None] == group[None])).sum(1)


def test_grouped_bvh_queries_return_their_own_groups_overlaps():
    rng = np.random.default_rng(0)
    n, groups = 400, 3
    lo = rng.random((n * groups, 3)).astype(np.float32)  # the groups overlap in space, like scenes
    hi = lo + 0.05
    group = np.repeat(np.arange(groups), n).astype(np.int32)
    with wp.ScopedDevice("cpu"):
        L, H, G = wp.array(lo, dtype=wp.vec3), wp.array(hi, dtype=wp.vec3), wp.array(group)
        bvh = wp.Bvh(L, H, groups=G)
        for step in range(2):
            if step:  # move every box, refit, query again
                lo = (lo + rng.normal(0.0, 0.05, lo.shape)).astype(np.float32)
                hi = lo + 0.05
                L.assign(lo)
                H.assign(hi)
                bvh.refit()
            same, other = wp.zeros(len(lo), dtype=wp.int32), wp.zeros(len(lo), dtype=wp.int32)
            wp.launch(_query, len(lo), inputs=[bvh.id, L, H, G, same, other])
            assert other.numpy().sum() == 0
            np.testing.assert_array_equal(same.numpy(), _expected(lo, hi, group))
