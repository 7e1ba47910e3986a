"""Paper 000's per-frame node features of a stored sample (torch; numpy in, numpy out too): the one
implementation that the store's reader, the exporters and the trainers share.

- :mod:`datagen.features.binding`: the static part, a garment instance bound to its shaped,
  subdivided body (:func:`body_shape`, :func:`bind_garment`, :func:`subdivided_rows`).
- :mod:`datagen.features.derived`: the per-frame arrays (:func:`derive`: anchors, normals, relative
  skinning features, joint distances, joints, the posed body).
- :mod:`datagen.features.nodes`: the node feature vectors of paper 000's two graphs
  (:func:`coarse_node_features`, :func:`detail_node_features`), for a dataset and a model alike.

It sits above :mod:`datagen.geometry` (rotations, skinning with the one torch SMPL posing
:func:`~datagen.geometry.skinning.pose_shaped`, topology) and below the store, which imports it on
the first derived array. It takes arrays: never a body model object, the store or the targets.
"""

from datagen.features.binding import BodyShape, GarmentBinding, bind_garment, body_shape, subdivided_rows
from datagen.features.derived import DERIVED, derive, joint_distances
from datagen.features.nodes import coarse_node_features, detail_node_features

__all__ = ["DERIVED", "BodyShape", "GarmentBinding", "bind_garment", "body_shape", "coarse_node_features", "derive",
           "detail_node_features", "joint_distances", "subdivided_rows"]
