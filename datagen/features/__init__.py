"""Paper 000's per-frame node features of a stored sample (torch; numpy in, numpy out too): the one
implementation that the store's reader, the exporters and the trainers share.

- :mod:`datagen.features.binding`: the static part, a garment instance bound to its shaped,
  subdivided body (:func:`body_shape`, :func:`bind_garment`, :func:`subdivided_rows`).
- :mod:`datagen.features.derived`: the per-frame arrays (:func:`derive`: anchors, normals, relative
  skinning features, joint distances, joints, the posed body).
Paper 000's GNN assembles its node vectors from these in one function,
:func:`training.gnn.features.node_features`, used by its dataset and its module alike.

It sits above :mod:`datagen.geometry` (rotations, skinning with the one torch SMPL posing
:func:`~datagen.geometry.skinning.pose_shaped`, topology) and below the store, which imports it on
the first derived array. It takes arrays: never a body model object, the store or the targets.
"""

from datagen.features.binding import BodyShape, GarmentBinding, bind_garment, body_shape, subdivided_rows
from datagen.features.derived import DERIVED, derive, joint_distances

__all__ = ["DERIVED", "BodyShape", "GarmentBinding", "bind_garment", "body_shape", "derive", "joint_distances",
           "subdivided_rows"]
