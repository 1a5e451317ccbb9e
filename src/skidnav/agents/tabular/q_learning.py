"""Q-learning: the model-free baseline (Watkins 1989; Sutton & Barto (2018) §6.5).

After each real step: one TD update of ``q[s, a]`` toward ``r + γ · max_a' q[s', a']`` (no
bootstrap after termination). No model, no planning.
"""

from __future__ import annotations

from typing import ClassVar, NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents.config import QLearningConfig
from skidnav.agents.learning import Experience, learning_step
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.sim.q_values import td_update, visit_step_size


class QArrays(NamedTuple):
    """What Q-learning learns into: the Q table, float64 (n_states, n_actions), and the real
    updates of each pair (:attr:`~skidnav.agents.tabular.agent.TabularAgent.visits`)."""

    q: np.ndarray
    visits: np.ndarray


class TDSettings(NamedTuple):
    """Step size α, discount γ and the step size's visit exponent ω."""

    alpha: float
    gamma: float
    alpha_exponent: float


@learning_step(QArrays)
@jit
def q_learning_step(
    arrays: QArrays,
    settings: TDSettings,
    counters: np.ndarray,
    step: Experience,
    rng: np.random.Generator,
) -> None:
    """The learning step of Q-learning: one TD update (draws nothing)."""
    alpha = visit_step_size(
        arrays.visits, step.state, step.action, settings.alpha, settings.alpha_exponent
    )
    td_update(
        arrays.q, step.state, step.action, step.reward, step.next_state, step.terminated,
        alpha, settings.gamma,
    )  # fmt: skip


class QLearningAgent(TabularAgent[QArrays, TDSettings]):
    """Tabular one-step Q-learning with ε-greedy behaviour."""

    name: ClassVar[str] = "q-learning"
    config_class: ClassVar[type[QLearningConfig]] = QLearningConfig

    def learning_arrays(self) -> QArrays:
        return QArrays(self.q, self.visits)

    def learning_settings(self) -> TDSettings:
        config = self.config
        return TDSettings(
            float(config.alpha), float(config.gamma), float(config.alpha_visit_exponent)
        )


AGENT_NAME = "q-learning"
AGENT_CLASS = QLearningAgent
