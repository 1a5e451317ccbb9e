"""Prioritized sweeping (Moore & Atkeson 1993; Sutton & Barto (2018) §8.4).

After each real step (s, a, r, s′):

1. model learning: count the transition in the :class:`MultinomialModel`;
2. priority: P = |model target of (s, a) − q[s, a]|; queue (s, a) if P > θ (a queued pair keeps
   the larger of its priorities);
3. planning: up to ``planning_steps`` times while the queue is not empty, pop the top pair, update
   it toward its model target, and queue every predecessor (s̄, ā) of s whose |TD error| > θ.

As in the book's algorithm, real experience changes ``q`` only through the queue, so every value
update is counted in ``planning_updates``. The priority is computed from the model (the book uses
the sampled reward; both are equal on a deterministic MDP).

Targets are expected over what the model leaves to chance, as the book's prioritized sweeping for
stochastic environments uses expected updates (§8.4): with ``planning_mode = "most-probable"``
(the default) a pair whose most probable outcome is tied gets the mean of the tied outcomes'
targets — the expectation over the uniform tie draw — for its priority and its update, and
planning draws no random number; with ``"sample"`` the priorities use the expected target. (A
tie redrawn at every pop kept the tied pairs' priorities above θ for ever: the queue cycled over
them, spending the whole planning budget, while the other pairs waited.)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar, NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents.config import QLearningConfig
from skidnav.agents.learning import PLANNING_UPDATES, Experience, learning_step
from skidnav.agents.tabular.config import PrioritizedSweepingConfig
from skidnav.agents.tabular.dyna_q import DynaAgent
from skidnav.agents.tabular.planning import sampled_sweep_step, sweep_step
from skidnav.agents.tabular.priority_queue import HeapArrays, heap_push, make_heap
from skidnav.models.multinomial_kernels import MultinomialArrays
from skidnav.models.multinomial_targets import MOST_PROBABLE


class SweepArrays(NamedTuple):
    """What prioritized sweeping learns into: Q table, model, and the priority queue of pairs."""

    q: np.ndarray
    model: MultinomialArrays
    queue: HeapArrays


class SweepSettings(NamedTuple):
    """α, γ, queue pops per real step, planning target and the priority threshold θ."""

    alpha: float
    gamma: float
    planning_steps: int
    mode: int
    theta: float


@learning_step(SweepArrays)
@jit
def prioritized_sweeping_step(
    arrays: SweepArrays,
    settings: SweepSettings,
    counters: np.ndarray,
    step: Experience,
    rng: np.random.Generator,
) -> None:
    """The learning step of prioritized sweeping
    (:func:`~skidnav.agents.tabular.planning.sweep_step`, or ``sampled_sweep_step`` for the sampling
    modes: model count, priority of the pair, then up to ``planning_steps`` pops)."""
    s = settings
    if s.mode == MOST_PROBABLE:  # inlined, its arrays bound in this branch only
        updates = sweep_step(
            arrays.q, arrays.model, arrays.queue, step.state, step.action, step.reward,
            step.next_state, step.terminated, s.planning_steps, s.theta, s.alpha, s.gamma,
        )  # fmt: skip
    else:
        updates = sampled_sweep_step(
            arrays.q, arrays.model, arrays.queue, step.state, step.action, step.reward,
            step.next_state, step.terminated, s.planning_steps, s.theta, s.alpha, s.gamma, s.mode,
            rng,
        )  # fmt: skip
    counters[PLANNING_UPDATES] += updates


class PrioritizedSweepingAgent(DynaAgent[SweepArrays, SweepSettings]):
    """Prioritized sweeping over the multinomial model."""

    name: ClassVar[str] = "prioritized-sweeping"
    config_class: ClassVar[type[QLearningConfig]] = PrioritizedSweepingConfig
    config: PrioritizedSweepingConfig

    def __init__(
        self,
        n_states: int,
        n_actions: int,
        config: QLearningConfig | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        super().__init__(n_states, n_actions, config, rng)
        self.queue = make_heap(n_states * n_actions)
        """Pairs s·n_actions + a waiting for an update, by priority (24 bytes per pair)."""

    def learning_arrays(self) -> SweepArrays:
        return SweepArrays(self.q, self.model.arrays, self.queue)

    def learning_settings(self) -> SweepSettings:
        config = self.config
        return SweepSettings(
            float(config.alpha), float(config.gamma), int(config.planning_steps),
            int(config.planning_mode_code), float(config.theta),
        )  # fmt: skip

    def _state_arrays(self) -> dict[str, np.ndarray]:
        size = int(self.queue.size[0])
        return {
            **super()._state_arrays(),
            "queue_items": self.queue.item[:size],
            "queue_priorities": self.queue.priority[:size],
        }

    def _restore_state_arrays(self, arrays: Mapping[str, np.ndarray]) -> None:
        super()._restore_state_arrays(arrays)
        self.queue = make_heap(self.n_states * self.n_actions)
        items = arrays["queue_items"]
        priorities = arrays["queue_priorities"]
        n_items = self.n_states * self.n_actions
        if items.shape != priorities.shape or len(set(items.tolist())) != items.size:
            raise ValueError("queue arrays disagree")
        if items.size and (items.min() < 0 or items.max() >= n_items):
            raise ValueError("queue item out of range")
        if not np.isin(items, self.model.visited_pairs()).all():
            raise ValueError("queued pair never observed")  # the model must answer every pop
        if not np.isfinite(priorities).all():
            raise ValueError("queue priority not finite")
        # Saved slots are in heap order: pushing them in order rebuilds the same heap.
        for item, priority in zip(items.tolist(), priorities.tolist(), strict=True):
            heap_push(self.queue, int(item), float(priority))


AGENT_NAME = "prioritized-sweeping"
AGENT_CLASS = PrioritizedSweepingAgent
