"""Q-learning: the model-free baseline (Watkins 1989; Sutton & Barto (2018) §6.5).

After each real step: one TD update of ``q[s, a]`` toward ``r + γ · max_a' q[s', a']`` (no
bootstrap after termination). No model, no planning.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from skidnav.agents.config import QLearningConfig
from skidnav.agents.core import TabularAgent
from skidnav.kernels.tabular import td_update


class QLearningAgent(TabularAgent):
    """Tabular one-step Q-learning with ε-greedy behaviour."""

    name: ClassVar[str] = "q-learning"
    config_class: ClassVar[type[QLearningConfig]] = QLearningConfig

    def _learn(
        self,
        state: int,
        action: int,
        reward: float,
        next_state: int,
        terminated: bool,
        info: Mapping[str, Any],
    ) -> None:
        td_update(
            self.q,
            state,
            action,
            reward,
            next_state,
            terminated,
            self.config.alpha,
            self.config.gamma,
        )


AGENT_NAME = "q-learning"
AGENT_CLASS = QLearningAgent
