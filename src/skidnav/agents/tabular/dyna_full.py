"""The thesis's combination: Dyna-Q with the multinomial model, kinematic-model planning on pairs
never visited, and planning prioritized around the shortest discovered trajectories
(Alhawary (2020), ch. 7).

Each planning update, once a successful trajectory exists, takes with probability
``trajectory_share`` the next pair of the trajectory sweeps (backward from the goal, then the
neighbourhood, which here includes never-visited pairs answered by the kinematic model); the rest
are split as in ``dyna-kinematic``: a share ``kinematic_share`` to the frontier of the visited
set, the others to uniform replay of visited pairs. See docs/agents/dyna-full.md and
:mod:`skidnav.agents.tabular.model_based`, :mod:`skidnav.agents.tabular.trajectory_prioritized`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from skidnav.agents.config import QLearningConfig
from skidnav.agents.tabular.dyna_kinematic import DynaKinematicConfig
from skidnav.agents.tabular.model_based import ModelBasedAgent
from skidnav.agents.tabular.trajectory_prioritized import TrajectoryPrioritizedConfig


@dataclass(frozen=True)
class DynaFullConfig(DynaKinematicConfig, TrajectoryPrioritizedConfig):
    """All fields of :class:`DynaKinematicConfig` and :class:`TrajectoryPrioritizedConfig`."""


class DynaFullAgent(ModelBasedAgent):
    """Multinomial + kinematic + trajectory-prioritized planning."""

    name: ClassVar[str] = "dyna-full"
    config_class: ClassVar[type[QLearningConfig]] = DynaFullConfig
    uses_kinematic: ClassVar[bool] = True
    uses_trajectories: ClassVar[bool] = True


AGENT_NAME = "dyna-full"
AGENT_CLASS = DynaFullAgent
