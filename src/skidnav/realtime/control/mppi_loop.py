"""``mppi-kinematic`` learning online on the robot (docs/robot-learning.md).

The loop is the frozen policy's (:class:`~skidnav.realtime.control.policy_loop.PolicyLoop`: one
action per ``substeps`` control periods, the wheels not stopped between actions, the same
virtual bumper, watchdog, lease, episodes, homing and checkpoints), with a pilot that learns:

1. Each action, the control path computes the observation from the newest tracked pose — the
   pose and goal features, and the laser readings a lidar of the agent's layout would take
   there in the run's map (:class:`~skidnav.sim.features.PoseFeatures`; the robot carries no
   laser: the readings come from the map the run is given, as for a frozen policy) — and plans
   one MPPI step on the newest view of the model and the map the learner published
   (:meth:`~skidnav.agents.mpc.agent.MPPIKinematicAgent.act_on`).
2. After the action it hands the step to the learner (:mod:`.learner`): the observation, the
   command sent, the reward, the observation at the end pose, and the info of the env's
   contract, whose ``kinematic_log`` holds the body twists measured from consecutive tracked
   poses under that command (realtime/control/transition.py) and ``collision`` the virtual
   bumper's verdict.
3. The learner's thread feeds the step to the agent — the model refitted on its schedule, the
   map evidence, cost map and lattice recomputed when they changed — and publishes a fresh view;
   the control path never waits for it.
4. When an episode ends (the wheels stopped) the loop waits for the learner to catch up, ends
   the agent's episode and writes the checkpoint: the agent's model, map, plan, counters and
   Generator (its ``save``), so ``--resume`` continues with everything learned up to the last
   finished episode, after a stall, a crash or a SIGKILL alike.

A control path that decides every period does not wait a whole extra period for a dropped
pose: a pose 15 % of a period late (:data:`LATE_POSE`) is given up and the loop decides with the
newest it has, leaving that period out of the kinematic log.

The interval between the control path's decisions is recorded (robot seconds: wall × time
scale), and :meth:`MPPILoop.summary_fields` reports its median and 95th percentile with the
learner's work (refits, cost-map recomputes) in ``summary.json``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.envs.step_info import step_info
from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.episodes import EpisodeLoop
from skidnav.realtime.control.learner import BackgroundLearner, Step
from skidnav.realtime.control.policy_loop import Decision, PolicyLoop
from skidnav.realtime.control.records import EpisodeResult
from skidnav.realtime.link.interface import Pose, RobotDriver
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

LATE_POSE = 0.15
"""How late [share of a period] a period's pose may be before the loop decides with the newest
it has (:attr:`~skidnav.realtime.control.periods.PeriodicControl.late_pose`): a dropped pose
costs its period 15 %, not a whole second period."""


class OnlinePlanner:
    """The agent's planner as the policy loop asks it, on the newest view its learner published
    (a :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`)."""

    def __init__(self, agent: MPPIKinematicAgent) -> None:
        self.agent = agent
        self.lidar_rays, self.lidar_range = agent.lidar_rays, agent.lidar_range
        self.goal = agent.goal
        self.control_period = agent.robot.action_duration
        self.learner: BackgroundLearner | None = None

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s]: one MPPI step at ``observation`` on the learner's newest view."""
        assert self.learner is not None, "the loop sets the learner"
        left, right = self.agent.act_on(observation, self.learner.view).tolist()
        return left, right


class MPPILoop(PolicyLoop):
    """Runs ``mppi-kinematic`` on a connected driver, learning off the control path (module
    doc).

    Args:
        driver, grid_map, config, out, robot, grid, progress, wait_for_operator: as
            :class:`~skidnav.realtime.control.policy_loop.PolicyLoop`.
        agent: the agent, new, loaded from a file or from a checkpoint.
    """

    def __init__(
        self,
        driver: RobotDriver,
        agent: MPPIKinematicAgent,
        grid_map: GridMap,
        config: RealtimeConfig,
        out: Path,
        *,
        robot: RobotParams | None = None,
        grid: Discretization | None = None,
        progress: Callable[[str], None] | None = None,
        wait_for_operator: Callable[[str], None] | None = None,
    ) -> None:
        planner = OnlinePlanner(agent)
        super().__init__(
            driver, planner, grid_map, config, out, policy_name=agent.name, robot=robot,
            grid=grid, progress=progress, wait_for_operator=wait_for_operator,
        )  # fmt: skip
        self.agent = agent
        self.late_pose = LATE_POSE
        self.learner = BackgroundLearner(agent, self.log.write, self.monitor.trip)
        planner.learner = self.learner
        self.intervals: list[float] = []
        """Robot seconds between consecutive decisions within an episode."""
        self._last_decision: float | None = None

    def state_dict(self) -> dict[str, Any]:
        """The loop state of :class:`EpisodeLoop` with the agent's name (``--resume`` loads the
        agent of the checkpoint) and the learner's statistics."""
        return {
            **EpisodeLoop.state_dict(self),
            "agent": self.agent.name,
            "learning": asdict(self.learner.stats),
        }

    def decide(self, pose: Pose) -> Decision:
        """:meth:`PolicyLoop.decide`, its time noted (:attr:`intervals`)."""
        now = time.monotonic()
        if self._last_decision is not None:
            self.intervals.append((now - self._last_decision) * self.settings.time_scale)
        self._last_decision = now
        return super().decide(pose)

    def _after_action(
        self,
        decision: Decision,
        end: Pose,
        rows: np.ndarray,
        collided: bool,
        reward: float,
        ended: tuple[bool, bool],
    ) -> None:
        """Hand the step to the learner (module doc, step 2)."""
        cell = self.grid.unflatten(self.grid.state(end.x, end.y, end.heading))
        info = step_info(
            (end.x, end.y, end.heading), cell, collided, decision.command,
            self.grid.region(end.x, end.y), rows,
        )  # fmt: skip
        next_observation = self.features(np.array([end.x, end.y, end.heading]))
        step = Step(decision.observation, np.array(decision.command), reward, next_observation,
                    ended[0], ended[1], info)  # fmt: skip
        self.learner.submit(step)

    def _play(self, result: EpisodeResult) -> None:
        self._last_decision = None  # homing or a stop came between: not a control period
        super()._play(result)

    def _end_episode(self) -> None:
        self.learner.drain()
        with self.learner.lock:
            self.agent.end_episode()

    def _save_checkpoint(self, episode: int) -> None:
        self.learner.drain()
        with self.learner.lock:
            self.checkpoints.save(episode, self.agent, self.state_dict())

    def run(self, first_episode: int = 0) -> int:
        """:meth:`EpisodeLoop.run` with the learner's thread running."""
        self.learner.start()
        try:
            return super().run(first_episode)
        finally:
            self.learner.close()

    def summary_fields(self) -> dict[str, Any]:
        """The control period [s robot time] between decisions (median, 95th percentile,
        longest, count) and the learner's statistics, for ``summary.json``."""
        intervals = np.asarray(self.intervals, dtype=np.float64)
        period: dict[str, Any] = {"target": self.settings.period * self.settings.substeps}
        if intervals.size:
            period.update(
                median=float(np.median(intervals)), p95=float(np.percentile(intervals, 95)),
                longest=float(intervals.max()), count=int(intervals.size),
            )  # fmt: skip
        return {"control_period": period, "learning": asdict(self.learner.stats)}
