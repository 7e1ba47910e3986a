"""What changes during a run: cloth positions and velocities, and the body collider per frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from datagen.errors import InputError


@dataclass
class ClothState:
    """Particle positions [m] and velocities [m/s], each a warp array of shape [particle_count, 3].

    ``pinned_target`` holds where pinned (inactive) vertices are at the end of the step.
    """

    positions: object
    velocities: object
    pinned_target: object

    @classmethod
    def from_model(cls, model, positions: np.ndarray | None = None) -> ClothState:
        import warp as wp

        x = model.host.rest_positions if positions is None else np.asarray(positions)
        if x.shape != (model.particle_count, 3):
            raise InputError(f"positions must have shape [{model.particle_count}, 3], got {x.shape}")
        with wp.ScopedDevice(model.device):
            p = wp.array(x.astype(np.float32), dtype=wp.vec3)
            return cls(positions=p, velocities=wp.zeros_like(p), pinned_target=wp.clone(p))

    def assign(self, other: ClothState) -> None:
        self.positions.assign(other.positions)
        self.velocities.assign(other.velocities)
        self.pinned_target.assign(other.pinned_target)

    def numpy(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the positions and velocities (on the CPU, warp's .numpy() is a view of the buffer)."""
        return self.positions.numpy().copy(), self.velocities.numpy().copy()


@dataclass
class BodyControl:
    """The body collider at the end of a step: vertices [m] of every scene's body, concatenated in
    scene order, shape [body_vertex_count, 3] (a warp array). The solver interpolates linearly
    from the previous control's vertices within the step, substep by substep."""

    body_vertices: object

    @classmethod
    def from_numpy(cls, model, vertices: np.ndarray) -> BodyControl:
        import warp as wp

        v = np.asarray(vertices, dtype=np.float32)
        if v.shape != (model.body_vertex_count, 3):
            raise InputError(f"body vertices must have shape [{model.body_vertex_count}, 3], got {v.shape}")
        if not np.isfinite(v).all():
            raise InputError("body vertices contain NaN or infinity")
        return cls(body_vertices=wp.array(v, dtype=wp.vec3, device=model.device))

    def set(self, vertices: np.ndarray) -> None:
        """Replace the vertices in place (same shape)."""
        self.body_vertices.assign(np.asarray(vertices, dtype=np.float32))
