"""The real-time loop of a frozen continuous policy (docs/realtime.md, "Continuous policies").

A :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy` chooses both wheel speeds from the
env's ``"features"`` observation. Each action, the loop computes that observation from the
newest tracked pose (:class:`~skidnav.sim.features.PoseFeatures` of the run's map, with the
policy's ``lidar_rays`` and ``lidar_range``), asks the policy for (ω_L, ω_R), clips them to
± ``robot.wheel_speed`` (:func:`~skidnav.robot.kinematics.clipped_wheel_speeds`, the env's rule)
and holds them for ``substeps`` control periods — one action of the continuous env with
``control_period = substeps · period`` — through the same periods, virtual bumper, watchdog and
lockstep as a tabular agent (:mod:`.periods`). A frozen policy does not learn: nothing is
observed, and the wheels are not stopped between its actions, only after a collision, when the
episode ends (goal or ``max_actions``: the last action ends at rest, as an agent's), and before
the policy is asked when the held command would enter a wall within a period or the policy's
previous answer took over half a period (:data:`SLOW_DECISION`). Each action is scored by the
env's rule and logged as a ``transition`` with the observation, the policy's output and the
command sent, before the wheels stop at the goal.

A policy that raises, or returns anything but two finite numbers, trips the safety monitor
(``policy failed: …``): the robot stops and the run ends with exit code 3. A policy with a state
of its own within an episode (:class:`~skidnav.agents.greedy.RolloutState`: the plan of
``mppi-kinematic``'s frozen planner) forgets it when an episode starts.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from skidnav.agents.greedy import start_rollout
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import first_line
from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.episodes import EpisodeLoop
from skidnav.realtime.control.periods import Aborted
from skidnav.realtime.control.records import EpisodeResult
from skidnav.realtime.link.interface import Pose, RobotDriver
from skidnav.robot.kinematics import clipped_wheel_speeds
from skidnav.robot.params import RobotParams
from skidnav.sim.features import PoseFeatures
from skidnav.sim.navigation import is_forward_drive
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

log = logging.getLogger(__name__)


SLOW_DECISION = 0.5
"""A policy answering in more than this share of a control period (wall time) decides its next
action with the wheels stopped: the virtual bumper checks one period ahead of each command, and
the command held while the policy answers would otherwise run unchecked."""


class Decision(NamedTuple):
    """One choice of the policy: the observation float64 (7 + k,), the policy's output and
    the command (ω_L, ω_R) [rad/s] sent, its output clipped to the wheels' limit."""

    observation: np.ndarray
    output: tuple[float, float]
    command: tuple[float, float]


class PolicyLoop(EpisodeLoop):
    """Runs a frozen continuous policy on a connected driver (see module doc).

    Args:
        driver: connected robot driver. policy: the policy. policy_name: what the loop state
            records (``--resume`` checks it): a policy name or a file.
        grid_map, config, out, robot, grid, progress, wait_for_operator: as
            :class:`~skidnav.realtime.control.episodes.EpisodeLoop`.
    """

    def __init__(
        self,
        driver: RobotDriver,
        policy: WheelSpeedPolicy,
        grid_map: GridMap,
        config: RealtimeConfig,
        out: Path,
        *,
        policy_name: str,
        robot: RobotParams | None = None,
        grid: Discretization | None = None,
        progress: Callable[[str], None] | None = None,
        wait_for_operator: Callable[[str], None] | None = None,
    ) -> None:
        super().__init__(
            driver, grid_map, config, out, robot=robot, grid=grid, progress=progress,
            wait_for_operator=wait_for_operator,
        )  # fmt: skip
        self.policy, self.policy_name = policy, policy_name
        self._slow_decision = False  # the policy's last answer took over SLOW_DECISION periods
        self.features = PoseFeatures(grid_map, self.grid, policy.lidar_rays, policy.lidar_range)

    def state_dict(self) -> dict[str, Any]:
        """The loop state of :class:`EpisodeLoop`, with the policy's name."""
        return {**super().state_dict(), "policy": self.policy_name}

    def decide(self, pose: Pose) -> Decision:
        """The policy's choice at ``pose``; the monitor trips and :class:`Aborted` is raised if
        the policy fails (see module doc)."""
        observation = self.features(np.array([pose.x, pose.y, pose.heading]))
        try:
            output = self.policy.wheel_speeds(observation.copy())
            command = clipped_wheel_speeds(output, self.robot.wheel_speed)
        except Exception as error:  # whatever a policy does wrong, the robot must stop
            reason = f"policy failed: {first_line(error, 160)}"
            log.error("%s", reason)  # one line; where it failed only when debugging
            log.debug("the policy's failure", exc_info=True)
            self.monitor.trip(reason)
            raise Aborted(reason) from None
        left, right = np.asarray(output, dtype=np.float64).tolist()
        return Decision(observation, (left, right), command)

    def _step(self, result: EpisodeResult, last: bool) -> bool:
        """Decide, drive, score and log one action; True if the episode is over."""
        before = self._pose()
        if self._last_command != (0.0, 0.0) and (
            self._slow_decision or self._would_collide(before, self._last_command)
        ):  # the held command would run unchecked by the bumper while the policy answers
            self._command(0.0, 0.0)
        started = time.monotonic()
        decision = self.decide(before)
        self._slow_decision = time.monotonic() - started > SLOW_DECISION * self.settings.period_wall
        end, rows, collided = self._hold(decision.command, stop=last)
        forward = is_forward_drive(decision.command)
        reward, terminated = self._score(end, rows, collided, forward, result)
        truncated = last and not terminated
        self._log_transition(result, before, decision, end, reward, terminated, truncated,
                             collided, len(rows))  # fmt: skip
        self._after_action(decision, end, rows, collided, reward, (terminated, truncated))
        if terminated and not collided and not last:  # stopped already otherwise
            self._stop_and_settle(self._measure()[1])
        return terminated or truncated

    def _after_action(
        self,
        decision: Decision,
        end: Pose,
        rows: np.ndarray,
        collided: bool,
        reward: float,
        ended: tuple[bool, bool],
    ) -> None:
        """Called after each action driven to its end (``end`` pose, kinematic log ``rows``
        (n, 6), ``ended`` = (terminated, truncated)): a frozen policy learns nothing; a loop
        whose pilot learns (:mod:`.mppi_loop`) hands the step on."""

    def _log_transition(
        self,
        result: EpisodeResult,
        before: Pose,
        decision: Decision,
        end: Pose,
        reward: float,
        terminated: bool,
        truncated: bool,
        collided: bool,
        log_rows: int,
    ) -> None:
        self.log.write(
            "transition",
            {
                "episode": result.episode,
                "state": self.grid.state(before.x, before.y, before.heading),
                "action": None,
                "observation": decision.observation.tolist(),
                "output": list(decision.output),
                "command": list(decision.command),
                "reward": reward,
                "next_state": self.grid.state(end.x, end.y, end.heading),
                "terminated": terminated,
                "truncated": truncated,
                "collision": collided,
                "pose": [end.x, end.y, end.heading],
                "log_rows": log_rows,
            },
        )

    def _play(self, result: EpisodeResult) -> None:
        start_rollout(self.policy)  # a policy with a state (a planner's plan) starts afresh
        for t in range(self.settings.max_actions):
            over = self._step(result, t + 1 == self.settings.max_actions)
            self.progress(self._status(result))
            if over:
                break

    def _save_checkpoint(self, episode: int) -> None:
        self.checkpoints.save(episode, None, self.state_dict())
