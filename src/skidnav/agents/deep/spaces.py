"""A saved deep agent's spaces without its world: the env its network is rebuilt on away from
the world it learned in (the real-time loop, :mod:`skidnav.agents.deep.family`'s policies)."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

from skidnav.agents.deep.common import MAX_COUNT
from skidnav.errors import shown


class SavedSpaces(gymnasium.Env[np.ndarray, Any]):
    """Only the spaces of a saved agent's ``.json`` (its observation bounds and
    :func:`~skidnav.agents.deep.common.action_meta`): enough to rebuild its network away from
    the world it learned in (the real-time loop); it cannot be stepped. ValueError (KeyError,
    TypeError) for a ``.json`` without them."""

    observation_space: gymnasium.spaces.Box

    def __init__(self, meta: dict[str, Any]) -> None:
        low, high = (
            np.asarray(meta[k], dtype=np.float64) for k in ("observation_low", "observation_high")
        )
        if low.ndim != 1 or high.shape != low.shape or not (low < high).all():
            raise ValueError("expected lower observation bounds below upper ones")
        self.observation_space = gymnasium.spaces.Box(low, high, dtype=np.float64)
        self.action_space = saved_action_space(meta)


def saved_action_space(meta: dict[str, Any]) -> gymnasium.Space[Any]:
    """The action space :func:`~skidnav.agents.deep.common.action_meta` describes in ``meta``;
    ValueError (KeyError, TypeError) when it describes none."""
    if "n_actions" in meta:
        n = meta["n_actions"]
        if type(n) is not int or not 1 <= n <= MAX_COUNT:
            raise ValueError(f"expected n_actions to be an integer >= 1, got {shown(n)}")
        return gymnasium.spaces.Discrete(n)
    slowest, fastest = (
        np.asarray(meta[k], dtype=np.float32) for k in ("action_low", "action_high")
    )
    if slowest.ndim != 1 or fastest.shape != slowest.shape or not (slowest < fastest).all():
        raise ValueError("expected lower action bounds below upper ones")
    return gymnasium.spaces.Box(slowest, fastest, dtype=np.float32)
