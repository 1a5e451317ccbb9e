"""A tiny agent added as a newcomer would (docs/architecture.md, "Adding an agent"): Q-learning
whose step size is 1 / N(s, a), the sample average of its targets. This module and one line of
the registry are all it takes; the step-by-step loop and the fused trainer both run it."""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar, NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents.learning import Experience, learning_step
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.sim.q_values import td_update


class AverageArrays(NamedTuple):
    """The Q table and the visit counts N(s, a), int64 (n_states, n_actions)."""

    q: np.ndarray
    visits: np.ndarray


class AverageSettings(NamedTuple):
    gamma: float


@learning_step(AverageArrays)
@jit
def sample_average_step(
    arrays: AverageArrays,
    settings: AverageSettings,
    counters: np.ndarray,
    step: Experience,
    rng: np.random.Generator,
) -> None:
    """Count the pair, then a TD update with α = 1 / N(s, a)."""
    arrays.visits[step.state, step.action] += 1
    alpha = 1.0 / arrays.visits[step.state, step.action]
    td_update(
        arrays.q, step.state, step.action, step.reward, step.next_state, step.terminated,
        alpha, settings.gamma,
    )  # fmt: skip


class SampleAverageAgent(TabularAgent):
    name: ClassVar[str] = "sample-average-q"

    def __init__(self, n_states: int, n_actions: int, config=None, rng=None) -> None:  # type: ignore[no-untyped-def]
        super().__init__(n_states, n_actions, config, rng)
        self.visits = np.zeros((n_states, n_actions), dtype=np.int64)

    def learning_arrays(self) -> AverageArrays:
        return AverageArrays(self.q, self.visits)

    def learning_settings(self) -> AverageSettings:
        return AverageSettings(float(self.config.gamma))

    def _state_arrays(self) -> dict[str, np.ndarray]:
        return {"visits": self.visits}

    def _restore_state_arrays(self, arrays: Mapping[str, np.ndarray]) -> None:
        if arrays["visits"].shape != self.visits.shape:
            raise ValueError("visits disagree with the Q table")
        self.visits[:] = arrays["visits"]


AGENT_NAME = "sample-average-q"
AGENT_CLASS = SampleAverageAgent
