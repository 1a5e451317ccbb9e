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
"What a robot must do"): the rules of the reference robot (:mod:`skidnav.realtime.reference_robot`,
which a microcontroller port runs) on the simulated robot, against its own clock (the wall clock
of the server, which keeps running while the process is stalled).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from skidnav.errors import UserError
from skidnav.realtime.arena import arena_map, seed_streams, start_pose
from skidnav.realtime.config import ServerOptions
from skidnav.realtime.control.records import EventLog
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.reference_robot.rules import Rules
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

if TYPE_CHECKING:
    from skidnav.realtime.reference_robot.rules import Effect


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
    """The robot's side of the line protocol on one connection (docs/protocol.md): the
    reference robot's :class:`~skidnav.realtime.reference_robot.rules.Rules` (one
    implementation of every rule for the sim server and for boards) carried out on a
    :class:`SimRobot`, with the server's log.

    :meth:`receive` answers one batch of messages — everything read at once — and applies only
    its newest motion message (``cmd``, ``stop``, or a malformed line, which stops), so a robot
    that stalled never replays the commands that queued up meanwhile; every ``stop`` is
    answered. A message whose ``seq`` does not exceed the previous one's is refused
    (``replay``), a ``cmd`` beyond the wheel-speed limit too (``range``), and so is one older
    than its ``ttl`` when read (``expired``); each stops the wheels. A line that fails
    authentication (``auth``) is refused too, and nothing more is taken from the connection:
    :attr:`hang_up` says why it is to be closed. A command holds the wheels for
    ``min(ttl, options.max_lease)`` after it was read, on the robot's own clock. :meth:`watch`,
    called every period, stops the wheels when the lease ends or when no valid message came for
    ``link_timeout``, and declares the client idle after ``idle_timeout``. Times are the robot's
    own clock [s]; the stamps the robot sends (``heartbeat``) are its simulated time.

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
        self.rules = Rules(
            options.name,
            robot.robot.dt,
            robot.robot.wheel_speed,
            now,
            max_lease=options.max_lease,
            link_timeout=options.link_timeout,
            idle_timeout=options.idle_timeout,
            nonce=nonce,
        )
        self.closed = False  # the connection is gone: nothing more is applied
        self.hang_up: str | None = None  # why the connection is to be closed
        self.applied = 0  # commands run so far (a lockstep server steps one period per command)

    @property
    def greeted(self) -> bool:
        """True once the client's ``hello`` was answered."""
        return self.rules.greeted

    def receive(self, items: list[pr.Message | pr.ProtocolError], now: float) -> None:
        """Answer the messages (or line errors) read at ``now``, in order (see class doc)."""
        batch = [item if isinstance(item, pr.ProtocolError) else _fields(item) for item in items]
        hang_up = self._carry_out(self.rules.receive(batch, now))
        if hang_up is not None:
            self.hang_up, self.closed = hang_up, True

    def watch(self, now: float) -> str | None:
        """The robot's own safety at ``now``: the lease and the quiet link stop the wheels;
        returns why the client is idle (to be dropped), or None."""
        return self._carry_out(self.rules.watch(now))

    def _carry_out(self, effects: list[Effect]) -> str | None:
        """Apply the rules' effects in order until the connection closes; the reason to hang
        up, if one came."""
        for effect in effects:
            if self.closed:
                return None
            kind = effect[0]
            if kind == "send":
                self._send(effect[1])
            elif kind == "wheels":
                self.robot.command(effect[1], effect[2])
                self.applied += 1
            elif kind == "stop":
                self.robot.stop()
            elif kind == "note":
                self._note(effect[1], effect[2])
            elif kind == "hang_up":
                return str(effect[1])
        return None

    def _send(self, fields: dict[str, Any]) -> None:
        fields = dict(fields)
        cls = pr.MESSAGE_TYPES[fields.pop("type")]
        if cls is pr.Heartbeat:
            fields["stamp"] = self.robot.time  # the robot's clock in its messages
        self.reply(lambda seq: cls(seq=seq, **fields))

    def _note(self, event: str, fields: dict[str, Any]) -> None:
        """Log a note of the rules; the wheels' own stops only when the robot was moving."""
        if event in ("lease", "watchdog") and not self.robot.moving:
            return
        if event in ("cmd", "stop", "lease", "watchdog"):
            fields = {**fields, "robot_time": self.robot.time}
        self.events.write(event, **fields)


def _fields(message: pr.Message) -> dict[str, Any]:
    """A decoded message as the rules take it: its type and wire fields."""
    return {"type": message.TYPE, **message.wire_fields()}
