"""Kept until training/ and sim/ move over: the old import path of paper 000's features.

They now live in :mod:`datagen.features` (above geometry, below the store) and the normals in
:mod:`datagen.geometry.topology`. Import from there; this module and its ``ignore_imports`` lines
in pyproject.toml's import contracts go once training/ has moved.
"""

from datagen.features.binding import BodyShape, GarmentBinding, bind_garment, body_shape, subdivided_rows
from datagen.features.derived import DERIVED, derive, joint_distances
from datagen.geometry.topology import vertex_normals

__all__ = ["DERIVED", "BodyShape", "GarmentBinding", "bind_garment", "body_shape", "derive", "joint_distances",
           "subdivided_rows", "vertex_normals"]
