"""The real-time loop of a tabular agent: it acts on a robot and learns online
(docs/realtime.md).

One action = ``substeps`` control periods of ``period`` seconds of robot time (``period /
time_scale`` wall seconds) of the discrete action's wheel speeds
(:func:`~skidnav.robot.kinematics.commanded_wheel_speeds`), driven through
:class:`~skidnav.realtime.control.periods.PeriodicControl` (robot-clock periods, virtual bumper,
lockstep). At the end of an action the wheels are stopped while the agent learns ("stop and
think"), so planning time never moves the robot; the reward (the env's rule), the discrete states
and the ``info`` dict (built by the env's :func:`~skidnav.envs.step_info.step_info`) follow the
env's contract. Episodes, homing, checkpoints and the recovery after a safety trip are those of
:class:`~skidnav.realtime.control.episodes.EpisodeLoop`; a frozen continuous policy runs in
:mod:`.policy_loop` instead.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from skidnav.agents.tabular.agent import TabularAgent
from skidnav.envs.step_info import step_info
from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.episodes import (
    EXIT_ALL_ABORTED,
    EXIT_DONE,
    EXIT_INTERRUPTED,
    EXIT_SAFETY,
    EpisodeLoop,
)
from skidnav.realtime.control.periods import Aborted
from skidnav.realtime.control.records import EpisodeResult
from skidnav.realtime.link.interface import Pose, RobotDriver
from skidnav.robot.kinematics import commanded_wheel_speeds
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

__all__ = [
    "EXIT_ALL_ABORTED", "EXIT_DONE", "EXIT_INTERRUPTED", "EXIT_SAFETY", "Aborted", "RealtimeLoop",
]  # fmt: skip


class RealtimeLoop(EpisodeLoop):
    """Runs a tabular agent on a connected driver (see module doc).

    Args:
        driver: connected robot driver. agent: a skidnav agent (act/observe/end_episode/save).
        grid_map: walls, start and goal. config: the run configuration. out: output directory.
        robot, grid: robot geometry and discretization. progress: gets a one-line status.
        wait_for_operator: blocks until the robot was placed by hand (``reset = "manual"``).
    """

    def __init__(
        self,
        driver: RobotDriver,
        agent: TabularAgent,
        grid_map: GridMap,
        config: RealtimeConfig,
        out: Path,
        *,
        robot: RobotParams | None = None,
        grid: Discretization | None = None,
        progress: Callable[[str], None] | None = None,
        wait_for_operator: Callable[[str], None] | None = None,
    ) -> None:
        super().__init__(
            driver, grid_map, config, out, robot=robot, grid=grid, progress=progress,
            wait_for_operator=wait_for_operator,
        )  # fmt: skip
        self.agent = agent

    def _act(self, action: int) -> tuple[Pose, np.ndarray, bool]:
        """Execute one action, then stop; (end pose at rest, kinematic log (n, 6), collided)."""
        return self._hold(commanded_wheel_speeds(action, self.robot.wheel_speed), stop=True)

    def _learn(
        self, state: int, action: int, result: EpisodeResult, last: bool
    ) -> tuple[int, bool]:
        """Act, score, observe; returns (next state, episode over)."""
        end, rows, collided = self._act(action)
        reward, terminated = self._score(end, rows, collided, action == 0, result)
        truncated = last and not terminated
        next_state = self.grid.state(end.x, end.y, end.heading)
        info = step_info(
            (end.x, end.y, end.heading),
            self.grid.unflatten(next_state),
            collided,
            commanded_wheel_speeds(action, self.robot.wheel_speed),
            self.grid.region(end.x, end.y),
            rows,
        )
        self.agent.observe(state, action, reward, next_state, terminated, truncated, info)
        self.log.write(
            "transition",
            {
                "episode": result.episode,
                "state": state,
                "action": action,
                "reward": reward,
                "next_state": next_state,
                "terminated": terminated,
                "truncated": truncated,
                "collision": collided,
                "pose": info["pose"],
                "log_rows": len(rows),
            },
        )
        return next_state, terminated or truncated

    def _play(self, result: EpisodeResult) -> None:
        pose = self._pose()
        state = self.grid.state(pose.x, pose.y, pose.heading)
        for t in range(self.settings.max_actions):
            action = int(self.agent.act(state))
            state, over = self._learn(state, action, result, t + 1 == self.settings.max_actions)
            self.progress(self._status(result))
            if over:
                break

    def _end_episode(self) -> None:
        self.agent.end_episode()

    def _save_checkpoint(self, episode: int) -> None:
        self.checkpoints.save(episode, self.agent, self.state_dict())
