"""Geometry shared by every layer: rotations (axis-angle, matrices, 6D), skinning (forward kinematics and
blend skinning), the derived per-frame features of a stored sample, and warp mesh queries."""
