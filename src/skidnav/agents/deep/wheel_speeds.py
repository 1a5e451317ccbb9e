"""What PPO and SAC share: deep agents whose actions are the two wheel speeds.

They train on the env's ``action="continuous"`` box (ω_L, ω_R) within ± ``robot.wheel_speed``
[rad/s] as it is: Stable-Baselines3 clips a Gaussian action to the box (PPO) or squashes it into
the box with tanh (SAC), so the actions reach the env in rad/s and nothing rescales them here.
The observation must be the env's ``"features"`` (:mod:`skidnav.sim.features`), so that the
frozen policy meets :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`.
"""

from __future__ import annotations

import copy
from pathlib import Path
from types import SimpleNamespace
from typing import Any, TypeVar

import gymnasium
import numpy as np

from skidnav.agents.deep.common import (
    ConfigT,
    DeepAgent,
    deterministic_action,
    load_agent,
    observation_scaler,
)
from skidnav.agents.deep.spaces import SavedSpaces
from skidnav.errors import CorruptFileError, first_line


class FrozenWheelPolicy:
    """A deep agent's deterministic policy, frozen: a copy of its acting network that later
    training does not change (a :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`).

    Attributes:
        lidar_rays: the range readings its observations carry.
        lidar_range: their largest reading [m].
    """

    def __init__(
        self,
        network: Any,
        observation_space: gymnasium.spaces.Box,
        lidar_rays: int,
        lidar_range: float,
    ) -> None:
        self._network = copy.deepcopy(network)
        self._network.requires_grad_(False)
        self._scale = observation_scaler(observation_space)
        self.lidar_rays, self.lidar_range = lidar_rays, lidar_range

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s] for the feature observation float64 (7 + k,), within the env's
        box."""
        left, right = deterministic_action(self._network, self._scale, observation).tolist()
        return float(left), float(right)


class WheelSpeedAgent(DeepAgent[ConfigT]):
    """A deep agent over the feature observation with the wheel-speed box as its actions."""

    action_space_class = gymnasium.spaces.Box

    def __init__(
        self, env: gymnasium.Env[Any, Any], config: ConfigT | None = None, seed: int = 0
    ) -> None:
        features = getattr(env.unwrapped, "features", None)
        rays = getattr(features, "lidar_rays", -1)
        space = env.observation_space
        if not isinstance(space, gymnasium.spaces.Box) or space.shape != (7 + rays,):
            raise ValueError(
                f"{self.name}: expected the feature observation (observation='features')"
            )
        if isinstance(env.action_space, gymnasium.spaces.Box) and env.action_space.shape != (2,):
            raise ValueError(f"{self.name}: expected two wheel speeds (action='continuous')")
        self.lidar_rays, self.lidar_range = int(rays), float(features.lidar_range)  # type: ignore[union-attr]
        super().__init__(env, config, seed)

    def extra_meta(self) -> dict[str, Any]:
        """The range readings of the observation, saved for :class:`SavedWheelSpaces`."""
        return {"lidar_rays": self.lidar_rays, "lidar_range": self.lidar_range}

    def greedy_action(self, observation: np.ndarray) -> np.ndarray:
        """The deterministic wheel speeds (ω_L, ω_R) [rad/s] at ``observation``, float32 (2,)."""
        return np.asarray(super().greedy_action(observation), dtype=np.float32)

    def policy(self) -> FrozenWheelPolicy:
        """The current deterministic policy, frozen."""
        space = self.scaled.env.observation_space
        assert isinstance(space, gymnasium.spaces.Box)
        return FrozenWheelPolicy(self.network(), space, self.lidar_rays, self.lidar_range)


WheelAgentT = TypeVar("WheelAgentT", bound=WheelSpeedAgent[Any])


class SavedWheelSpaces(SavedSpaces):
    """The spaces of a saved wheel-speed agent's ``.json``, with the range readings its feature
    observation carries (``features``: ``lidar_rays``, ``lidar_range``), as the agent asks its
    env for them."""

    def __init__(self, meta: dict[str, Any]) -> None:
        if "action_low" not in meta:
            raise ValueError("expected the bounds of the wheel speeds")
        super().__init__(meta)
        high = self.observation_space.high
        rays, reach = meta["lidar_rays"], meta["lidar_range"]
        if type(rays) is not int or rays < 0 or high.shape != (7 + rays,):
            raise ValueError("expected the bounds of a feature observation with its lidar_rays")
        if type(reach) is not float or not reach > 0 or (rays > 0 and reach != high[-1]):
            raise ValueError("expected lidar_range to be the bound of the range readings")
        self.features = SimpleNamespace(lidar_rays=rays, lidar_range=float(reach))


def saved_policy(
    agent_class: type[WheelAgentT], json_path: str | Path, meta: dict[str, Any]
) -> FrozenWheelPolicy:
    """The frozen policy of an ``agent_class`` saved at ``json_path`` (``meta``: its parsed
    content), without the env it learned in; CorruptFileError in one line naming the file."""
    try:
        spaces = SavedWheelSpaces(meta)
    except (KeyError, TypeError, ValueError, OverflowError) as error:  # overflow: a huge integer
        raise CorruptFileError(f"{json_path}: cannot load policy: {first_line(error)}") from None
    return load_agent(agent_class, json_path, spaces).policy()
