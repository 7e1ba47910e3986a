"""Small cloth meshes shared by the simulator's tests."""

from __future__ import annotations

import numpy as np


def grid(nx: int, nz: int, dx: float, *, y: float = 0.0, centre=(0.0, 0.0)):
    """A flat nx x nz vertex grid of spacing dx in the plane y = const, centred on (x, z) = centre,
    two triangles per cell with normals +Y."""
    xs = centre[0] + (np.arange(nx) - (nx - 1) / 2) * dx
    zs = centre[1] + (np.arange(nz) - (nz - 1) / 2) * dx
    X, Z = np.meshgrid(xs, zs, indexing="ij")
    v = np.stack([X.ravel(), np.full(X.size, float(y)), Z.ravel()], 1)
    faces = []
    for i in range(nx - 1):
        for j in range(nz - 1):
            a, b, c, d = i * nz + j, (i + 1) * nz + j, (i + 1) * nz + j + 1, i * nz + j + 1
            faces += [[a, d, c], [a, c, b]]
    return v, np.array(faces)
