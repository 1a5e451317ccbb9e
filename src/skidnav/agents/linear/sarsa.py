"""Linear Sarsa(λ): on-policy TD(λ) control on tile-coded features with replacing traces
(Sutton & Barto (2018) §12.7, "Sarsa(λ) with binary features and linear function
approximation").

``observe`` chooses the next action a′ ε-greedily from the current weights before the update
(the boxed algorithm's order), uses ``q(s′, a′)`` in the TD error and hands a′ to the next
``act(s′)``; after termination there is no a′. Traces are zeroed at every episode start.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from skidnav.agents.linear.agent import LinearAgent
from skidnav.agents.linear.config import LinearConfig, LinearSarsaConfig
from skidnav.agents.linear.updates import choose_action, sarsa_lambda_update


class LinearSarsaAgent(LinearAgent):
    """Linear Sarsa(λ) with replacing traces and ε-greedy behaviour."""

    name: ClassVar[str] = "linear-sarsa"
    config_class: ClassVar[type[LinearConfig]] = LinearSarsaConfig

    def _allocate(self) -> None:
        super()._allocate()
        self.traces = np.zeros_like(self.w)
        """Eligibility traces z, float64 (n_actions, n_features), zero at an episode start."""

    def _learn(
        self,
        tiles: np.ndarray,
        action: int,
        reward: float,
        next_tiles: np.ndarray,
        terminated: bool,
    ) -> int | None:
        config = self.config
        assert isinstance(config, LinearSarsaConfig)
        next_action = 0
        if not terminated:
            next_action = int(
                choose_action(self.w, next_tiles, self._values, self.epsilon, self.rng)
            )
        sarsa_lambda_update(
            self.w, self.traces, tiles, action, reward, next_tiles, next_action, terminated,
            self.step_size, float(config.gamma), float(config.lam),
        )  # fmt: skip
        return None if terminated else next_action

    def end_episode(self) -> None:
        super().end_episode()
        self.traces[:] = 0.0

    def state_arrays(self) -> dict[str, np.ndarray]:
        return {**super().state_arrays(), "traces": self.traces}


AGENT_NAME = "linear-sarsa"
AGENT_CLASS = LinearSarsaAgent
