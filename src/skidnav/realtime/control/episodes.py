"""Episodes of a real-time run, whoever chooses the wheel speeds (docs/realtime.md).

:class:`EpisodeLoop` runs the episodes, the homing between them (realtime/control/homing.py) or
the operator's reset, the checkpoints and the recovery after a safety trip; what happens inside
an episode is its subclass's: a tabular agent that learns online (:mod:`.loop`) or a frozen
continuous policy (:mod:`.policy_loop`). Every action is scored by the env's rule
(:func:`~skidnav.realtime.control.transition.reward_of`), its kinematic log rows feeding the
x_ICR estimates that homing pivots about and, for forward actions, the observed wheel-speed
variance of the reward.

Safety (realtime/control/safety.py) can abort an episode at any time: the episode is marked
aborted, its unfinished action is not learned from, a checkpoint is written, and the run
reconnects (link or pose faults, up to ``reconnect_timeout``) or ends (interrupt, robot outside
the arena, a policy that failed).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.checkpoint import Checkpoints
from skidnav.realtime.control.homing import HomingController
from skidnav.realtime.control.periods import Aborted, PeriodicControl
from skidnav.realtime.control.records import EpisodeResult
from skidnav.realtime.control.safety import STOP_WAIT
from skidnav.realtime.control.transition import IcrEstimates, WheelSpeedStats, reward_of
from skidnav.realtime.link.interface import Pose, RobotDriver
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

log = logging.getLogger(__name__)

EXIT_DONE, EXIT_SAFETY, EXIT_ALL_ABORTED, EXIT_INTERRUPTED = 0, 3, 4, 130
"""Exit codes of a run (docs/realtime.md, "Exit codes"): every episode run, at least one of
them not aborted; ended by a safety trip it could not recover from; every episode run, every
one aborted; interrupted."""
FINAL_TRIPS = ("robot outside", "policy")
"""Trip reasons that end the run instead of a reconnect: someone has to look at the robot, or
at the policy."""


class EpisodeLoop(PeriodicControl):
    """The episodes of a run on a connected driver (see module doc); subclasses define
    :meth:`_play`, :meth:`_end_episode` and :meth:`_save_checkpoint`.

    Args:
        driver, grid_map, config, out, robot, grid: as :class:`PeriodicControl`.
        progress: gets a one-line status.
        wait_for_operator: blocks until the robot was placed by hand (``reset = "manual"``).
    """

    def __init__(
        self,
        driver: RobotDriver,
        grid_map: GridMap,
        config: RealtimeConfig,
        out: Path,
        *,
        robot: RobotParams | None = None,
        grid: Discretization | None = None,
        progress: Callable[[str], None] | None = None,
        wait_for_operator: Callable[[str], None] | None = None,
    ) -> None:
        super().__init__(driver, grid_map, config, out, robot=robot, grid=grid)
        self.progress = progress or (lambda line: None)
        self.wait_for_operator = wait_for_operator or (lambda message: None)
        self.checkpoints = Checkpoints(out / "checkpoints", self.settings.keep_checkpoints)
        self.stats = WheelSpeedStats(self.grid.n_regions, self.robot)
        self.icr = IcrEstimates(self.grid.n_regions, self.robot.x_icr)
        self.results: list[EpisodeResult] = []
        self.interrupted = False
        self.waiting_for_operator = False

    def _x_icr(self, pose: Pose) -> float:
        """x_ICR [m] of the virtual bumper at ``pose``: the estimate of its region (homing's,
        :class:`IcrEstimates`), within the axles (−a ≤ x_ICR ≤ b). With the nominal 5 cm on the
        MuJoCo robot (x_ICR ≈ 0) the bumper predicted a turn in place away from a wall beside
        the robot to slide the body into it and stopped every such turn: the planner, whose
        model had learned the turn, chose it again and the robot stood pressed against the wall
        (docs/robot-learning.md, "Measured on the MuJoCo robot")."""
        value = float(self.icr.values()[self.grid.region(pose.x, pose.y)])
        return min(max(value, -self.robot.front_axle), self.robot.rear_axle)

    # --- what a subclass defines ---------------------------------------------------------
    def _play(self, result: EpisodeResult) -> None:
        """The actions of one episode from the current pose, counted into ``result``; raises
        :class:`Aborted` when the monitor trips."""
        raise NotImplementedError

    def _end_episode(self) -> None:
        """Called after every episode, aborted or not."""

    def _save_checkpoint(self, episode: int) -> None:
        """Write the checkpoint after ``episode`` (0-based)."""
        raise NotImplementedError

    # --- state ---------------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        """The loop state saved with every checkpoint."""
        return {
            "format": "skidnav-realtime-loop",
            "version": 1,
            "episodes_done": len(self.results),
            "results": [asdict(result) for result in self.results],
            "wheel_speed_stats": self.stats.stats.tolist(),
            "icr_sums": self.icr.sums.tolist(),
            "run": asdict(self.settings),
        }

    def restore(self, state: dict[str, Any]) -> None:
        """Continue from :meth:`state_dict` of an earlier run."""
        self.results = [EpisodeResult(**result) for result in state["results"]]
        stats = np.asarray(state["wheel_speed_stats"], dtype=np.float64)
        if not self.stats.load(stats):
            log.warning("checkpoint wheel-speed statistics of shape %s ignored", stats.shape)
        icr_sums = np.asarray(state.get("icr_sums", self.icr.sums), dtype=np.float64)
        if icr_sums.shape == self.icr.sums.shape:
            self.icr.sums[:] = icr_sums

    def summary_fields(self) -> dict[str, Any]:
        """What the loop adds to the run's ``summary.json`` (nothing; a learner's loop adds its
        control-period and learning statistics)."""
        return {}

    def interrupt(self, reason: str) -> None:
        """Called from a signal handler: stop now and end the run (plain assignments only: the
        watchdog makes the trip, :meth:`~.safety.SafetyMonitor.request_trip`)."""
        self.interrupted = True
        self.monitor.request_trip(reason)

    # --- scoring -------------------------------------------------------------------------
    def _score(
        self, end: Pose, rows: np.ndarray, collided: bool, forward: bool, result: EpisodeResult
    ) -> tuple[float, bool]:
        """(reward, terminated) of an action that ended at ``end`` with kinematic log ``rows``
        (the wheel-speed statistics learn from them if it was a ``forward`` action), counted
        into ``result``."""
        self.icr.add_rows(rows)
        if forward:
            self.stats.add_rows(rows)
        reward, terminated = reward_of(end, collided, self.grid_map.goal, self.grid, self.stats)
        result.actions += 1
        result.return_ += reward
        result.collisions += int(collided)
        result.reached_goal = terminated
        return reward, terminated

    def _status(self, result: EpisodeResult) -> str:
        goals = sum(r.reached_goal for r in self.results)
        aborted = sum(r.aborted for r in self.results)
        return (
            f"episode {result.episode + 1}/{self.settings.episodes}  action {result.actions}  "
            f"return {result.return_:.1f}  goals {goals}  aborted {aborted}"
        )

    # --- episodes ------------------------------------------------------------------------
    def run_episode(self, episode: int) -> EpisodeResult:
        """One episode from the current pose; aborted (not raised) if the monitor trips."""
        result = EpisodeResult(episode)
        started = time.monotonic()
        self.monitor.arm()
        self.log.write("episode_start", {"episode": episode})
        try:
            self._play(result)
        except Aborted as abort:
            result.aborted, result.reason = True, str(abort)
        self._end_episode()
        result.wall_time = time.monotonic() - started
        self.log.write("episode_end", asdict(result))
        return result

    def _reset_robot(self) -> None:
        """Home to the start (``auto``) or wait for the operator (``manual``)."""
        if self.settings.reset == "manual":
            self.monitor.disarm()
            self.waiting_for_operator = True
            try:
                self.wait_for_operator("place the robot on the start cell, heading +x")
            finally:
                self.waiting_for_operator = False
            self.monitor.arm()
            return
        controller = HomingController(
            self.grid_map,
            self.grid,
            self.robot.wheel_speed,
            self.settings.homing_tolerance,
            x_icr=self.icr.values(),
        )
        period, period_wall = self.settings.period, self.settings.period_wall
        self.log.write("homing_start", {})
        pose, stamp = self._measure()
        for _ in range(math.ceil(self.settings.homing_timeout / period)):
            command = controller.command(pose)
            if command is None:
                break
            self._command(*command)
            # one command per period of the robot's clock, as in _hold: a controller fed the
            # same pose twice over a lagging link overshoots and circles on a slippery floor
            pose, stamp = self._wait_for_stamp(stamp + period, time.monotonic() + 2 * period_wall)
        else:
            log.warning("homing timed out; the next episode starts where the robot is")
        self._command(0.0, 0.0)
        self.log.write("homing_end", {"pose": list(self._pose()[1:])})

    def _recover(self) -> bool:
        """After a trip: reconnect and clear it, or False if the run must end."""
        self.monitor.stop_done.wait(timeout=STOP_WAIT)
        reason = self.monitor.reason or ""
        if self.interrupted or reason.startswith(FINAL_TRIPS):
            return False
        deadline = time.monotonic() + self.settings.reconnect_timeout
        while time.monotonic() < deadline and not self.interrupted:
            try:
                self.driver.close()
                self.driver.connect()
            except ConnectionError as error:
                log.info("reconnect failed: %s", error)
                time.sleep(0.2)
                continue
            self.monitor.reset()
            self.log.write("reconnected", {"after": reason})
            return True
        return False

    def run(self, first_episode: int = 0) -> int:
        """Episodes ``first_episode`` … ``episodes − 1``; returns the exit code: 0 done, at
        least one of these episodes not aborted (the goal reached or the action limit); 4
        (:data:`EXIT_ALL_ABORTED`) done, but every one of them aborted (a robot that stalls,
        a lease or link lost every time: nothing was learned); 3 ended by a safety trip it
        could not recover from; 130 interrupted."""
        self.monitor.start()
        episode = first_episode
        done_before = len(self.results)  # restored from a checkpoint
        try:
            while episode < self.settings.episodes:
                result = self.run_episode(episode)
                self.results.append(result)
                self._save_checkpoint(episode)
                episode += 1
                if result.aborted and not self._recover():
                    return EXIT_INTERRUPTED if self.interrupted else EXIT_SAFETY
                if episode < self.settings.episodes and not self._between_episodes():
                    return EXIT_INTERRUPTED if self.interrupted else EXIT_SAFETY
            self.monitor.disarm()
            ran = self.results[done_before:]
            return EXIT_ALL_ABORTED if ran and all(r.aborted for r in ran) else EXIT_DONE
        except KeyboardInterrupt:  # raised by the signal handler while waiting for the operator
            self.interrupted = True
            return EXIT_INTERRUPTED
        finally:
            self.monitor.close()
            self.log.close()

    def _between_episodes(self) -> bool:
        """Reset the robot, recovering from trips on the way; False if the run must end."""
        while True:
            try:
                self._reset_robot()
                return True
            except Aborted:
                if not self._recover():
                    return False
