"""Dyna-Q with the sparse multinomial model (Sutton & Barto (2018) §8.2; thesis).

After each real step (s, a, r, s′):

1. direct RL: one TD update of ``q[s, a]`` (:func:`skidnav.kernels.tabular.td_update`);
2. model learning: count the transition in the :class:`MultinomialModel`;
3. planning: ``planning_steps`` updates, each on a visited (s, a) pair drawn uniformly, toward the
   model's target in ``planning_mode`` ("most-probable" by default, as in the thesis).

With ``planning_steps = 0`` it is exactly Q-learning (the model draws no random number).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from skidnav.agents.config import DynaQConfig, QLearningConfig
from skidnav.agents.core import TabularAgent
from skidnav.kernels.planning import dyna_planning
from skidnav.kernels.tabular import td_update
from skidnav.models.multinomial import MultinomialModel


class DynaQAgent(TabularAgent):
    """Dyna-Q: Q-learning plus uniform replay of visited pairs through a learned model."""

    name: ClassVar[str] = "dyna-q"
    config_class: ClassVar[type[QLearningConfig]] = DynaQConfig
    config: DynaQConfig

    def __init__(
        self,
        n_states: int,
        n_actions: int,
        config: QLearningConfig | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        super().__init__(n_states, n_actions, config, rng)
        self.model = MultinomialModel(n_actions)
        """The transition model learned from real steps."""

    def _learn(
        self,
        state: int,
        action: int,
        reward: float,
        next_state: int,
        terminated: bool,
        info: Mapping[str, Any],
    ) -> None:
        config = self.config
        td_update(self.q, state, action, reward, next_state, terminated, config.alpha, config.gamma)
        self.model.observe(state, action, reward, next_state, terminated)
        self._plan()

    def _plan(self) -> None:
        """Run ``planning_steps`` model-based updates."""
        config = self.config
        if config.planning_steps == 0:
            return
        self.planning_updates += int(
            dyna_planning(
                self.q,
                self.model.arrays,
                config.planning_steps,
                config.alpha,
                config.gamma,
                config.planning_mode_code,
                self.rng,
            )
        )

    def _state_arrays(self) -> dict[str, np.ndarray]:
        return {**super()._state_arrays(), **self.model.to_arrays()}

    def _restore_state_arrays(self, arrays: Mapping[str, np.ndarray]) -> None:
        super()._restore_state_arrays(arrays)
        self.model = MultinomialModel.from_arrays(dict(arrays))
        arrays_ = self.model.arrays
        n_pairs, n_entries = int(arrays_.counters[0]), int(arrays_.counters[1])
        if self.model.n_actions != self.n_actions:
            raise ValueError("model and Q table disagree on the number of actions")
        keys = arrays_.pair_key[:n_pairs]
        next_states = arrays_.entry_next_state[:n_entries]
        if (keys.size and (keys.min() < 0 or keys.max() >= self.q.size)) or (
            next_states.size and (next_states.min() < 0 or next_states.max() >= self.n_states)
        ):
            raise ValueError("model refers to states outside the Q table")


AGENT_NAME = "dyna-q"
AGENT_CLASS = DynaQAgent
