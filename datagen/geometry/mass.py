"""Height, volume, mass and BMI of a closed body mesh (maths on arrays): what ``drape body info``
reports for a body shape and what a dataset card (:mod:`datagen.store.card`) gives for its bodies."""

from __future__ import annotations

import numpy as np

BODY_DENSITY = 985.0
"""Mean density of the human body [kg/m^3], to turn mesh volume into mass."""


def measure(vertices: np.ndarray, faces: np.ndarray) -> dict[str, float]:
    """Height [m] (vertical extent, Y up), volume [m^3], mass [kg] and BMI [kg/m^2] of a closed
    body mesh [V, 3] (faces [F, 3]) in a pose with straight legs (the rest pose)."""
    import trimesh

    vertices = np.asarray(vertices, dtype=np.float64)
    mesh = trimesh.Trimesh(vertices, np.asarray(faces), process=False)
    height = float(vertices[:, 1].max() - vertices[:, 1].min())
    volume = float(abs(mesh.volume))
    mass = volume * BODY_DENSITY
    return {"height_m": height, "volume_m3": volume, "mass_kg": mass, "bmi": mass / height**2}
