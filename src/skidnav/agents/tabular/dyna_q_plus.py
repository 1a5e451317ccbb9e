"""Dyna-Q+: Dyna-Q with an exploration bonus for long-untried pairs (Sutton & Barto (2018) §8.3).

Like Dyna-Q, but planning draws a *visited state* uniformly and then *any* action uniformly. A pair
never tried from a visited state is modelled as leading back to the same state with reward 0 (the
book's footnote to Example 8.3). Every planning target gets the bonus κ·√τ, τ being the number of
real steps since (s, a) was last tried, so the agent is drawn back to test parts of the world that
may have changed (blocking and shortcut mazes, Examples 8.2 and 8.3).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar, NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents.config import QLearningConfig
from skidnav.agents.learning import PLANNING_UPDATES, STEPS, Experience, learning_step
from skidnav.agents.tabular.config import DynaQPlusConfig
from skidnav.agents.tabular.dyna_q import DynaAgent
from skidnav.agents.tabular.planning import dyna_plus_planning
from skidnav.models.multinomial_kernels import MultinomialArrays, model_observe
from skidnav.sim.q_values import td_update, visit_step_size


class DynaPlusArrays(NamedTuple):
    """What Dyna-Q+ learns into. ``last_tried`` int64 (n_states, n_actions): the real step at
    which each pair was last tried (0 = never); ``visited`` int64 (n_states,) whose first
    ``n_visited[0]`` entries are the states seen, in order of first visit; ``is_visited`` bool
    (n_states,); ``visits``: the real updates of each pair
    (:attr:`~skidnav.agents.tabular.agent.TabularAgent.visits`)."""

    q: np.ndarray
    model: MultinomialArrays
    last_tried: np.ndarray
    visited: np.ndarray
    n_visited: np.ndarray
    is_visited: np.ndarray
    visits: np.ndarray


class BonusSettings(NamedTuple):
    """α, γ, planning updates per real step, planning target, the bonus weight κ and the visit
    exponent ω of the real updates' step size."""

    alpha: float
    gamma: float
    planning_steps: int
    mode: int
    kappa: float
    alpha_exponent: float


@learning_step(DynaPlusArrays)
@jit
def dyna_q_plus_step(
    arrays: DynaPlusArrays,
    settings: BonusSettings,
    counters: np.ndarray,
    step: Experience,
    rng: np.random.Generator,
) -> None:
    """The learning step of Dyna-Q+: note when the pair was tried and the state first visited,
    TD update, model count, then the planning updates with the bonus."""
    d, s = arrays, settings
    d.last_tried[step.state, step.action] = counters[STEPS]
    if not d.is_visited[step.state]:
        d.is_visited[step.state] = True
        d.visited[d.n_visited[0]] = step.state
        d.n_visited[0] += 1
    alpha = visit_step_size(d.visits, step.state, step.action, s.alpha, s.alpha_exponent)
    td_update(
        d.q, step.state, step.action, step.reward, step.next_state, step.terminated, alpha,
        s.gamma,
    )  # fmt: skip
    model_observe(d.model, step.state, step.action, step.reward, step.next_state, step.terminated)
    if s.planning_steps > 0:
        counters[PLANNING_UPDATES] += dyna_plus_planning(
            d.q, d.model, d.visited, d.n_visited[0], d.last_tried, counters[STEPS], s.kappa,
            s.planning_steps, s.alpha, s.gamma, s.mode, rng,
        )  # fmt: skip


class DynaQPlusAgent(DynaAgent[DynaPlusArrays, BonusSettings]):
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
        self._visited = np.zeros(n_states, dtype=np.int64)
        self._n_visited = np.zeros(1, dtype=np.int64)
        self._is_visited = np.zeros(n_states, dtype=np.bool_)

    @property
    def visited_states(self) -> np.ndarray:
        """States seen as the start of a real step, in order of first visit, int64 (n,)."""
        return self._visited[: self._n_visited[0]].copy()

    def learning_arrays(self) -> DynaPlusArrays:
        return DynaPlusArrays(
            self.q, self.model.arrays, self.last_tried, self._visited, self._n_visited,
            self._is_visited, self.visits,
        )  # fmt: skip

    def learning_settings(self) -> BonusSettings:
        config = self.config
        return BonusSettings(
            float(config.alpha), float(config.gamma), int(config.planning_steps),
            int(config.planning_mode_code), float(config.kappa),
            float(config.alpha_visit_exponent),
        )  # fmt: skip

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
            raise ValueError("visited states repeat")  # the visited buffer holds n_states
        self._visited[: visited.size] = visited
        self._n_visited[0] = visited.size
        self._is_visited[:] = False
        self._is_visited[visited] = True


AGENT_NAME = "dyna-q-plus"
AGENT_CLASS = DynaQPlusAgent
