"""Linear Dyna: Dyna-style planning with a linear model on tile-coded features (Sutton,
Szepesvári, Geramifard & Bowling 2008, "Dyna-style planning with linear function approximation
and prioritized sweeping", UAI), with action values.

After each real step, three things, as Dyna-Q (Sutton & Barto (2018) §8.2) does them:

1. direct RL: the update of linear Q-learning (:mod:`skidnav.agents.linear.q_learning`);
2. model learning: per action ``a`` a linear model of the next feature vector, ``x' ≈ F_a x``,
   and of the reward, ``r ≈ b_aᵀ x``, by the paper's LMS updates (``x' = 0`` after
   termination); the state's active features go into a ring buffer of the
   ``planning_memory`` most recently visited states;
3. planning: ``planning_steps`` updates, each of a state drawn uniformly from that buffer and an
   action drawn uniformly, toward ``b_aᵀ x + γ · max_a' w[a'] · (F_a x)``.

The paper plans from feature vectors chosen by the planner (unit basis vectors in its
prioritized-sweeping variants) and keeps state values; here the feature vectors are those of
recently visited states, so planning stays on the part of the space the agent has seen, and the
values are action values, so that ``planning_steps = 0`` is linear Q-learning bit for bit.

Memory: ``F`` is dense, ``n_actions · n_features² · 8`` bytes (plus ``n_actions ·
n_features · 8`` for ``b``, the same for ``w``, and ``planning_memory · n_tilings · 8`` for the
buffer); a config whose ``F`` would exceed :data:`MAX_MODEL_BYTES` is refused before anything is
allocated. The default coder on the 3-D pose (8 tilings × 5³) has 1,000 features: 32 MB with 4
actions.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from skidnav.agents.linear.config import LinearConfig, LinearDynaConfig
from skidnav.agents.linear.q_learning import LinearQAgent
from skidnav.agents.linear.updates import linear_dyna_planning, model_update
from skidnav.errors import CorruptFileError

MAX_MODEL_BYTES = 128 * 2**20
"""Largest next-feature model F [bytes]: n_actions · n_features² · 8 ≤ 128 MiB, i.e. at most
2,048 features with 4 actions (:func:`model_bytes`)."""


def model_bytes(n_actions: int, n_features: int) -> int:
    """Bytes of the dense model ``F``: ``n_actions · n_features² · 8``.

    >>> model_bytes(4, 1000)
    32000000
    """
    return n_actions * n_features * n_features * 8


class LinearDynaAgent(LinearQAgent):
    """Linear Dyna with action values, ε-greedy behaviour and uniform planning draws."""

    name: ClassVar[str] = "linear-dyna"
    config_class: ClassVar[type[LinearConfig]] = LinearDynaConfig

    def _allocate(self) -> None:
        super()._allocate()
        config = self.config
        assert isinstance(config, LinearDynaConfig)
        self.next_model = np.zeros((self.n_actions, self.n_features, self.n_features))
        """F transposed, float64 (n_actions, n_features, n_features): row i is F_a's column i."""
        self.reward_model = np.zeros((self.n_actions, self.n_features))
        """b_a, float64 (n_actions, n_features)."""
        self.visited = np.zeros((config.planning_memory, config.n_tilings), dtype=np.int64)
        """Active features of the most recent states, int64 (planning_memory, n_tilings): row
        ``(step − 1) mod planning_memory`` holds the state of real step ``step``."""
        self._predicted = np.zeros(self.n_features)

    def _check_sizes(self) -> None:
        super()._check_sizes()
        size = model_bytes(self.n_actions, self.n_features)
        if size > MAX_MODEL_BYTES:
            raise ValueError(
                f"expected a model of at most {MAX_MODEL_BYTES:,} bytes "
                f"(n_actions · n_features² · 8), got {size:,}; use fewer tiles or tilings"
            )

    def _learn(
        self,
        tiles: np.ndarray,
        action: int,
        reward: float,
        next_tiles: np.ndarray,
        terminated: bool,
    ) -> int | None:
        super()._learn(tiles, action, reward, next_tiles, terminated)
        config = self.config
        assert isinstance(config, LinearDynaConfig)
        model_step = float(config.model_alpha) / config.n_tilings
        model_update(
            self.next_model, self.reward_model, tiles, action, reward, next_tiles, terminated,
            model_step, self._predicted,
        )  # fmt: skip
        capacity = config.planning_memory
        self.visited[(self.steps - 1) % capacity] = tiles
        if config.planning_steps:
            linear_dyna_planning(
                self.w, self.next_model, self.reward_model, self.visited,
                min(self.steps, capacity), config.planning_steps, self.step_size,
                float(config.gamma), self.rng, self._predicted,
            )  # fmt: skip
            self.planning_updates += config.planning_steps
        return None

    def state_arrays(self) -> dict[str, np.ndarray]:
        return {
            **super().state_arrays(),
            "next_model": self.next_model,
            "reward_model": self.reward_model,
            "visited": self.visited,
        }

    def restore(
        self, counters: Mapping[str, Any], rng_state: Mapping[str, Any], arrays: Any
    ) -> None:
        visited = arrays["visited"]
        if visited.size and not (visited.min() >= 0 and visited.max() < self.n_features):
            raise CorruptFileError(f"saved visited features outside [0, {self.n_features})")
        super().restore(counters, rng_state, arrays)


AGENT_NAME = "linear-dyna"
AGENT_CLASS = LinearDynaAgent
