"""Policies that choose both wheel speeds: the contract every continuous-action learner meets.

With ``action="continuous"`` the navigation env takes an action (ω_L, ω_R) [rad/s] within
± ``robot.wheel_speed`` (:class:`skidnav.envs.navigation.SkidSteerNavEnv`). A learner of such
actions (policy search, actor-critic deep RL) hands out a frozen :class:`WheelSpeedPolicy`: a
deterministic map from the env's ``observation="features"`` vector (pose, goal distance and
bearing, lidar ranges: :mod:`skidnav.sim.features`) to the two wheel speeds. The comparisons,
the pictures and the real-time loop use policies only through this contract, so any learner's
policy runs anywhere the others do.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class WheelSpeedPolicy(Protocol):
    """A deterministic policy over the feature observation.

    Attributes:
        lidar_rays: the k range readings its observations carry (the env's ``lidar_rays``).
        lidar_range: their largest reading [m] (the env's ``lidar_range``).
    """

    lidar_rays: int
    lidar_range: float

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s] for the feature observation float64 (7 + k,); the env clips them
        to its box."""
        ...
