"""The navigation MDP on the physical robot: one action of the MuJoCo robot, scored by the
kinematic MDP's own rules (docs/simulator.md, docs/physics.md).

:func:`physics_transition` is the physics twin of
:func:`skidnav.sim.navigation.command_transition` (and :func:`simulate_physics_action` of
``simulate_action``): one action holds the wheel speeds (ω_L, ω_R) [rad/s] of a discrete action
or of a continuous one for ``substeps`` sub-steps of ``dt`` seconds; in each, with the robot in
slip region ρ at simulated time t:

1. η of ρ at the sub-step's start (:func:`~skidnav.sim.navigation.slip_scale`: the slip
   field, drifting or not);
2. :meth:`PhysicsRobot.substep`: each commanded wheel speed loses u·η in magnitude, u from
   ``noise`` (laid out as the kinematic kernel's: two uniforms per sub-step, left then right),
   and the velocity servos drive the wheels at the result for ``dt`` seconds on the materials
   under them;
3. the measured position is clipped to the arena (an arena edge without a wall stops the robot
   there); if it lies in a wall cell the motion stops: the position stays at the last free
   sub-step, the heading of the colliding sub-step is kept, the robot is put there at rest
   (:meth:`PhysicsRobot.place`) and the action is a collision; otherwise the sub-step is logged
   as a row of :data:`~skidnav.sim.navigation.LOG_COLUMNS` whose v_x, v_y and yaw rate are
   the sub-step's measured mean body twist, so the kinematic models learn the physics' slip.

With the observed variance (``RewardScheme.observed_variance``) the wheel set points of forward
actions (:func:`~skidnav.sim.navigation.records_variance`) feed the region's running
statistics, as in the kinematic kernel. Reward, termination, state and region come from the
kernels' ``score_action``, ``hits_wall`` and ``region_of``: the rules exist once.

The caller owns the pose (x [m], y [m], heading [rad], the heading unwrapped as in the kinematic
env); the MuJoCo robot holds the velocities. A pose changed outside (a reset) puts the robot
there at rest before the next action.
"""

from __future__ import annotations

import numpy as np

from skidnav.physics.materials import MATERIALS, region_materials
from skidnav.physics.mjcf import uniform_floor
from skidnav.physics.mujoco_robot import PhysicsRobot
from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.sim.navigation import (
    NavigationTask,
    Outcome,
    _log_row,
    _record_wheel_speed,
    hits_wall,
    records_variance,
    score_action,
    slip_scale,
)
from skidnav.world.discretization import region_of

POSE_TOLERANCE = 1e-9
"""Largest difference [m, rad] between the caller's pose and the robot's still taken as equal."""


def floor_materials(
    preset: str, field: SlipField, floor: str | None, robot: RobotParams | None = None
) -> np.ndarray:
    """Material name per slip region, object array of ``field.shape``: ``floor`` everywhere, or
    with ``floor=None`` the slip preset's materials
    (:func:`~skidnav.physics.materials.region_materials`)."""
    if floor is None:
        return region_materials(preset, field, robot)
    if floor not in MATERIALS:
        raise ValueError(f"expected floor in {', '.join(MATERIALS)} or None, got {floor!r}")
    return uniform_floor(floor, field.shape)


def synchronize(body: PhysicsRobot, pose: np.ndarray) -> None:
    """Put ``body`` at rest at ``pose`` (x [m], y [m], heading [rad]) unless it is there."""
    x, y, heading = body.pose
    moved = max(abs(x - pose[0]), abs(y - pose[1]), abs(wrap_angle(heading - pose[2])))
    if moved > POSE_TOLERANCE:
        body.place(float(pose[0]), float(pose[1]), float(pose[2]))


def measured_pose(
    body: PhysicsRobot, task: NavigationTask, heading: float
) -> tuple[float, float, float, bool]:
    """The robot's pose after a sub-step that started at ``heading`` [rad]: (x, y) clipped to
    the arena [m], the heading unwrapped from ``heading`` [rad], and whether clipping moved it."""
    x, y, measured = body.pose
    clipped_x = min(max(x, 0.0), task.robot.arena_width)
    clipped_y = min(max(y, 0.0), task.robot.arena_height)
    new_heading = heading + wrap_angle(measured - heading)
    return clipped_x, clipped_y, new_heading, (clipped_x, clipped_y) != (x, y)


def simulate_physics_action(
    task: NavigationTask,
    body: PhysicsRobot,
    pose: np.ndarray,
    commands: tuple[float, float],
    time: float,
    noise: np.ndarray,
    log: np.ndarray,
) -> tuple[bool, int, float, float]:
    """Drive ``body`` through one action (module doc), updating ``pose`` in place.

    Args:
        task: the MDP (walls, slip field, robot timing, rewards). body: the MuJoCo robot.
            pose: float64 (3,) [m, m, rad]. commands: the wheel speeds (ω_L, ω_R) [rad/s] held
            through the action. time: simulated time at the start of the action [s]. noise:
            float64 (2·substeps,) uniforms in [0, 1). log: float64 (≥ substeps, 6) receiving
            one row per free sub-step.

    Returns:
        (collided, rows logged, measured ω_L and ω_R at the end of the last sub-step [rad/s]).
    """
    robot, grid = task.robot, task.grid
    record = records_variance(task.rewards, commands)
    synchronize(body, pose)
    x, y, heading = float(pose[0]), float(pose[1]), float(pose[2])
    region = region_of(x, y, grid)
    n_logged, collided = 0, False
    for k in range(robot.substeps):
        eta = slip_scale(task, region, time + k * robot.dt)
        set_points, twist = body.substep(commands, eta, (noise[2 * k], noise[2 * k + 1]), robot.dt)
        new_x, new_y, heading, clipped = measured_pose(body, task, heading)
        if hits_wall(task, new_x, new_y, heading):
            collided = True
            break
        if clipped:
            body.place(new_x, new_y, heading)
        x, y = new_x, new_y
        _log_row(log, n_logged, region, commands, twist)
        n_logged += 1
        if record:
            _record_wheel_speed(task.variance_stats, region, set_points[0])
            _record_wheel_speed(task.variance_stats, region, set_points[1])
        region = region_of(x, y, grid)
    omega_left, omega_right = body.wheel_speeds()
    if collided:
        body.place(x, y, heading)
    pose[0], pose[1], pose[2] = x, y, heading
    return collided, n_logged, omega_left, omega_right


def physics_transition(
    task: NavigationTask,
    body: PhysicsRobot,
    pose: np.ndarray,
    commands: tuple[float, float],
    time: float,
    noise: np.ndarray,
    log: np.ndarray,
) -> Outcome:
    """One step of the MDP on the physical robot: :func:`simulate_physics_action`, then scored
    by :func:`skidnav.sim.navigation.score_action`, as the kinematic transition is
    (arguments as there)."""
    collided, n_logged, omega_left, omega_right = simulate_physics_action(
        task, body, pose, commands, time, noise, log
    )
    return score_action(task, pose, time, collided, n_logged, omega_left, omega_right)
