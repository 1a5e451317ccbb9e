"""Dyna-Q with the sparse multinomial model (Sutton & Barto (2018) §8.2; thesis).

After each real step (s, a, r, s′):

1. direct RL: one TD update of ``q[s, a]`` (:func:`skidnav.sim.q_values.td_update`);
2. model learning: count the transition in the :class:`MultinomialModel`;
3. planning: ``planning_steps`` updates, each on a visited (s, a) pair drawn uniformly, toward the
   model's target in ``planning_mode`` ("most-probable" by default, as in the thesis).

With ``planning_steps = 0`` it is exactly Q-learning (the model draws no random number).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar, NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents.config import QLearningConfig
from skidnav.agents.learning import PLANNING_UPDATES, Experience, learning_step
from skidnav.agents.tabular.agent import ArraysT, SettingsT, TabularAgent
from skidnav.agents.tabular.config import DynaQConfig
from skidnav.agents.tabular.planning import dyna_planning
from skidnav.models.multinomial import MultinomialModel
from skidnav.models.multinomial_kernels import MultinomialArrays, model_observe
from skidnav.sim.q_values import td_update, visit_step_size


class DynaArrays(NamedTuple):
    """What Dyna-Q learns into: the Q table, the multinomial model's arrays and the real updates
    of each pair (:attr:`~skidnav.agents.tabular.agent.TabularAgent.visits`)."""

    q: np.ndarray
    model: MultinomialArrays
    visits: np.ndarray


class PlanningSettings(NamedTuple):
    """α, γ, planning updates per real step, the planning target (``planning_mode_code``) and
    the visit exponent ω of the real updates' step size."""

    alpha: float
    gamma: float
    planning_steps: int
    mode: int
    alpha_exponent: float


@learning_step(DynaArrays)
@jit
def dyna_q_step(
    arrays: DynaArrays,
    settings: PlanningSettings,
    counters: np.ndarray,
    step: Experience,
    rng: np.random.Generator,
) -> None:
    """The learning step of Dyna-Q: TD update, model count, then the planning updates."""
    s = settings
    alpha = visit_step_size(arrays.visits, step.state, step.action, s.alpha, s.alpha_exponent)
    td_update(
        arrays.q, step.state, step.action, step.reward, step.next_state, step.terminated,
        alpha, s.gamma,
    )  # fmt: skip
    model_observe(
        arrays.model, step.state, step.action, step.reward, step.next_state, step.terminated
    )
    if s.planning_steps > 0:
        counters[PLANNING_UPDATES] += dyna_planning(
            arrays.q, arrays.model, s.planning_steps, s.alpha, s.gamma, s.mode, rng
        )


class DynaAgent(TabularAgent[ArraysT, SettingsT]):
    """Base of the agents that count every real step in a :class:`MultinomialModel` (Dyna-Q and
    its variants): the model, its room and its saving. Generic in the NamedTuples of the agent's
    learning step, which a subclass names and builds (:meth:`learning_arrays`,
    :meth:`learning_settings`)."""

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

    def reserve(self, n_steps: int) -> None:
        self.model.reserve(n_steps)

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


class DynaQAgent(DynaAgent[DynaArrays, PlanningSettings]):
    """Dyna-Q: Q-learning plus uniform replay of visited pairs through a learned model."""

    name: ClassVar[str] = "dyna-q"
    config_class: ClassVar[type[QLearningConfig]] = DynaQConfig

    def learning_arrays(self) -> DynaArrays:
        return DynaArrays(self.q, self.model.arrays, self.visits)

    def learning_settings(self) -> PlanningSettings:
        config = self.config
        return PlanningSettings(
            float(config.alpha), float(config.gamma), int(config.planning_steps),
            int(config.planning_mode_code), float(config.alpha_visit_exponent),
        )  # fmt: skip


AGENT_NAME = "dyna-q"
AGENT_CLASS = DynaQAgent
