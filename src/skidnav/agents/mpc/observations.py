"""What ``mppi-kinematic`` reads of an observation: the pose, and the lidar readings of a
feature observation (the env's ``"features"``: x, y, cos ψ, sin ψ, the goal's three features,
then the k lidar ranges)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def pose_of(observation: Any, lidar_rays: int) -> np.ndarray:
    """The pose (x [m], y [m], heading [rad]) float64 (3,) of a pose observation (3,) or of a
    feature observation (7 + ``lidar_rays``,) (x, y, cos ψ, sin ψ, …); ValueError otherwise."""
    values = np.asarray(observation, dtype=np.float64)
    if values.shape == (3,):
        pose = values.copy()
    elif values.shape == (7 + lidar_rays,):
        pose = np.array([values[0], values[1], math.atan2(values[3], values[2])])
    else:
        raise ValueError(
            f"expected a pose (3,) or a feature observation ({7 + lidar_rays},), got shape "
            f"{values.shape}"
        )
    if not np.isfinite(pose).all():
        raise ValueError("expected a finite pose")
    return pose


def ranges_of(observation: Any, lidar_rays: int) -> np.ndarray:
    """The lidar readings [m] float64 (``lidar_rays``,) of a feature observation (its entries
    7 onwards), or (0,) for a pose observation (which holds none)."""
    values = np.asarray(observation, dtype=np.float64)
    if values.shape == (7 + lidar_rays,):
        return np.ascontiguousarray(values[7:])
    return np.zeros(0)
