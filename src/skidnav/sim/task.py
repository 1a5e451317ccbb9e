"""Python's doors into the navigation kernels (:mod:`skidnav.sim.navigation`): building a task
from a map, a slip field and the robot (:func:`build_task`; :func:`floor_task` for the simulated
robot), the env's one compiled call per step over the task's arrays (:func:`task_arrays`,
:func:`step_arrays`: numba types a NamedTuple of arrays faster than the task itself), and the
simulated robot's sub-step under arbitrary wheel speeds (:func:`drive_substep`)."""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.robot.params import KinematicConstants, RobotParams
from skidnav.robot.slip import SlipField
from skidnav.sim.navigation import (
    NavigationTask,
    RewardScheme,
    command_transition,
    hits_wall,
    region_slip,
    substep,
)
from skidnav.world.discretization import Discretization, GridShape, region_of
from skidnav.world.grid import GridMap


def build_task(
    grid_map: GridMap,
    slip: SlipField,
    robot: RobotParams,
    discretization: Discretization,
    rewards: RewardScheme | None = None,
    goal_disc: tuple[float, float, float] | None = None,
) -> NavigationTask:
    """Assemble a :class:`NavigationTask` from the Python-side objects, checking they agree
    (map and slip-field sizes, x_ICR of every region within the robot's [−a, b]). With
    ``goal_disc`` (x [m], y [m], radius [m] > 0) an episode ends within that disc instead of in
    the map's goal cell."""
    if grid_map.shape != (discretization.n_x, discretization.n_y):
        raise ValueError(
            f"expected a map of {discretization.n_x} × {discretization.n_y} cells, "
            f"got {grid_map.shape[0]} × {grid_map.shape[1]}"
        )
    task = floor_task(grid_map.as_uint8(), slip, robot, discretization)
    goal_i, goal_j = (int(v) for v in grid_map.goal)
    task = task._replace(goal_i=goal_i, goal_j=goal_j, rewards=rewards or RewardScheme())
    if goal_disc is None:
        return task
    goal_x, goal_y, goal_radius = (float(v) for v in goal_disc)
    if not (math.isfinite(goal_x) and math.isfinite(goal_y) and math.isfinite(goal_radius)):
        raise ValueError(f"expected a finite goal disc, got {goal_disc}")
    if not goal_radius > 0:
        raise ValueError(f"expected a goal radius > 0 m, got {goal_radius}")
    return task._replace(goal_x=goal_x, goal_y=goal_y, goal_radius=goal_radius)


def floor_task(
    occupancy: np.ndarray | None,
    slip: SlipField,
    robot: RobotParams,
    discretization: Discretization,
) -> NavigationTask:
    """The task of a robot that only moves (no goal: goal cell (−1, −1)), for
    :func:`drive_substep`: walls ``occupancy`` (bool or uint8 (n_x, n_y), nonzero = wall; None
    for none) and the floor ``slip``, checked as in :func:`build_task`."""
    shape = (discretization.n_x, discretization.n_y)
    walls = np.zeros(shape, dtype=np.uint8) if occupancy is None else occupancy
    if walls.shape != shape:
        raise ValueError(f"expected walls of {shape[0]} × {shape[1]} cells, got {walls.shape}")
    if slip.shape != (discretization.regions_x, discretization.regions_y):
        raise ValueError(
            f"expected a slip field of {discretization.regions_x} × {discretization.regions_y} "
            f"regions, got {slip.shape[0]} × {slip.shape[1]}"
        )
    slip.check_x_icr(robot)
    eta, x_icr, wheel_radius, half_track, phase = slip.kernel_arrays(robot)
    return NavigationTask(
        robot=robot.kernel_constants(),
        grid=discretization.grid_shape(),
        occupancy=np.ascontiguousarray(walls != 0, dtype=np.uint8),
        goal_i=-1,
        goal_j=-1,
        goal_x=0.0,
        goal_y=0.0,
        goal_radius=0.0,
        eta=eta,
        x_icr=x_icr,
        wheel_radius=wheel_radius,
        half_track=half_track,
        drift_phase=phase,
        drift_amplitude=float(slip.drift_amplitude),
        drift_period=float(slip.drift_period),
        rewards=RewardScheme(),
        variance_stats=np.zeros((discretization.n_regions, 3)),
    )


