"""Geometry shared by the inputs and the simulator: rotations (axis-angle, matrices, 6D) and warp mesh queries."""
