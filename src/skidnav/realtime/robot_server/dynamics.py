"""What moves the simulated robot for one control period: the kinematic model or MuJoCo physics.

:class:`~skidnav.realtime.robot_server.simulated_robot.SimRobot` keeps the commands, latency, clock
and tracker noise; a :class:`Dynamics` only turns (pose, wheel commands, time, two uniforms) into
the pose one period later. Both implementations share the slip field's wheel-speed loss (each wheel
loses u·η(ρ, t) in magnitude, u the period's uniform, η of the region under the robot, drifting as
:func:`skidnav.sim.navigation.slip_scale` says) and the wall rule (a period that would end in a wall
cell leaves the robot where it was, turned to its new heading):

- :class:`KinematicDynamics`: the simulator's own sub-step,
  :func:`skidnav.sim.task.drive_substep` (the ICR model with x_ICR of the region).
- :class:`PhysicsDynamics`: :meth:`skidnav.physics.mujoco_robot.PhysicsRobot.substep` — the slipped
  speeds become the set points of the MuJoCo robot's wheel servos and the physics runs for the
  period, on the floor materials of the slip preset
  (:func:`skidnav.physics.materials.region_materials`) or one material everywhere. A blocked period
  is undone with :meth:`~skidnav.physics.mujoco_robot.PhysicsRobot.place`, which also brings the
  body to rest (a bump stops it); so is a period that ends outside the arena (the kinematic model
  clips the pose to the arena instead).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.sim.navigation import NavigationTask, slip_scale
from skidnav.sim.task import drive_substep
from skidnav.world.discretization import Discretization, cell_of, region_of

PHYSICS = ("kinematic", "mujoco")
"""The names of the robot dynamics (``skidnav robot sim-server --physics``)."""

Pose = tuple[float, float, float]
"""(x [m], y [m], heading [rad])."""


class Dynamics(Protocol):
    """One control period of the robot's motion (see module doc)."""

    name: str

    def advance(
        self, pose: Pose, wheels: tuple[float, float], time: float, noise: tuple[float, float]
    ) -> Pose:
        """The pose one period of ``dt`` [s] after ``pose`` at robot time ``time`` [s], driven
        by the commanded (ω_L, ω_R) [rad/s], ``noise`` the period's two uniforms in [0, 1)."""
        ...

    def warm_up(self) -> None:
        """Compile or load what the first period needs, without moving the robot."""
        ...


class KinematicDynamics:
    """The ICR model of the simulator (see module doc); ``task`` from
    :func:`~skidnav.sim.task.floor_task`."""

    name = "kinematic"

    def __init__(self, task: NavigationTask) -> None:
        self.task = task

    def advance(
        self, pose: Pose, wheels: tuple[float, float], time: float, noise: tuple[float, float]
    ) -> Pose:
        x, y, heading = (float(value) for value in pose)
        new_x, new_y, new_heading = drive_substep(
            self.task, (x, y, heading), wheels, time, noise[0], noise[1]
        )
        return float(new_x), float(new_y), float(new_heading)

    def warm_up(self) -> None:
        drive_substep(self.task, (0.0, 0.0, 0.0), (0.0, 0.0), 0.0, 0.0, 0.0)


class PhysicsDynamics:
    """The MuJoCo robot (see module doc).

    Args:
        task: the floor task (walls, η and its drift) the kinematic model would use.
        robot: geometry and control period ``robot.dt`` [s].
        materials: material name per slip region, shape (regions_x, regions_y).
        pose: the initial pose.

    Raises:
        PhysicsUnavailable: MuJoCo is not installed.
    """

    name = "mujoco"

    def __init__(
        self, task: NavigationTask, robot: RobotParams, materials: np.ndarray, pose: Pose
    ) -> None:
        from skidnav.physics.mujoco_robot import PhysicsRobot  # imports MuJoCo only when built

        self.task = task
        self.robot = robot
        self.physics = PhysicsRobot(robot, materials)  # not drawn: the lighter model
        self.physics.reset(*pose)
        self._pose = self.physics.pose

    def advance(
        self, pose: Pose, wheels: tuple[float, float], time: float, noise: tuple[float, float]
    ) -> Pose:
        if pose != self._pose:  # moved from outside (a test, an operator): put it there
            self.physics.place(*pose)
        x, y, _ = pose
        eta = float(slip_scale(self.task, region_of(x, y, self.task.grid), time))
        self.physics.substep(wheels, eta, noise, self.robot.dt)
        new_x, new_y, new_heading = self.physics.pose
        if self._blocked(new_x, new_y):
            self.physics.place(x, y, new_heading)
        self._pose = self.physics.pose
        return self._pose

    def _blocked(self, x: float, y: float) -> bool:
        """True outside the arena or in a wall cell."""
        grid = self.task.grid
        if not (0.0 <= x <= grid.arena_width and 0.0 <= y <= grid.arena_height):
            return True
        i, j = cell_of(x, y, grid)
        return bool(self.task.occupancy[i, j] != 0)

    def warm_up(self) -> None:
        slip_scale(self.task, region_of(0.0, 0.0, self.task.grid), 0.0)
        cell_of(0.0, 0.0, self.task.grid)


def floor_materials(
    preset: str, slip: SlipField, robot: RobotParams, grid: Discretization, floor: str | None
) -> np.ndarray:
    """Material name per slip region: ``floor`` everywhere if given, else the preset's
    (:func:`skidnav.physics.materials.region_materials`); ValueError for an unknown name."""
    from skidnav.physics.materials import material, region_materials

    if floor:
        material(floor)  # ValueError naming the materials
        return np.full((grid.regions_x, grid.regions_y), floor, dtype=object)
    return region_materials(preset, slip, robot)
