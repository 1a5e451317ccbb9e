"""Dyna-Q+: Dyna-Q with an exploration bonus for long-untried pairs (Sutton & Barto (2018) §8.3).

Like Dyna-Q, but planning draws a *visited state* uniformly and then *any* action uniformly. A pair
never tried from a visited state is modelled as leading back to the same state with reward 0 (the
book's footnote to Example 8.3). Every planning target gets the bonus κ·√τ, τ being the number of
real steps since (s, a) was last tried, so the agent is drawn back to test parts of the world that
may have changed (blocking and shortcut mazes, Examples 8.2 and 8.3).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from skidnav.agents.config import DynaQPlusConfig, QLearningConfig
from skidnav.agents.dyna_q import DynaQAgent
from skidnav.kernels.planning import dyna_plus_planning


class DynaQPlusAgent(DynaQAgent):
    """Dyna-Q+ (bonus κ·√τ on planning rewards)."""

    name: ClassVar[str] = "dyna-q-plus"
    config_class: ClassVar[type[QLearningConfig]] = DynaQPlusConfig
    config: DynaQPlusConfig

    def __init__(
        self,
        n_states: int,
        n_actions: int,
        config: QLearningConfig | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        super().__init__(n_states, n_actions, config, rng)
        self.last_tried = np.zeros((n_states, n_actions), dtype=np.int64)
        """Real-step count when each pair was last tried (0 = never), (n_states, n_actions)."""
        self.visited_states = np.zeros(0, dtype=np.int64)
        """States seen as the start of a real step, in order of first visit."""
        self._is_visited = np.zeros(n_states, dtype=np.bool_)

    def _learn(
        self,
        state: int,
        action: int,
        reward: float,
        next_state: int,
        terminated: bool,
        info: Mapping[str, Any],
    ) -> None:
        self.last_tried[state, action] = self.steps
        if not self._is_visited[state]:
            self._is_visited[state] = True
            self.visited_states = np.append(self.visited_states, state)
        super()._learn(state, action, reward, next_state, terminated, info)

    def _plan(self) -> None:
        config = self.config
        if config.planning_steps == 0:
            return
        self.planning_updates += int(
            dyna_plus_planning(
                self.q,
                self.model.arrays,
                self.visited_states,
                self.visited_states.shape[0],
                self.last_tried,
                self.steps,
                config.kappa,
                config.planning_steps,
                config.alpha,
                config.gamma,
                config.planning_mode_code,
                self.rng,
            )
        )

    def _state_arrays(self) -> dict[str, np.ndarray]:
        return {
            **super()._state_arrays(),
            "last_tried": self.last_tried,
            "visited_states": self.visited_states,
        }

    def _restore_state_arrays(self, arrays: Mapping[str, np.ndarray]) -> None:
        super()._restore_state_arrays(arrays)
        last_tried = arrays["last_tried"]
        if last_tried.shape != self.last_tried.shape:
            raise ValueError(f"last_tried has shape {last_tried.shape}")
        if last_tried.size and (last_tried.min() < 0 or last_tried.max() > self.steps):
            raise ValueError(f"last_tried outside [0, {self.steps}] real steps")
        self.last_tried[:] = last_tried
        visited = np.array(arrays["visited_states"], dtype=np.int64)
        if visited.size and (visited.min() < 0 or visited.max() >= self.n_states):
            raise ValueError("visited state out of range")
        if np.any(np.diff(np.sort(visited)) == 0):
            raise ValueError("visited states repeat")  # the compiled trainer holds n_states
        self.visited_states = visited
        self._is_visited[:] = False
        self._is_visited[self.visited_states] = True


AGENT_NAME = "dyna-q-plus"
AGENT_CLASS = DynaQPlusAgent
