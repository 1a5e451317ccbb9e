"""The real-time loop of a frozen continuous policy (docs/realtime.md, "Continuous policies").

A :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy` chooses both wheel speeds from the
env's ``"features"`` observation. Each action, the loop computes that observation from the
newest tracked pose (:class:`~skidnav.envs.features.PoseFeatures` of the run's map, with the
policy's ``lidar_rays`` and ``lidar_range``), asks the policy for (ω_L, ω_R), clips them to
± ``robot.wheel_speed`` (:func:`~skidnav.envs.navigation.clipped_wheel_speeds`, the env's rule)
and holds them for ``substeps`` control periods — one action of the continuous env with
``control_period = substeps · period`` — through the same periods, virtual bumper, watchdog and
lockstep as a tabular agent (:mod:`.periods`). A frozen policy does not learn: nothing is
observed, and the wheels are not stopped between its actions, only after a collision and when
the episode ends (goal or ``max_actions``). Each action is scored by the env's rule and logged
as a ``transition`` with the observation, the policy's output and the command sent.

A policy that raises, or returns anything but two finite numbers, trips the safety monitor
(``policy failed: …``): the robot stops and the run ends with exit code 3.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.envs.features import PoseFeatures
from skidnav.envs.navigation import clipped_wheel_speeds
from skidnav.errors import first_line
from skidnav.kernels.navigation import is_forward_drive
from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.episodes import EpisodeLoop
from skidnav.realtime.control.periods import Aborted
from skidnav.realtime.control.records import EpisodeResult
from skidnav.realtime.link.interface import Pose, RobotDriver
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

log = logging.getLogger(__name__)


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
            log.error("%s", reason, exc_info=True)
            self.monitor.trip(reason)
            raise Aborted(reason) from None
        left, right = np.asarray(output, dtype=np.float64).tolist()
        return Decision(observation, (left, right), command)

    def _step(self, result: EpisodeResult, last: bool) -> bool:
        """Decide, drive, score and log one action; True if the episode is over."""
        before = self._pose()
        decision = self.decide(before)
        end, rows, collided = self._hold(decision.command, stop=False)
        forward = is_forward_drive(decision.command)
        reward, terminated = self._score(end, rows, collided, forward, result)
        truncated = last and not terminated
        if (terminated or truncated) and not collided:  # a collision has stopped the wheels
            self._stop_and_settle(self._measure()[1])
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
                "log_rows": len(rows),
            },
        )
        return terminated or truncated

    def _play(self, result: EpisodeResult) -> None:
        for t in range(self.settings.max_actions):
            over = self._step(result, t + 1 == self.settings.max_actions)
            self.progress(self._status(result))
            if over:
                break

    def _save_checkpoint(self, episode: int) -> None:
        self.checkpoints.save(episode, None, self.state_dict())
