"""The physics of the simulated robot behind the sim server (hardware-in-the-loop stand-in).

One control period of ``dt`` seconds of robot time is one step of the robot's
:class:`~skidnav.realtime.robot_server.dynamics.Dynamics` — by default the simulator's own kernel
(:func:`skidnav.sim.task.drive_substep`, the env's sub-step driven by arbitrary
wheel-speed commands instead of the four actions), or the MuJoCo robot (``physics="mujoco"``):

1. commands whose latency has elapsed take effect (a FIFO of (due time, ω_L, ω_R));
2. each wheel loses U(0, η(ρ, t)) in magnitude (the slip field, possibly drifting,
   :mod:`skidnav.robot.slip`);
3. kinematic: the ICR model with x_ICR[ρ] gives the body twist; the robot's integrator
   (``RobotParams.integrator``: explicit Euler or the exact constant-twist step) advances the
   pose, clipped to the arena. MuJoCo: the slipped speeds are the wheel servos' set points and
   the physics runs for the period on the floor's materials;
4. a step that would end in a wall cell does not happen: walls physically block the robot
   (its heading still turns, as in the kernels).

The measured pose adds Gaussian noise (σ [m] on x and y, σ/0.1 [rad] on the heading). Wheel
commands saturate at ±``RobotParams.wheel_speed`` (the motors' limit).

:class:`Firmware` is the robot's side of the line protocol on one connection (docs/protocol.md,
"What a robot must do"): the reference a microcontroller port follows, written against its
own clock (the wall clock of the server, which keeps running while the process is stalled).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from skidnav.errors import UserError
from skidnav.realtime.arena import arena_map, seed_streams, start_pose
from skidnav.realtime.config import ServerOptions
from skidnav.realtime.control.records import EventLog
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.robot_server.dynamics import (
    PHYSICS,
    Dynamics,
    KinematicDynamics,
    PhysicsDynamics,
    floor_materials,
)
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField, make_slip_field
from skidnav.sim.task import drive_substep, floor_task
from skidnav.world.discretization import Discretization


@dataclass(frozen=True)
class SimRobotConfig:
    """Imperfections of the simulated robot, validated on construction.

    Attributes:
        latency: delay between receiving a command and the wheels following it [s robot time].
        pose_noise: standard deviation of the reported x and y [m].
        drop: probability that a period's pose report is not sent.
    """

    latency: float = 0.0
    pose_noise: float = 0.0
    drop: float = 0.0

    def __post_init__(self) -> None:
        if not 0 <= self.latency < math.inf:
            raise ValueError(f"expected a finite latency >= 0 s, got {self.latency}")
        if not 0 <= self.pose_noise < math.inf:
            raise ValueError(f"expected a finite pose_noise >= 0 m, got {self.pose_noise}")
        if not 0 <= self.drop < 1:
            raise ValueError(f"expected drop in [0, 1), got {self.drop}")


class SimRobot:
    """A skid-steer robot on a slippery floor with walls.

    Args:
        robot: geometry, integrator and control period (``robot.dt`` is the period [s]).
        slip: the floor (its arrays are shared with the kernel's task, not copied: changing
            ``slip.x_icr`` in place changes the floor).
        occupancy: bool (n_x, n_y) walls (True) on the grid of ``grid``, or None for none.
        grid: discretization whose cells index ``occupancy`` and whose regions index ``slip``.
        config: imperfections.
        rng: every random draw (slip, noise, drops).
        pose: initial (x [m], y [m], heading [rad]).
        dynamics: what moves the robot (default: :class:`KinematicDynamics` of the floor task).
    """

    def __init__(
        self,
        robot: RobotParams,
        slip: SlipField,
        occupancy: np.ndarray | None,
        grid: Discretization,
        config: SimRobotConfig,
        rng: np.random.Generator,
        pose: tuple[float, float, float],
        dynamics: Dynamics | None = None,
    ) -> None:
        self.robot = robot
        self.slip = slip
        self.grid = grid
        self.task = floor_task(occupancy, slip, robot, grid)
        self.dynamics = dynamics or KinematicDynamics(self.task)
        self.config = config
        self.rng = rng
        self.pose = (float(pose[0]), float(pose[1]), float(pose[2]))
        self.time = 0.0
        self.wheels = (0.0, 0.0)
        self._queue: deque[tuple[float, float, float]] = deque()

    def command(self, omega_left: float, omega_right: float) -> None:
        """Queue wheel speeds [rad/s] to take effect after the latency; each saturates at
        ±``wheel_speed``. ValueError if one is not finite."""
        if not (math.isfinite(omega_left) and math.isfinite(omega_right)):
            raise ValueError(f"expected finite wheel speeds, got {omega_left}, {omega_right}")
        limit = self.robot.wheel_speed
        left, right = (float(min(max(omega, -limit), limit)) for omega in (omega_left, omega_right))
        self._queue.append((self.time + self.config.latency, left, right))

    def stop(self) -> None:
        """Zero the wheels now and drop every queued command."""
        self._queue.clear()
        self.wheels = (0.0, 0.0)

    @property
    def moving(self) -> bool:
        """True while a wheel turns or a command waits out its latency."""
        return self.wheels != (0.0, 0.0) or bool(self._queue)

    def blocked(self, x: float, y: float) -> bool:
        """True if position (x, y) [m] lies in a wall cell."""
        return bool(self.task.occupancy[self.grid.cell(x, y)])

    def step(self) -> None:
        """Advance one control period (see module doc)."""
        while self._queue and self._queue[0][0] <= self.time + 1e-12:
            _, left, right = self._queue.popleft()
            self.wheels = (left, right)
        noise = (self.rng.random(), self.rng.random())
        self.pose = self.dynamics.advance(self.pose, self.wheels, self.time, noise)
        self.time += self.robot.dt

    def measured_pose(self, droppable: bool = True) -> tuple[float, float, float] | None:
        """The pose as the tracker reports it (noisy), or None when this report is dropped
        (never when not ``droppable``: no draw is made for the drop then)."""
        if droppable and self.config.drop > 0 and self.rng.random() < self.config.drop:
            return None
        x, y, heading = self.pose
        sigma = self.config.pose_noise
        if sigma > 0:
            x += sigma * self.rng.standard_normal()
            y += sigma * self.rng.standard_normal()
            heading += sigma / 0.1 * self.rng.standard_normal()
        wrapped = float(np.arctan2(np.sin(heading), np.cos(heading)))
        return x, y, wrapped


def build_robot(
    *,
    slip: str,
    drift: float,
    drift_period: float,
    map_spec: str,
    seed: int,
    config: SimRobotConfig,
    robot: RobotParams | None = None,
    grid: Discretization | None = None,
    physics: str = "kinematic",
    floor: str | None = None,
) -> SimRobot:
    """A simulated robot at the start pose of the map ``map_spec`` (see
    :func:`skidnav.realtime.arena.arena_map`), its floor the slip preset ``slip`` with relative
    drift amplitude ``drift`` and period ``drift_period`` [s]; random streams from ``seed``.
    ``physics`` (one of :data:`~skidnav.realtime.robot_server.dynamics.PHYSICS`) chooses what moves
    it; for ``mujoco``, ``floor`` names one material for the whole floor (None: the preset's).

    Raises:
        UserError: an unknown preset, physics or material.
        PhysicsUnavailable: ``mujoco`` without MuJoCo installed.
    """
    if physics not in PHYSICS:
        raise UserError(f"expected physics one of {', '.join(PHYSICS)}, got {physics!r}")
    if floor and physics == "kinematic":
        raise UserError(f"a floor material ({floor!r}) needs physics 'mujoco'")
    robot = robot or RobotParams()
    grid = grid or Discretization()
    streams = seed_streams(seed)
    grid_map = arena_map(map_spec, seed, grid)
    try:
        field = make_slip_field(
            slip,
            streams["slip"],
            regions=(grid.regions_x, grid.regions_y),
            drift_amplitude=drift,
            drift_period=drift_period,
            robot=robot,
        )
        materials = (
            None if physics == "kinematic" else floor_materials(slip, field, robot, grid, floor)
        )
    except ValueError as error:
        raise UserError(str(error)) from None
    pose = start_pose(grid_map, grid)
    sim = SimRobot(robot, field, grid_map.occupancy, grid, config, streams["robot"], pose)
    if materials is not None:
        dynamics = PhysicsDynamics(sim.task, robot, materials, sim.pose)
        sim.dynamics, sim.pose = dynamics, dynamics.physics.pose
    return sim


def warm_up(robot: SimRobot) -> None:
    """Compile the kinematics kernels now (numba), so the first periods are not late."""
    drive_substep(robot.task, robot.pose, (0.0, 0.0), robot.time, 0.0, 0.0)
    robot.dynamics.warm_up()
    robot.grid.cell(0.0, 0.0)
    robot.grid.region(0.0, 0.0)


class Firmware:
    """The robot's side of the line protocol on one connection (docs/protocol.md).

    :meth:`receive` answers one batch of messages — everything read at once — and applies only
    its newest motion message (``cmd``, ``stop``, or a malformed line, which stops), so a robot
    that stalled never replays the commands that queued up meanwhile; every ``stop`` is
    answered. A message whose ``seq`` does not exceed the previous one's is refused
    (``replay``), a ``cmd`` beyond the wheel-speed limit too (``range``), and so is one older
    than its ``ttl`` when read (``expired``: its ``stamp`` mapped onto the robot's clock by
    :class:`~skidnav.realtime.link.protocol.HostClock`); each stops the wheels. A line that
    fails authentication (``auth``) is refused too, and nothing more is taken from the
    connection: :attr:`hang_up` says why it is to be closed. A command holds the wheels for
    ``min(ttl, options.max_lease)`` after it was read, on the robot's own clock: no ``stamp``
    or ``ttl`` can stretch that lease. :meth:`watch`, called every period, stops the wheels when
    the lease ends or when no valid message came for ``link_timeout``, and declares the client
    idle after ``idle_timeout``. Times are the robot's own clock [s].

    Args:
        robot: the robot. options: the timeouts and the robot's name. events: the log.
        reply: queues one message for the host (called with a builder taking the ``seq``).
        now: the time of connection.
        nonce: the robot's handshake nonce for its ``hello`` (hex; empty without
            authentication).
    """

    def __init__(
        self,
        robot: SimRobot,
        options: ServerOptions,
        events: EventLog,
        reply: Callable[[Callable[[int], pr.Message]], None],
        now: float,
        nonce: str = "",
    ) -> None:
        self.robot, self.options, self.events, self.reply = robot, options, events, reply
        self.nonce = nonce
        self.greeted = False
        self.closed = False  # the connection is gone: nothing more is applied
        self.hang_up: str | None = None  # why the connection is to be closed
        self.clock = pr.HostClock()
        self.last_valid = now
        self.last_seq: int | None = None  # the newest seq taken from the host
        self.lease: float | None = None
        self.applied = 0  # commands run so far (a lockstep server steps one period per command)

    def stop(self) -> None:
        """Zero the wheels and end the lease."""
        self.robot.stop()
        self.lease = None

    def reject(self, code: str, text: str) -> None:
        """Bad input: stop the wheels and report it with an ``error``."""
        self.stop()
        self.events.write("error", code=code, message=text)
        self.reply(lambda seq: pr.Error(seq=seq, code=code, message=text[:200]))

    def receive(self, items: list[pr.Message | pr.ProtocolError], now: float) -> None:
        """Answer the messages (or line errors) read at ``now``, in order (see class doc)."""
        motions = [i for i, item in enumerate(items) if isinstance(item, _MOTION)]
        newest = motions[-1] if motions else -1
        for index, item in enumerate(items):
            if self.closed:
                return
            if isinstance(item, pr.ProtocolError):
                self._refuse_line(item)
            elif not self._in_order(item):
                continue
            elif isinstance(item, pr.Hello):
                self._hello(item, now)
            elif not self.greeted:
                self.reject("state", f"{item.TYPE} before hello")
            else:
                self.last_valid = now
                self._handle(item, now, superseded=index < newest)

    def _refuse_line(self, error: pr.ProtocolError) -> None:
        """A line that is no valid message; after a failed authentication, hang up."""
        self.reject(error.code, str(error))
        if error.code == "auth":
            self.hang_up = f"authentication failed: {error}"
            self.closed = True

    def _in_order(self, message: pr.Message) -> bool:
        """The seq rule: True if ``message`` comes after the last one taken, else refuse it."""
        last = self.last_seq
        if last is not None and message.seq <= last:
            self.reject("replay", f"{message.TYPE} {message.seq} after {last}: seq must increase")
            return False
        self.last_seq = message.seq
        return True

    def _hello(self, message: pr.Hello, now: float) -> None:
        self.greeted, self.last_valid = True, now
        self.events.write("hello", name=message.name)
        period, name, nonce = self.robot.robot.dt, self.options.name, self.nonce
        self.reply(lambda seq: pr.Hello(seq=seq, name=name, period=period, nonce=nonce))

    def _handle(self, message: pr.Message, now: float, superseded: bool) -> None:
        if isinstance(message, pr.Command | pr.Heartbeat):
            self.clock.observe(message.stamp, now)
        if isinstance(message, pr.Command):
            self._command(message, now, superseded)
        elif isinstance(message, pr.Stop):
            self.stop()
            self.events.write("stop", seq=message.seq, robot_time=self.robot.time)
            self.reply(lambda seq: pr.Stopped(seq=seq, ack=message.seq))
        elif isinstance(message, pr.Heartbeat):
            stamp = self.robot.time
            self.reply(lambda seq: pr.Heartbeat(seq=seq, stamp=stamp))
        elif isinstance(message, pr.Error):
            self.events.write("peer_error", code=message.code, message=message.message)
        else:
            self.reject("state", f"unexpected {message.TYPE} from host")

    def _command(self, message: pr.Command, now: float, superseded: bool) -> None:
        """Apply a ``cmd`` unless superseded, beyond the limit or stale; its lease is
        ``min(ttl, max_lease)`` from now."""
        if superseded:
            self.events.write("superseded", seq=message.seq, stamp=message.stamp)
            return
        limit = self.robot.robot.wheel_speed
        if max(abs(message.omega_left), abs(message.omega_right)) > limit:
            self.reject("range", f"cmd {message.seq}: a wheel speed beyond ±{limit} rad/s")
            return
        ttl = min(message.ttl, self.options.max_lease)
        age = self.clock.age(message.stamp, now)
        if age >= ttl:
            self.reject("expired", f"cmd {message.seq} read {age - ttl:.3f} s after its deadline")
            return
        self.robot.command(message.omega_left, message.omega_right)
        self.lease = now + ttl
        self.applied += 1
        self.events.write(
            "cmd",
            seq=message.seq,
            omega_left=message.omega_left,
            omega_right=message.omega_right,
            stamp=message.stamp,
            age=age,
            lease=ttl,
            robot_time=self.robot.time,
        )
        self.reply(lambda seq: pr.Ack(seq=seq, ack=message.seq))

    def watch(self, now: float) -> str | None:
        """The robot's own safety at ``now``: the lease and the quiet link stop the wheels;
        returns why the client is idle (to be dropped), or None."""
        if self.lease is not None and now >= self.lease:
            if self.robot.moving:
                self.events.write("lease", late=now - self.lease, robot_time=self.robot.time)
            self.stop()
        quiet = now - self.last_valid
        if quiet > self.options.idle_timeout:
            return f"no valid message for {quiet:.3f} s"
        if quiet > self.options.link_timeout:
            if self.robot.moving:
                self.events.write("watchdog", robot_time=self.robot.time)
            self.stop()
        return None


_MOTION = (pr.Command, pr.Stop, pr.ProtocolError)
"""What sets the wheels: a ``cmd``, a ``stop``, or a malformed line (which stops them)."""
