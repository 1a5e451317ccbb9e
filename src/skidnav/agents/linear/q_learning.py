"""Linear Q-learning: semi-gradient Q-learning on tile-coded features (Sutton & Barto (2018)
§10.1 with the Q-learning target of §6.5; tile coding §9.5.4).

After each real step: ``w[a, F(s)] += α/n · (r + γ · max_a' q(s', a') − q(s, a))`` (no
bootstrap after termination). No traces, no model.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from skidnav.agents.linear.agent import LinearAgent
from skidnav.agents.linear.config import LinearConfig
from skidnav.agents.linear.updates import q_learning_update


class LinearQAgent(LinearAgent):
    """Linear Q-learning with ε-greedy behaviour."""

    name: ClassVar[str] = "linear-q"
    config_class: ClassVar[type[LinearConfig]] = LinearConfig

    def _learn(
        self,
        tiles: np.ndarray,
        action: int,
        reward: float,
        next_tiles: np.ndarray,
        terminated: bool,
    ) -> int | None:
        q_learning_update(
            self.w, tiles, action, reward, next_tiles, terminated, self.step_size,
            float(self.config.gamma), self._values,
        )  # fmt: skip
        return None


AGENT_NAME = "linear-q"
AGENT_CLASS = LinearQAgent
