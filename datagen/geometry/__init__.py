"""Geometry shared by every layer, as maths on arrays: rotations (axis-angle, matrices, 6D), skinning
(forward kinematics, blend skinning and the one torch SMPL posing), mesh topology (unique edges,
vertex-face incidence, vertex normals), the store's quantised positions, and warp mesh queries.
It never imports the store or its layout (an import contract); paper 000's features built on it
are :mod:`datagen.features`."""
