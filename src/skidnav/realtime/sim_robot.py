"""The physics of the simulated robot behind the sim server (hardware-in-the-loop stand-in).

One control period of ``dt`` seconds of robot time, with the robot in coarse region ρ at robot
time t (the same model as kernels/navigation.py, but driven by arbitrary wheel-speed commands):

1. commands whose latency has elapsed take effect (a FIFO of (due time, ω_L, ω_R));
2. each wheel loses U(0, η(ρ, t)) in magnitude (the slip field, possibly drifting, SPEC §2);
3. the ICR model with x_ICR[ρ] gives the body twist; explicit Euler advances the pose
   (Kozłowski & Pazderski 2004), clipped to the arena;
4. a step that would end in a wall cell does not happen: walls physically block the robot
   (its heading still turns, as in the kernels).

The measured pose adds Gaussian noise (σ [m] on x and y, σ/0.1 [rad] on the heading).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from skidnav.errors import UserError
from skidnav.realtime.arena import build_map, seed_streams, start_pose
from skidnav.robot.kinematics import apply_slip, body_velocities, euler_step
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField, make_slip_field
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
        if not self.latency >= 0:
            raise ValueError(f"expected latency >= 0 s, got {self.latency}")
        if not self.pose_noise >= 0:
            raise ValueError(f"expected pose_noise >= 0 m, got {self.pose_noise}")
        if not 0 <= self.drop < 1:
            raise ValueError(f"expected drop in [0, 1), got {self.drop}")


class SimRobot:
    """A skid-steer robot on a slippery floor with walls.

    Args:
        robot: geometry and control period (``robot.dt`` is the period [s]).
        slip: the floor.
        occupancy: bool (n_x, n_y) walls (True) on the grid of ``grid``, or None for none.
        grid: discretization whose cells index ``occupancy`` and whose regions index ``slip``.
        config: imperfections.
        rng: every random draw (slip, noise, drops).
        pose: initial (x [m], y [m], heading [rad]).
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
    ) -> None:
        self.robot = robot
        self.slip = slip
        self.occupancy = occupancy
        self.grid = grid
        self.config = config
        self.rng = rng
        self.pose = (float(pose[0]), float(pose[1]), float(pose[2]))
        self.time = 0.0
        self.wheels = (0.0, 0.0)
        self._queue: deque[tuple[float, float, float]] = deque()

    def command(self, omega_left: float, omega_right: float) -> None:
        """Queue wheel speeds [rad/s] to take effect after the latency."""
        self._queue.append((self.time + self.config.latency, omega_left, omega_right))

    def stop(self) -> None:
        """Zero the wheels now and drop every queued command."""
        self._queue.clear()
        self.wheels = (0.0, 0.0)

    def blocked(self, x: float, y: float) -> bool:
        """True if position (x, y) [m] lies in a wall cell."""
        if self.occupancy is None:
            return False
        return bool(self.occupancy[self.grid.cell(x, y)])

    def step(self) -> None:
        """Advance one control period (see module doc)."""
        while self._queue and self._queue[0][0] <= self.time + 1e-12:
            _, left, right = self._queue.popleft()
            self.wheels = (left, right)
        x, y, heading = self.pose
        region = self.grid.region(x, y)
        ri, rj = divmod(region, self.grid.regions_y)
        eta = float(self.slip.eta_at(self.time)[ri, rj])
        left = apply_slip(self.wheels[0], self.rng.random() * eta)
        right = apply_slip(self.wheels[1], self.rng.random() * eta)
        v_x, v_y, yaw_rate = body_velocities(
            left,
            right,
            float(self.slip.x_icr[ri, rj]),
            self.robot.wheel_radius,
            self.robot.half_track,
        )
        new_x, new_y, new_heading = euler_step(x, y, heading, v_x, v_y, yaw_rate, self.robot.dt)
        new_x = min(max(new_x, 0.0), self.robot.arena_width)
        new_y = min(max(new_y, 0.0), self.robot.arena_height)
        if self.blocked(new_x, new_y):
            new_x, new_y = x, y
        self.pose = (new_x, new_y, new_heading)
        self.time += self.robot.dt

    def measured_pose(self) -> tuple[float, float, float] | None:
        """The pose as the tracker reports it (noisy), or None when this report is dropped."""
        if self.config.drop > 0 and self.rng.random() < self.config.drop:
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
) -> SimRobot:
    """A simulated robot at the start pose of the map ``map_spec`` (see
    :func:`skidnav.realtime.arena.build_map`), its floor the slip preset ``slip`` with relative
    drift amplitude ``drift`` and period ``drift_period`` [s]; random streams from ``seed``."""
    robot = robot or RobotParams()
    grid = grid or Discretization()
    streams = seed_streams(seed)
    grid_map = build_map(map_spec, seed, grid)
    try:
        field = make_slip_field(
            slip,
            streams["slip"],
            regions=(grid.regions_x, grid.regions_y),
            drift_amplitude=drift,
            drift_period=drift_period,
            robot=robot,
        )
    except ValueError as error:
        raise UserError(str(error)) from None
    return SimRobot(
        robot,
        field,
        grid_map.occupancy,
        grid,
        config,
        streams["robot"],
        start_pose(grid_map, grid),
    )


def warm_up(robot: SimRobot) -> None:
    """Compile the kinematics kernels now (numba), so the first periods are not late."""
    body_velocities(0.0, 0.0, 0.0, 1.0, 1.0)
    euler_step(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1)
    apply_slip(0.0, 0.0)
    robot.grid.cell(0.0, 0.0)
    robot.grid.region(0.0, 0.0)
