"""Dyna-Q with planning prioritized around the shortest discovered trajectories (the idea of
Alhawary (2020), §4.6.2 and ch. 7; the procedure is ours, docs/agents/trajectory-prioritized.md).

The thesis found that the *order* of planning updates matters and organised them around the
shortest start→goal trajectories found so far; its exact procedure is not known. Ours
(docs/agents/trajectory-prioritized.md has it numbered):

1. record the pairs (s, a) of every episode;
2. when an episode reaches the goal, erase its loops (every state kept once, each kept pair still
   led in reality to the next kept state) and keep it if it is among the ``n_trajectories``
   shortest distinct trajectories so far;
3. rebuild two sweep lists: the kept trajectories' pairs backward from the goal (shortest
   trajectory first), and their neighbourhood (other actions at the trajectory states, then every
   action at states one cell or one heading bin away), visited pairs only for this agent;
4. each planning update takes, with probability ``trajectory_share``, the next pair of a sweep
   list (half the draws per list, each cycling), otherwise a visited pair drawn uniformly
   (Dyna-Q); every update uses the multinomial model's target (the expected update by default,
   :data:`~skidnav.agents.tabular.config.MODEL_BASED_PLANNING_MODE`).

Before the first success it is exactly Dyna-Q with uniform replay.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from skidnav.agents.config import QLearningConfig, check
from skidnav.agents.tabular.config import MODEL_BASED_PLANNING_MODE, DynaQConfig
from skidnav.agents.tabular.model_based import ModelBasedAgent


@dataclass(frozen=True)
class TrajectoryPrioritizedConfig(DynaQConfig):
    """Dyna-Q whose planning sweeps the best discovered trajectories."""

    planning_steps: int = 10
    """Planning updates n after each real step."""
    planning_mode: str = MODEL_BASED_PLANNING_MODE
    """How the model answers (:data:`~skidnav.agents.tabular.config.MODEL_BASED_PLANNING_MODE`)."""
    n_trajectories: int = 5
    """K: how many of the shortest loop-erased successful trajectories are kept (≥ 1)."""
    trajectory_share: float = 0.5
    """Share of planning updates taken from the sweep lists once a trajectory exists, in [0, 1]."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(
            isinstance(self.n_trajectories, int) and self.n_trajectories >= 1,
            "an integer n_trajectories >= 1",
            self.n_trajectories,
        )
        check(
            0.0 <= self.trajectory_share <= 1.0, "trajectory_share in [0, 1]", self.trajectory_share
        )


class TrajectoryPrioritizedAgent(ModelBasedAgent):
    """Dyna-Q + sweeps backward along the shortest discovered start→goal trajectories."""

    name: ClassVar[str] = "trajectory-prioritized"
    config_class: ClassVar[type[QLearningConfig]] = TrajectoryPrioritizedConfig
    uses_kinematic: ClassVar[bool] = False
    uses_trajectories: ClassVar[bool] = True


AGENT_NAME = "trajectory-prioritized"
AGENT_CLASS = TrajectoryPrioritizedAgent
