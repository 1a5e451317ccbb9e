"""The frozen ``mppi-kinematic`` planner
(:meth:`~skidnav.agents.mpc.agent.MPPIKinematicAgent.policy`): its model and map copied, its own
Generator; within a rollout it marks what its lidar reads."""

from __future__ import annotations

import copy
from typing import Protocol

import numpy as np

from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.costmap import MapCosts
from skidnav.agents.mpc.dynamics import SampledDynamics
from skidnav.agents.mpc.evidence import MapEvidence
from skidnav.agents.mpc.observations import pose_of, ranges_of
from skidnav.agents.mpc.planner import MPPIPlanner
from skidnav.robot.params import KinematicConstants, RobotParams
from skidnav.world.discretization import GridShape


class Planning(Protocol):
    """What a frozen planner copies of the agent
    (:class:`~skidnav.agents.mpc.agent.MPPIKinematicAgent`)."""

    lidar_rays: int
    lidar_range: float
    lidar_fov: float
    goal: tuple[int, int]
    robot: RobotParams
    dynamics: SampledDynamics
    evidence: MapEvidence
    costs: MapCosts
    config: MPPIConfig
    kernel_robot: KinematicConstants
    kernel_grid: GridShape


class MPPIPolicy:
    """A frozen ``mppi-kinematic`` planner: a
    :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`.

    MPPI is a controller with a state (its plan, warm-started from step to step, and the
    rollout's map) and samples from its own Generator: the wheel speeds depend on the rollout's
    observations, the plan and the draws, the same for the same seed and observations.
    :meth:`reset` forgets the plan and the readings (a new episode).
    """

    def __init__(self, agent: Planning, seed: int) -> None:
        self.lidar_rays, self.lidar_range = agent.lidar_rays, agent.lidar_range
        self.lidar_fov = agent.lidar_fov
        self.goal = agent.goal
        """The goal cell (i, j) it drives to."""
        self.control_period = agent.robot.action_duration
        """The duration [s] of one action it plans with: a run must hold each command as long."""
        self.dynamics = SampledDynamics(*(np.copy(array) for array in agent.dynamics))
        self._frozen_evidence = copy.deepcopy(agent.evidence)
        self.evidence = copy.deepcopy(self._frozen_evidence)
        """The map it plans on: the agent's as frozen, plus what its lidar has read since the
        rollout started (:meth:`wheel_speeds`)."""
        self.costs = agent.costs
        self.planner = MPPIPlanner(
            agent.config, agent.kernel_robot, agent.kernel_grid, np.random.default_rng(seed)
        )

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s] for a pose (3,) or feature observation (7 + k,). The lidar
        readings of a feature observation go into the rollout's map first, as the agent's own
        steps put them into its map: a navigator sees the walls in front of it whether or not
        it learns (the model stays frozen, and :meth:`reset` forgets the readings)."""
        pose = pose_of(observation, self.lidar_rays)
        ranges = ranges_of(observation, self.lidar_rays)
        self.evidence.record_readings(pose, ranges, self.lidar_range, self.lidar_fov)
        return self.planner.step(pose, self.dynamics, self.evidence.cost_map, self.costs)

    def reset(self) -> None:
        """Forget the plan and what the lidar read since the policy was frozen."""
        self.planner.reset()
        self.evidence = copy.deepcopy(self._frozen_evidence)

    def start_greedy_rollout(self) -> None:
        """A rollout (an episode) starts: :meth:`reset`
        (:class:`~skidnav.agents.greedy.RolloutState`)."""
        self.reset()