@jit
def drive_substep(
    task: NavigationTask,
    pose: tuple[float, float, float],
    commands: tuple[float, float],
    time: float,
    noise_left: float,
    noise_right: float,
) -> tuple[float, float, float]:
    """One sub-step of a robot driven by any wheel speeds ``commands`` (ω_L, ω_R) [rad/s], as the
    simulated robot server moves it: :func:`substep` from ``pose`` (x [m], y [m], heading [rad])
    at time ``time`` [s]. A wall blocks the position but not the turn (the heading of a colliding
    sub-step is kept, as in an action). Returns the new pose."""
    x, y, _ = pose
    region = region_of(x, y, task.grid)
    slip = region_slip(task, region, time)
    new_x, new_y, new_heading, _, _, _ = substep(
        task.robot, slip, pose, commands, (noise_left, noise_right)
    )
    if hits_wall(task, new_x, new_y, new_heading):
        return x, y, new_heading
    return new_x, new_y, new_heading


N_TASK_SCALARS = 29
"""Length of the scalar vector of :func:`task_arrays`."""

TaskArrays = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray
]
"""A task as :func:`task_arrays` gives it."""


def task_arrays(task: NavigationTask) -> TaskArrays:
    """``task`` as the eight arrays :func:`step_arrays` takes: float64 (:data:`N_TASK_SCALARS`,)
    of its scalars (the fields of ``robot`` and ``grid``, the goal cell, the goal disc, the
    drift amplitude and period, the fields of ``rewards``, in this order), then ``occupancy``,
    ``eta``, ``x_icr``, ``wheel_radius``, ``half_track``, ``drift_phase`` and ``variance_stats``
    (shared, not copied: the kernel updates the last).

    Why arrays: numba types a NamedTuple argument in Python on every call (about 4 µs for a task,
    more than the action's own work), an array in C (about 0.05 µs).
    """
    scalars = np.array(
        [*task.robot, *task.grid, task.goal_i, task.goal_j, task.goal_x, task.goal_y,
         task.goal_radius, task.drift_amplitude, task.drift_period, *task.rewards],
        dtype=np.float64,
    )  # fmt: skip
    assert scalars.shape == (N_TASK_SCALARS,)
    return (
        scalars, task.occupancy, task.eta, task.x_icr, task.wheel_radius, task.half_track,
        task.drift_phase, task.variance_stats,
    )  # fmt: skip


@inline_jit
def task_from_arrays(
    scalars: np.ndarray,
    occupancy: np.ndarray,
    eta: np.ndarray,
    x_icr: np.ndarray,
    wheel_radius: np.ndarray,
    half_track: np.ndarray,
    drift_phase: np.ndarray,
    variance_stats: np.ndarray,
) -> NavigationTask:
    """The :class:`NavigationTask` of :func:`task_arrays` (integers and flags are exact in
    float64)."""
    s = scalars
    robot = KinematicConstants(
        s[0], s[1], s[2], s[3], int(s[4]), s[5], s[6], s[7] != 0.0, s[8], s[9]
    )
    grid = GridShape(int(s[10]), int(s[11]), int(s[12]), int(s[13]), int(s[14]), s[15], s[16])
    rewards = RewardScheme(s[24], s[25], s[26], s[27], s[28] != 0.0)
    return NavigationTask(
        robot, grid, occupancy, int(s[17]), int(s[18]), s[19], s[20], s[21], eta, x_icr,
        wheel_radius, half_track, drift_phase, s[22], s[23], rewards, variance_stats,
    )  # fmt: skip


@jit
def step_arrays(
    scalars: np.ndarray,
    occupancy: np.ndarray,
    eta: np.ndarray,
    x_icr: np.ndarray,
    wheel_radius: np.ndarray,
    half_track: np.ndarray,
    drift_phase: np.ndarray,
    variance_stats: np.ndarray,
    pose: np.ndarray,
    omega_left: float,
    omega_right: float,
    time: float,
    noise: np.ndarray,
    log: np.ndarray,
) -> tuple[float, bool, bool, int, float, float, int, int, float]:
    """:func:`command_transition` of the wheel speeds (``omega_left``, ``omega_right``) [rad/s]
    on the task given as :func:`task_arrays`, for callers in Python (the env): the
    :class:`Outcome` fields as a plain tuple, which crosses back into Python faster."""
    task = task_from_arrays(
        scalars, occupancy, eta, x_icr, wheel_radius, half_track, drift_phase, variance_stats
    )
    outcome = command_transition(task, pose, (omega_left, omega_right), time, noise, log)
    return (
        outcome.reward, outcome.terminated, outcome.collided, outcome.n_logged,
        outcome.omega_left, outcome.omega_right, outcome.state, outcome.region, outcome.cost,
    )  # fmt: skip
