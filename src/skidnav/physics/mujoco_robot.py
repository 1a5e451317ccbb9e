"""Driving the MuJoCo robot: set wheel speeds, advance the physics, read the pose.

:class:`PhysicsRobot` owns one ``MjModel``/``MjData`` pair built from
:func:`~skidnav.physics.mjcf.arena_mjcf`. Time advances only through :meth:`PhysicsRobot.drive`
(no wall clock): the same calls give the same trajectory, bit for bit (MuJoCo is deterministic
on one machine). Before each drive, every wheel's friction is set to the material of the slip
region under it (:mod:`skidnav.physics.materials`).

Poses are (x [m], y [m], heading [rad]) in the arena frame of the kinematic simulator; the
chassis' centre of mass is the robot's position.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav.physics.backend import load_mujoco
from skidnav.physics.materials import MATERIALS
from skidnav.physics.mjcf import WHEELS, PhysicsParams, arena_mjcf, physics_for
from skidnav.robot.kinematics import apply_slip, wrap_angle
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import level_index


def heading_quaternion(heading: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation by ``heading`` [rad] about z."""
    return np.array([math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2)])


def quaternion_heading(quaternion: np.ndarray) -> float:
    """Heading [rad] (yaw about z) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = (float(value) for value in quaternion)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class PhysicsRobot:
    """A skid-steer robot (the thesis robot, the Jackal) on a MuJoCo floor.

    Args:
        robot: geometry and arena size.
        materials: material name per slip region, shape (regions_x, regions_y).
        physics: masses, motors and timestep (default: those of ``robot``'s build,
            :func:`~skidnav.physics.mjcf.physics_for`).
        occupancy: uint8 (n_x, n_y) wall map for a model to draw (walls and floor tiles), None
            for one only to simulate (:func:`~skidnav.physics.mjcf.arena_mjcf`).
    """

    def __init__(
        self,
        robot: RobotParams,
        materials: np.ndarray,
        physics: PhysicsParams | None = None,
        occupancy: np.ndarray | None = None,
    ) -> None:
        self.mujoco = load_mujoco()
        self.robot = robot
        self.physics = physics or physics_for(robot)
        self.materials = np.asarray(materials, dtype=object)
        self.mjcf = arena_mjcf(robot, self.physics, self.materials, occupancy)
        self.model = self.mujoco.MjModel.from_xml_string(self.mjcf)
        self.data = self.mujoco.MjData(self.model)
        self._wheel_geoms = [self.model.geom(name).id for name in WHEELS]
        self._wheel_dofs = [int(self.model.joint(name).dofadr[0]) for name in WHEELS]
        self._region_friction = np.array(
            [[MATERIALS[str(name)].friction for name in row] for row in self.materials]
        )
        self.reset(0.0, 0.0, 0.0)

    @property
    def time(self) -> float:
        """Simulated time since the last :meth:`reset` [s]."""
        return float(self.data.time)

    def reset(self, x: float, y: float, heading: float) -> None:
        """Put the robot at rest at pose (x [m], y [m], heading [rad]), time 0."""
        self.mujoco.mj_resetData(self.model, self.data)
        self.place(x, y, heading)

    def place(self, x: float, y: float, heading: float) -> None:
        """Move the robot to a pose and stop it (wheels, body; time goes on)."""
        qpos = self.data.qpos
        qpos[0:3] = (x, y, self.robot.wheel_radius)
        qpos[3:7] = heading_quaternion(heading)
        self.data.qvel[:] = 0.0
        self.data.ctrl[:] = 0.0
        self.mujoco.mj_forward(self.model, self.data)

    @property
    def pose(self) -> tuple[float, float, float]:
        """(x [m], y [m], heading [rad] in [−π, π])."""
        qpos = self.data.qpos
        return float(qpos[0]), float(qpos[1]), quaternion_heading(qpos[3:7])

    def body_twist(self) -> tuple[float, float, float]:
        """Instantaneous (v_x, v_y [m/s] in the body frame, yaw rate [rad/s])."""
        heading = quaternion_heading(self.data.qpos[3:7])
        v_world_x, v_world_y = float(self.data.qvel[0]), float(self.data.qvel[1])
        cos, sin = math.cos(heading), math.sin(heading)
        # MuJoCo's free joint: linear velocity in the world frame, angular in the body frame.
        return (
            cos * v_world_x + sin * v_world_y,
            -sin * v_world_x + cos * v_world_y,
            float(self.data.qvel[5]),
        )

    def wheel_speeds(self) -> tuple[float, float]:
        """Measured (ω_L, ω_R) [rad/s]: the mean joint speed of each side's two wheels."""
        qvel, dofs = self.data.qvel, self._wheel_dofs
        return (
            0.5 * float(qvel[dofs[0]] + qvel[dofs[1]]),
            0.5 * float(qvel[dofs[2]] + qvel[dofs[3]]),
        )

    def region_under(self, x: float, y: float) -> tuple[int, int]:
        """Slip region (i, j) of a floor point [m], by the discretization's own rule
        (:func:`~skidnav.world.discretization.level_index`: the MDP's slip regions)."""
        n_x, n_y = self.materials.shape
        return (
            int(level_index(x, self.robot.arena_width, n_x)),
            int(level_index(y, self.robot.arena_height, n_y)),
        )

    def _set_wheel_friction(self) -> None:
        """Each wheel's friction := that of the region under its centre."""
        positions = self.data.geom_xpos
        for geom in self._wheel_geoms:
            i, j = self.region_under(float(positions[geom, 0]), float(positions[geom, 1]))
            self.model.geom_friction[geom] = self._region_friction[i, j]

    def drive(self, omega_left: float, omega_right: float, duration: float) -> None:
        """Command (ω_L, ω_R) [rad/s] to the wheel servos and run the physics for ``duration``
        seconds (a whole number of timesteps, at least one)."""
        steps = max(1, round(duration / self.physics.timestep))
        self._set_wheel_friction()
        self.data.ctrl[:] = (omega_left, omega_left, omega_right, omega_right)
        self.mujoco.mj_step(self.model, self.data, nstep=steps)

    def displacement(self, start: tuple[float, float, float]) -> tuple[float, float, float]:
        """Body-frame displacement from pose ``start``: forward [m], left [m] in ``start``'s
        frame, and the heading change [rad] (wrapped)."""
        x, y, heading = self.pose
        dx, dy = x - start[0], y - start[1]
        cos, sin = math.cos(start[2]), math.sin(start[2])
        return cos * dx + sin * dy, -sin * dx + cos * dy, wrap_angle(heading - start[2])

    def substep(
        self,
        commands: tuple[float, float],
        eta: float,
        noise: tuple[float, float],
        duration: float,
    ) -> tuple[tuple[float, float], tuple[float, float, float]]:
        """One control sub-step of ``duration`` [s], the physics twin of
        :func:`skidnav.sim.navigation.substep`: each commanded wheel speed (ω_L, ω_R)
        [rad/s] loses u·η in magnitude (the slip field's wheel-speed loss, ``noise`` = (u_L, u_R)
        uniforms in [0, 1), ``eta`` [rad/s]; 0 for the floor's friction alone), the servos get
        the result as set points, and the physics runs.

        Returns:
            the set points (ω_L, ω_R) [rad/s], and the sub-step's mean body twist (v_x, v_y
            [m/s] in the frame of the pose it started from, yaw rate [rad/s]) from its
            displacement, the velocities the kinematic log records.
        """
        start = self.pose
        set_points = (
            apply_slip(commands[0], noise[0] * eta),
            apply_slip(commands[1], noise[1] * eta),
        )
        self.drive(set_points[0], set_points[1], duration)
        forward, left, turned = self.displacement(start)
        return set_points, (forward / duration, left / duration, turned / duration)
