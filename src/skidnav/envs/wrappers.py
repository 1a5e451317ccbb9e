"""Wrappers of the skid-steer env that change what an agent observes.

:class:`FineStates` gives a tabular agent the flat state of its pose on a grid finer than the
env's own (the discretization-gap study, the optimum on finer grids).
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

from skidnav.world.discretization import Discretization


class FineStates(gymnasium.ObservationWrapper[int, int, np.ndarray]):
    """A skid-steer env with ``observation="pose"`` whose observation is the flat state of the
    pose on ``grid`` (``Discrete(grid.n_states)``); rewards, termination and info are the env's.

    Args:
        env: the skid-steer env (``observation="pose"``, unwrapped or not).
        grid: the finer state grid (same arena as the env's).
    """

    def __init__(self, env: gymnasium.Env[np.ndarray, int], grid: Discretization) -> None:
        super().__init__(env)
        if getattr(env.unwrapped, "observation_kind", None) != "pose":
            raise ValueError("expected a skid-steer env with observation='pose'")
        self.discretization = grid
        self.observation_space = gymnasium.spaces.Discrete(grid.n_states)  # type: ignore[assignment]

    def observation(self, observation: np.ndarray) -> int:
        """Flat state on the fine grid of a pose (x [m], y [m], heading [rad])."""
        return self.discretization.state(observation[0], observation[1], observation[2])


def fine_grid(env: Any) -> Discretization | None:
    """The finer grid of a :class:`FineStates` env, None for any other env."""
    return env.discretization if isinstance(env, FineStates) else None
