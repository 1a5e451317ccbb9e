"""Commanding a robot one control period at a time: timing, the safety gate, the virtual bumper.

The layer every real-time loop drives through (:mod:`.loop` for the tabular agents,
:mod:`.policy_loop` for continuous policies). :meth:`PeriodicControl._hold` runs one action: it
re-sends a wheel command every control period of ``period`` seconds of robot time for
``substeps`` periods, periods being counted on the robot's own clock (the poses' stamps), and
turns consecutive poses into kinematic log rows (realtime/control/transition.py). A virtual
bumper predicts the next period's pose with the nominal kinematics (x_ICR estimated on the floor,
in the episode loop): if it would enter a wall cell of the map, the wheels stop and the action is
a collision, as in the env.

Lockstep (a driver with ``lockstep`` set, docs/realtime.md): each ``cmd`` is one period of robot
time, acknowledged after its pose; the loop waits for each ``ack`` instead of a pose stamp, so
actions last exactly ``substeps`` commands whatever the wall clock does.

Every command passes the safety monitor (realtime/control/safety.py); once it has tripped, the
waits and commands raise :class:`Aborted`.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.records import RunLog
from skidnav.realtime.control.safety import SafetyLimits, SafetyMonitor
from skidnav.realtime.control.transition import log_row
from skidnav.realtime.link.interface import Pose, RobotDriver
from skidnav.robot.kinematics import body_velocities, pose_step
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap


class Aborted(Exception):
    """The safety monitor tripped; the current episode or homing ends."""


class PeriodicControl:
    """A connected driver commanded period by period (see module doc), with the run log
    ``out/run.jsonl`` and the safety monitor.

    Args:
        driver: connected robot driver. grid_map: walls, start and goal.
        config: the run configuration. out: output directory.
        robot, grid: robot geometry and discretization.
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
    ) -> None:
        self.driver, self.grid_map, self.config = driver, grid_map, config
        self.settings = config.run
        self.robot = robot or RobotParams()
        self.grid = grid or Discretization()
        self.log = RunLog(out / "run.jsonl")
        self.lockstep = bool(getattr(driver, "lockstep", False))
        self._last_command = (0.0, 0.0)
        self._stamp_before = -math.inf  # lockstep: the robot stamp when the newest cmd left
        self._stale_periods = 0  # lockstep: periods in a row that brought no new pose
        self.late_pose: float | None = None
        """None (the default): each period of an action waits for its pose up to two periods
        after its command (:meth:`_hold`). A share f of a period: a pilot that decides every
        period (:mod:`.mppi_loop`) gives up on a period's pose f periods after it was due (a
        whole number of periods after the newest pose's stamp) and goes on with the newest, so
        a dropped pose delays its next decision by f of a period, not by a whole one; a
        kinematic log row spanning more than 1.5 periods (two commands) is then left out."""
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

    def _x_icr(self, pose: Pose) -> float:
        """x_ICR [m] the virtual bumper predicts with at ``pose``: the nominal one (the episode
        loop's estimate, :meth:`~skidnav.realtime.control.episodes.EpisodeLoop._x_icr`)."""
        return self.robot.x_icr

    def _would_collide(self, pose: Pose, command: tuple[float, float]) -> bool:
        """Virtual bumper: the pose after one period with the nominal wheel radius and half track
        (no slip), the x_ICR of :meth:`_x_icr` and the robot's integrator, not clipped to the
        arena, lies in a wall or outside (or already does)."""
        v_x, v_y, yaw_rate = body_velocities(
            command[0],
            command[1],
            self._x_icr(pose),
            self.robot.wheel_radius,
            self.robot.half_track,
        )
        x, y, _ = pose_step(
            pose.x, pose.y, pose.heading, v_x, v_y, yaw_rate, self.settings.period,
            self.robot.exact_integration,
        )  # fmt: skip
        return self._blocked(pose.x, pose.y) or self._blocked(x, y)

    # --- waiting for periods -------------------------------------------------------------
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

    # --- one action ----------------------------------------------------------------------
    def _hold(self, command: tuple[float, float], *, stop: bool) -> tuple[Pose, np.ndarray, bool]:
        """Hold the wheel ``command`` (ω_L, ω_R) [rad/s] for one action; (end pose, kinematic
        log float64 (n, 6), collided). With ``stop``, and after a collision, the wheels are
        stopped at the end and the end pose read once the robot is at rest
        (:meth:`_stop_and_settle`); without, the end pose is the one of the last period and
        the wheels keep the command until the next one.

        Periods are counted on the robot's clock (pose stamps), not the host's: at a high time
        scale a host scheduling delay of a millisecond is a whole period, and counting it would
        make actions last 8 to 11 periods instead of ``substeps``. The wall clock only bounds
        each wait (two periods; :attr:`late_pose`), so a lost pose cannot stall the action."""
        period = self.settings.period
        pose, stamp = self._measure()
        first = stamp
        rows: list[np.ndarray] = []
        collided = False
        for k in range(self.settings.substeps):
            if self._would_collide(pose, command):
                collided = True
                break
            previous = self._last_command
            self._command(*command)
            target = first + (k + 1) * period
            new, new_stamp = self._wait_for_stamp(target, self._pose_deadline(pose))
            region = self.grid.region(pose.x, pose.y)
            in_effect = self._in_effect(previous, command, new_stamp - stamp)
            row = log_row(pose, new, new_stamp - stamp, region, in_effect)
            if row is not None:
                spans_one = self.late_pose is None or new_stamp - stamp <= 1.5 * period
                if k >= self.settings.settle_periods and spans_one:
                    rows.append(row)
                pose, stamp = new, new_stamp
        if stop or collided:
            pose = self._stop_and_settle(stamp)
        return pose, np.array(rows, dtype=np.float64).reshape(-1, 6), collided

    def _in_effect(
        self, previous: tuple[float, float], command: tuple[float, float], elapsed: float
    ) -> tuple[float, float]:
        """The wheel command (ω_L, ω_R) [rad/s] in effect, on average, over the ``elapsed``
        [s robot time] after ``command`` replaced ``previous``: the wheels ran ``previous`` for
        ``[run] command_latency`` of it (all of it at most), ``command`` for the rest."""
        latency = self.settings.command_latency
        if latency <= 0.0 or not elapsed > 0.0 or previous == command:
            return command
        share = min(1.0, latency / elapsed)
        return (
            share * previous[0] + (1.0 - share) * command[0],
            share * previous[1] + (1.0 - share) * command[1],
        )

    def _pose_deadline(self, newest: Pose) -> float:
        """When (monotonic [s]) a period's wait for its pose ends whatever its stamp, the
        command just sent and ``newest`` the pose before it (:attr:`late_pose`)."""
        period_wall, now = self.settings.period_wall, time.monotonic()
        deadline = now + 2.0 * period_wall
        if self.late_pose is None:
            return deadline
        # the next pose is due a whole number of periods after the newest one's stamp
        periods = math.floor(max(0.0, now - newest.stamp) / period_wall) + 1
        return min(deadline, newest.stamp + (periods + self.late_pose) * period_wall)

    def _stop_and_settle(self, stamp: float) -> Pose:
        """Stop the wheels and return the pose ``max(1, settle_periods)`` periods of robot time
        after ``stamp`` [s], so that it includes all motion of the commands before."""
        period, period_wall = self.settings.period, self.settings.period_wall
        self._command(0.0, 0.0)
        settle = max(1, self.settings.settle_periods)
        end, _ = self._wait_for_stamp(
            stamp + settle * period, time.monotonic() + (settle + 1.0) * period_wall, settle
        )
        return end
