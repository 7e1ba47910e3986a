"""The body as the pattern programs see it: girth profiles and the placement frame.

Programs read only :class:`~datagen.body.measurements.BodyMeasurements`, so one design fits every
body shape: girths along the torso, an arm and a leg are interpolated between the measured
levels, and garments add their ease to them.

Placement frame: panel y is height above the floor, so a panel's translation adds the body's
``floor_y``; x = 0 is the body's midline and z = ``centre_z`` the torso's vertical axis (both from
the measurements). Panels stand on the circle of the garment's girth round that axis
(:func:`ring_radius`); placement pushes out what enters the body.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from datagen.body.measurements import BodyMeasurements

__all__ = ["Frame", "arm_girth", "frame", "leg_girth", "ring_radius", "torso_girth"]


@dataclass(frozen=True, kw_only=True)
class Frame:
    """Where the measurements' coordinates sit in the body's rest frame [m]."""

    floor_y: float
    centre_z: float


def frame(m: BodyMeasurements) -> Frame:
    """The body's floor height and torso axis in its rest frame."""
    return Frame(floor_y=float(m.floor_y), centre_z=float(m.centre_z))


def torso_girth(m: BodyMeasurements, y) -> np.ndarray:
    """Torso girth [m] at heights ``y`` [m] above the floor, interpolated between the measured
    levels (chest above the chest line, hip below the hip line down to the crotch)."""
    levels = sorted([(m.crotch_height, m.hip), (m.hip_height, m.hip), (m.waist_height, m.waist),
                     (m.underbust_height, m.underbust), (m.chest_height, m.chest),
                     (max(m.armpit_height, m.chest_height + 1e-3), m.chest)])
    ys = np.array([a for a, _ in levels])
    gs = np.array([b for _, b in levels])
    return np.interp(np.asarray(y, float), ys, gs)


def ring_radius(girth: float) -> float:
    """Distance [m] from the torso's axis at which the flat panels of a garment ``girth`` [m] round
    are placed: the radius of a circle of that girth, so that front and back panels bent round the
    axis (``place(..., "wrap")``) close the ring. (4 cm further out, the sewn pairs of the wrapped
    panels started 8-25 cm apart instead of 2-17 cm, survey of 18 designs x 3 bodies.)"""
    return girth / (2 * math.pi)


def arm_girth(m: BodyMeasurements, t) -> np.ndarray:
    """Arm girth [m] at fraction ``t`` of the arm's length from the shoulder point (0) to the wrist
    (1): the upper arm's to a quarter, the wrist's at the end, the elbow (a half) between them."""
    elbow = 0.5 * (m.upper_arm + m.wrist) * 1.05
    return np.interp(np.asarray(t, float), [0.0, 0.25, 0.5, 1.0], [m.upper_arm * 1.05, m.upper_arm, elbow, m.wrist])


def leg_girth(m: BodyMeasurements, y) -> np.ndarray:
    """Leg girth [m] at heights ``y`` [m] above the floor: thigh just below the crotch, knee, ankle."""
    ys = [m.ankle_height, m.knee_height, m.crotch_height - 0.02]
    gs = [m.ankle, m.knee, m.thigh]
    if not ys[0] < ys[1] < ys[2]:  # a degenerate body: keep the profile monotone in height
        ys = sorted(ys)
    return np.interp(np.asarray(y, float), ys, gs)
