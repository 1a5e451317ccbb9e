"""``dyna-sweep``: the thesis's full agent whose learned models are solved, not sampled (ours).

``dyna-full`` spends a fixed number of planning updates per real step on pairs drawn from the
model. ``dyna-sweep`` does all of that and, at the end of every episode once a goal cell is known,
solves the whole learned model by value iteration (:mod:`skidnav.agents.tabular.model_sweep`): every
pair seen in reality backed up with the multinomial model's expected target, every pair never seen
with the kinematic model's prediction from its cell, walls found by collisions respected, until
no value moves by more than ``sweep_tolerance``. Unknown cells count as free, so the greedy policy
is the shortest path the models predict; a collision adds a wall and the next solution goes
around it (optimism in the face of uncertainty, as in Sutton & Barto (2018) §8.3's exploration
bonus or in D* Lite path replanning, Koenig & Likhachev (2002)).

Sources: value iteration (Bellman 1957; Sutton & Barto (2018) §4.4); "sweeping the model" as the
limit of Dyna planning with an unbounded budget (Sutton & Barto (2018) §8.1); the kinematic and
multinomial models of the thesis (:mod:`skidnav.agents.tabular.model_based`). See
docs/agents/dyna-sweep.md.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from skidnav.agents import kinematic_planning as kp
from skidnav.agents.config import QLearningConfig, check
from skidnav.agents.tabular.dyna_full import DynaFullConfig
from skidnav.agents.tabular.model_based import ModelBasedAgent
from skidnav.agents.tabular.model_sweep import model_value_iteration


@dataclass(frozen=True)
class DynaSweepConfig(DynaFullConfig):
    """:class:`DynaFullConfig` plus the end-of-episode value iteration."""

    max_sweeps: int = 100
    """Most value-iteration sweeps over the whole table at the end of an episode (≥ 1)."""
    sweep_tolerance: float = 1e-2
    """Value iteration stops when no value moves by more than this, > 0."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(
            isinstance(self.max_sweeps, int) and 1 <= self.max_sweeps <= 100_000,
            "an integer max_sweeps in [1, 100000]",
            self.max_sweeps,
        )
        check(self.sweep_tolerance > 0.0, "sweep_tolerance > 0", self.sweep_tolerance)


class DynaSweepAgent(ModelBasedAgent):
    """``dyna-full`` + value iteration over the learned models after each episode."""

    name: ClassVar[str] = "dyna-sweep"
    config_class: ClassVar[type[QLearningConfig]] = DynaSweepConfig
    uses_kinematic: ClassVar[bool] = True
    uses_trajectories: ClassVar[bool] = True

    _solved: tuple[int, ...] = ()
    """:meth:`_structure` when the models were last solved."""

    def _structure(self) -> tuple[int, ...]:
        """What changes the solution materially: the known map (walls found or cleared, goals
        found) and kinematic refits."""
        refits = self.kinematic.refits if self.kinematic is not None else 0
        counters = self.planner.counters
        return (int(counters[kp.MAP_CHANGES]), int(self.planner.goals.sum()), refits)

    def end_episode(self) -> None:
        """As :meth:`ModelBasedAgent.end_episode`, then, once a goal is known, solve the models
        again if the episode changed their structure (a wall found or cleared, a goal found, a
        kinematic refit); what else the episode taught (new pairs, new counts) is left to the
        per-step planning until the next solution."""
        super().end_episode()
        structure = self._structure()
        if not self.planner.goals.any() or structure == self._solved:
            return
        self._solved = structure
        config: DynaSweepConfig = self.config  # type: ignore[assignment]
        _, updates = model_value_iteration(
            self.q, self.model.arrays, self.planner, config.gamma, self.kernel_grid,
            config.max_sweeps, config.sweep_tolerance,
        )  # fmt: skip
        self.planning_updates += int(updates)

    def _state_arrays(self) -> dict[str, np.ndarray]:
        return {**super()._state_arrays(), "sweep_solved": np.array(self._solved, dtype=np.int64)}

    def _restore_state_arrays(self, arrays: Mapping[str, np.ndarray]) -> None:
        super()._restore_state_arrays(arrays)
        solved = np.asarray(arrays["sweep_solved"])
        if (
            solved.ndim != 1
            or solved.size not in (0, 3)
            or (solved.size and solved.dtype.kind not in "iu")
        ):
            raise ValueError("saved sweep_solved is not 0 or 3 integers")
        self._solved = tuple(int(v) for v in solved)


AGENT_NAME = "dyna-sweep"
AGENT_CLASS = DynaSweepAgent
