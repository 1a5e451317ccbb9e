"""Dyna-Q with the multinomial model plus a learned kinematic model (Alhawary (2020), ch. 7).

After each real step (s, a, r, s′) with the env's ``info``:

1. direct RL: one TD update of ``q[s, a]``;
2. model learning: count the transition in the multinomial model; feed the free sub-steps of
   ``info["kinematic_log"]`` to the per-region Bayesian ridge kinematic model; record the reward
   in the reward statistics; weigh the map's evidence — the cell the robot ended in is free, the
   guessed wall cell of a collision is a wall — and mark the goal cell of a termination (the
   kinematic table around cells that changed is recomputed at the end of the episode);
3. planning: ``planning_steps`` updates. With probability ``kinematic_share`` an update goes to the
   *frontier*: a visited pair drawn uniformly, a random action predicted from its state, and a
   random action at the predicted state; otherwise to a uniformly drawn visited pair (Dyna-Q).
   Pairs visited are answered by the multinomial model, pairs never visited by the kinematic
   table (see :mod:`skidnav.agents.kinematic_planning`).

At the end of each episode the kinematic model refits on its schedule and, if it did, the whole
prediction table ``pred_next[s, a]`` is recomputed. See docs/agents/dyna-kinematic.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from skidnav.agents.config import KinematicModelFields, QLearningConfig, check
from skidnav.agents.tabular.config import MODEL_BASED_PLANNING_MODE, DynaQConfig
from skidnav.agents.tabular.model_based import ModelBasedAgent


@dataclass(frozen=True)
class DynaKinematicConfig(DynaQConfig, KinematicModelFields):
    """Dyna-Q with kinematic-model planning (:class:`KinematicModelFields` for the model)."""

    planning_steps: int = 10
    """Planning updates n after each real step."""
    planning_mode: str = MODEL_BASED_PLANNING_MODE
    """How the model answers (:data:`~skidnav.agents.tabular.config.MODEL_BASED_PLANNING_MODE`)."""
    kinematic_share: float = 0.5
    """Share of planning updates sent to the frontier of the visited set, in [0, 1]."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(0.0 <= self.kinematic_share <= 1.0, "kinematic_share in [0, 1]", self.kinematic_share)
        self.kinematic_config()  # validates the kinematic fields


class DynaKinematicAgent(ModelBasedAgent):
    """Dyna-Q whose planning also reaches never-visited pairs through the kinematic model."""

    name: ClassVar[str] = "dyna-kinematic"
    config_class: ClassVar[type[QLearningConfig]] = DynaKinematicConfig
    uses_kinematic: ClassVar[bool] = True
    uses_trajectories: ClassVar[bool] = False


AGENT_NAME = "dyna-kinematic"
AGENT_CLASS = DynaKinematicAgent
