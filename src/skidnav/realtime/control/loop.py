"""The real-time loop: an agent acting on a robot at wall-clock pace (SPEC §6, docs/realtime.md).

One action = ``substeps`` control periods of ``period`` seconds of robot time (``period /
time_scale`` wall seconds). In each period the loop re-sends the action's wheel command and waits
for the robot's next pose, periods being counted on the robot's own clock (the poses' stamps);
consecutive poses give the kinematic log rows
(realtime/control/transition.py). A virtual bumper predicts the next period's pose with the nominal
kinematics: if it would enter a wall cell of the map, the wheels stop and the action is a
collision, as in the env. At the end of an action the wheels are stopped while the agent learns
("stop and think"), so planning time never moves the robot; the reward (the env's rule), the
discrete states and the ``info`` dict (built by the env's
:func:`~skidnav.envs.step_info.step_info`) follow the env's contract. Between episodes the robot
drives back to the start (realtime/control/homing.py) or waits for the operator.

Lockstep (a driver with ``lockstep`` set, docs/realtime.md): each ``cmd`` is one period of robot
time, acknowledged after its pose; the loop waits for each ``ack`` instead of a pose stamp, so
actions last exactly ``substeps`` commands whatever the wall clock does.

Safety (realtime/control/safety.py) can abort an episode at any time: the episode is marked
aborted, its unfinished action is not learned from, a checkpoint is written, and the run
reconnects (link or pose faults, up to ``reconnect_timeout``) or ends (interrupt, robot outside
the arena).
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

from skidnav.agents.core import TabularAgent
from skidnav.envs.step_info import step_info
from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.checkpoint import Checkpoints
from skidnav.realtime.control.homing import HomingController
from skidnav.realtime.control.records import EpisodeResult, RunLog
from skidnav.realtime.control.safety import STOP_WAIT, SafetyLimits, SafetyMonitor
from skidnav.realtime.control.transition import IcrEstimates, WheelSpeedStats, log_row, reward_of
from skidnav.realtime.link.interface import Pose, RobotDriver
from skidnav.robot.kinematics import body_velocities, commanded_wheel_speeds, pose_step
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

log = logging.getLogger(__name__)

EXIT_DONE, EXIT_SAFETY, EXIT_INTERRUPTED = 0, 3, 130


class Aborted(Exception):
    """The safety monitor tripped; the current episode or homing ends."""


class RealtimeLoop:
    """Runs an agent on a connected driver (see module doc).

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
        self.driver, self.agent, self.grid_map, self.config = driver, agent, grid_map, config
        self.settings = config.run
        self.robot = robot or RobotParams()
        self.grid = grid or Discretization()
        self.progress = progress or (lambda line: None)
        self.wait_for_operator = wait_for_operator or (lambda message: None)
        self.log = RunLog(out / "run.jsonl")
        self.checkpoints = Checkpoints(out / "checkpoints", self.settings.keep_checkpoints)
        self.stats = WheelSpeedStats(self.grid.n_regions, self.robot)
        self.icr = IcrEstimates(self.grid.n_regions, self.robot.x_icr)
        self.results: list[EpisodeResult] = []
        self.interrupted = False
        self.waiting_for_operator = False
        self.lockstep = bool(getattr(driver, "lockstep", False))
        self._last_command = (0.0, 0.0)
        self._stamp_before = -math.inf  # lockstep: the robot stamp when the newest cmd left
        self._stale_periods = 0  # lockstep: periods in a row that brought no new pose
        period_wall = self.settings.period_wall
        self.monitor = SafetyMonitor(
            driver,
            SafetyLimits(
                pose_timeout=self.settings.pose_timeout,
                check_interval=min(0.025, max(0.001, period_wall / 4)),
                arena_width=self.robot.arena_width,
                arena_height=self.robot.arena_height,
                arena_margin=self.settings.arena_margin,
            ),
            record=self.log.write,
        )
        if hasattr(driver, "on_pose"):
            driver.on_pose = self._log_pose

    # --- logging and state ---------------------------------------------------------------
    def _log_pose(self, pose: Pose, robot_stamp: float) -> None:
        self.log.write(
            "pose",
            {
                "stamp": pose.stamp,
                "robot_stamp": robot_stamp,
                "x": pose.x,
                "y": pose.y,
                "heading": pose.heading,
            },
        )

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

    def interrupt(self, reason: str) -> None:
        """Called from a signal handler: stop now and end the run."""
        self.interrupted = True
        self.monitor.trip(reason)

    # --- timing and commands -------------------------------------------------------------
    def _wait_until(self, deadline: float) -> None:
        """Sleep until ``deadline`` (monotonic [s]); Aborted as soon as the monitor trips."""
        remaining = deadline - time.monotonic()
        if self.monitor.tripped.wait(max(0.0, remaining)):
            raise Aborted(self.monitor.reason)

    def _command(self, omega_left: float, omega_right: float) -> None:
        if self.lockstep:
            measurement = getattr(self.driver, "latest_measurement", lambda: None)()
            self._stamp_before = -math.inf if measurement is None else measurement[1]
        if not self.monitor.command(omega_left, omega_right):
            raise Aborted(self.monitor.reason)
        self._last_command = (omega_left, omega_right)
        self.log.write("cmd", {"omega_left": omega_left, "omega_right": omega_right})

    def _measure(self) -> tuple[Pose, float]:
        """The newest pose and its robot time [s], waiting for a first one (the monitor bounds
        the wait). Drivers without a robot clock give the local stamp times the time scale."""
        while True:
            measurement = getattr(self.driver, "latest_measurement", lambda: None)()
            if measurement is not None:
                return measurement  # type: ignore[no-any-return]
            pose = self.driver.latest_pose()
            if pose is not None:
                return pose, pose.stamp * self.settings.time_scale
            self._wait_until(time.monotonic() + self.monitor.limits.check_interval)

    def _pose(self) -> Pose:
        """The newest pose (see :meth:`_measure`)."""
        return self._measure()[0]

    def _blocked(self, x: float, y: float) -> bool:
        inside = 0 <= x <= self.robot.arena_width and 0 <= y <= self.robot.arena_height
        return not inside or bool(self.grid_map.occupancy[self.grid.cell(x, y)])

    def _would_collide(self, pose: Pose, command: tuple[float, float]) -> bool:
        """Virtual bumper: the nominal pose after one period (no slip, nominal x_ICR, the robot's
        integrator, not clipped to the arena) lies in a wall or outside (or already does)."""
        v_x, v_y, yaw_rate = body_velocities(
            command[0],
            command[1],
            self.robot.x_icr,
            self.robot.wheel_radius,
            self.robot.half_track,
        )
        x, y, _ = pose_step(
            pose.x, pose.y, pose.heading, v_x, v_y, yaw_rate, self.settings.period,
            self.robot.exact_integration,
        )  # fmt: skip
        return self._blocked(pose.x, pose.y) or self._blocked(x, y)

    # --- one action ----------------------------------------------------------------------
    def _wait_for_stamp(
        self, target: float, deadline: float, periods: int = 1
    ) -> tuple[Pose, float]:
        """The newest pose once its robot-clock stamp reaches ``target`` [s], polling ten times
        per control period; at ``deadline`` (monotonic [s]) the newest pose whatever its stamp,
        so a dropped pose never stalls an action (the watchdog handles a silent robot).
        Lockstep: :meth:`_lockstep_periods` of ``periods`` instead."""
        if self.lockstep:
            return self._lockstep_periods(periods)
        poll = self.settings.period_wall / 10.0
        while True:
            pose, stamp = self._measure()
            now = time.monotonic()
            if stamp >= target - 1e-9 or now >= deadline:
                return pose, stamp
            self._wait_until(min(deadline, now + poll))

    def _lockstep_periods(self, periods: int) -> tuple[Pose, float]:
        """Lockstep: the newest pose after the newest command's period and ``periods − 1`` more
        of the same command, each ended by its ``ack``. A pose outside the arena, or
        ``pose_timeout_periods`` periods in a row without a new pose (a silent tracker), trip
        the monitor at once; the wall-clock watchdog still bounds each wait."""
        answered = self.driver.wait_answered  # type: ignore[attr-defined]
        for n in range(periods):
            if n:
                self._command(*self._last_command)
            while not answered(self.monitor.limits.check_interval):
                self._wait_until(time.monotonic())  # Aborted once the monitor tripped
            pose, stamp = self._measure()
            self._stale_periods = 0 if stamp > self._stamp_before else self._stale_periods + 1
            reason = self.monitor.check()
            if reason is None and self._stale_periods >= self.settings.pose_timeout_periods:
                reason = f"pose stale for {self._stale_periods} lockstep periods"
            if reason is not None:
                self.monitor.trip(reason)
                raise Aborted(reason)
        return pose, stamp

    def _act(self, action: int) -> tuple[Pose, np.ndarray, bool]:
        """Execute one action; (end pose, kinematic log (n, 6), collided).

        Periods are counted on the robot's clock (pose stamps), not the host's: at a high time
        scale a host scheduling delay of a millisecond is a whole period, and counting it would
        make actions last 8 to 11 periods instead of ``substeps``. The wall clock only bounds
        each wait (two periods), so a lost pose cannot stall the action."""
        command = commanded_wheel_speeds(action, self.robot.wheel_speed)
        period, period_wall = self.settings.period, self.settings.period_wall
        pose, stamp = self._measure()
        first = stamp
        rows: list[np.ndarray] = []
        collided = False
        for k in range(self.settings.substeps):
            if self._would_collide(pose, command):
                collided = True
                break
            self._command(*command)
            target = first + (k + 1) * period
            new, new_stamp = self._wait_for_stamp(target, time.monotonic() + 2.0 * period_wall)
            region = self.grid.region(pose.x, pose.y)
            row = log_row(pose, new, new_stamp - stamp, region, command)
            if row is not None:
                if k >= self.settings.settle_periods:
                    rows.append(row)
                pose, stamp = new, new_stamp
        self._command(0.0, 0.0)
        # let the robot come to rest so the end pose includes all motion of the action
        settle = max(1, self.settings.settle_periods)
        end, _ = self._wait_for_stamp(
            stamp + settle * period, time.monotonic() + (settle + 1.0) * period_wall, settle
        )
        return end, np.array(rows, dtype=np.float64).reshape(-1, 6), collided

    def _learn(
        self, state: int, action: int, result: EpisodeResult, last: bool
    ) -> tuple[int, bool]:
        """Act, score, observe; returns (next state, episode over)."""
        end, rows, collided = self._act(action)
        self.icr.add_rows(rows)
        if action == 0:
            self.stats.add_rows(rows)
        reward, terminated = reward_of(end, collided, self.grid_map.goal, self.grid, self.stats)
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
        result.actions += 1
        result.return_ += reward
        result.collisions += int(collided)
        result.reached_goal = terminated
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

    # --- episodes ------------------------------------------------------------------------
    def _status(self, result: EpisodeResult) -> str:
        goals = sum(r.reached_goal for r in self.results)
        aborted = sum(r.aborted for r in self.results)
        return (
            f"episode {result.episode + 1}/{self.settings.episodes}  action {result.actions}  "
            f"return {result.return_:.1f}  goals {goals}  aborted {aborted}"
        )

    def run_episode(self, episode: int) -> EpisodeResult:
        """One episode from the current pose; aborted (not raised) if the monitor trips."""
        result = EpisodeResult(episode)
        started = time.monotonic()
        self.monitor.arm()
        self.log.write("episode_start", {"episode": episode})
        try:
            pose = self._pose()
            state = self.grid.state(pose.x, pose.y, pose.heading)
            for t in range(self.settings.max_actions):
                action = int(self.agent.act(state))
                state, over = self._learn(state, action, result, t + 1 == self.settings.max_actions)
                self.progress(self._status(result))
                if over:
                    break
        except Aborted as abort:
            result.aborted, result.reason = True, str(abort)
        self.agent.end_episode()
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
            # one command per period of the robot's clock, as in _act: a controller fed the
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
        if self.interrupted or reason.startswith("robot outside"):
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
        """Episodes ``first_episode`` … ``episodes − 1``; returns the exit code
        (0 done, 3 ended by a safety trip it could not recover from, 130 interrupted)."""
        self.monitor.start()
        episode = first_episode
        try:
            while episode < self.settings.episodes:
                result = self.run_episode(episode)
                self.results.append(result)
                self.checkpoints.save(episode, self.agent, self.state_dict())
                episode += 1
                if result.aborted and not self._recover():
                    return EXIT_INTERRUPTED if self.interrupted else EXIT_SAFETY
                if episode < self.settings.episodes and not self._between_episodes():
                    return EXIT_INTERRUPTED if self.interrupted else EXIT_SAFETY
            self.monitor.disarm()
            return EXIT_DONE
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
