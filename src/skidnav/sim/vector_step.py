"""The compiled step of N independent navigation robots (the native vector env,
:mod:`skidnav.envs.vector`).

Each robot k has its own pose, slip clock, wheel-speed statistics and noise; all share one arena
and slip field. One call moves every robot whose ``active[k]`` is set through one action of
wheel speeds ``commands[k]`` by the MDP's own step
(:func:`skidnav.sim.navigation.command_transition`), then writes its observation, so a
vector step crosses into compiled code once, whatever N.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.sim.features import fill_features
from skidnav.sim.navigation import NavigationTask, command_transition
from skidnav.world.discretization import state_of

DISCRETE_OBSERVATION, POSE_OBSERVATION, FEATURE_OBSERVATION = 0, 1, 2
"""Observation codes: the flat discrete state, the pose (x, y, wrapped heading), the features."""


@inline_jit
def with_statistics(task: NavigationTask, variance_stats: np.ndarray) -> NavigationTask:
    """``task`` with the wheel-speed statistics ``variance_stats`` float64 (n_regions, 3) of one
    robot."""
    return NavigationTask(
        task.robot, task.grid, task.occupancy, task.goal_i, task.goal_j, task.goal_x,
        task.goal_y, task.goal_radius, task.eta, task.x_icr, task.wheel_radius, task.half_track,
        task.drift_phase, task.drift_amplitude,
        task.drift_period, task.rewards, variance_stats,
    )  # fmt: skip


@jit
def write_observation(
    task: NavigationTask,
    kind: int,
    pose: np.ndarray,
    state: int,
    geometry: tuple[float, float, float, float, float],
    out: np.ndarray,
) -> None:
    """Write the observation of ``kind`` for a robot at ``pose`` (x [m], y [m], heading [rad])
    in flat state ``state`` into its row ``out`` float64 (d,): the state (as a float, for the
    discrete kind), (x, y, heading wrapped to [−π, π]), or the features of
    :mod:`skidnav.sim.features` with ``geometry`` = (W, H, goal x, goal y, lidar range) [m]."""
    if kind == DISCRETE_OBSERVATION:
        out[0] = state
    elif kind == POSE_OBSERVATION:
        out[0], out[1] = pose[0], pose[1]
        out[2] = math.atan2(math.sin(pose[2]), math.cos(pose[2]))
    else:
        width, height, goal_x, goal_y, max_range = geometry
        fill_features(task.occupancy, (width, height), (goal_x, goal_y), pose, max_range, out)


@jit
def vector_step(
    task: NavigationTask,
    variance_stats: np.ndarray,
    poses: np.ndarray,
    times: np.ndarray,
    commands: np.ndarray,
    noise: np.ndarray,
    noise_used: np.ndarray,
    active: np.ndarray,
    kind: int,
    geometry: tuple[float, float, float, float, float],
    rewards: np.ndarray,
    terminated: np.ndarray,
    collided: np.ndarray,
    regions: np.ndarray,
    wheel_speeds: np.ndarray,
    observations: np.ndarray,
) -> None:
    """One action of every robot k with ``active[k]``.

    Args:
        task: the shared arena and slip field. variance_stats: float64 (N, n_regions, 3), each
            robot's statistics (:class:`NavigationTask`). poses: float64 (N, 3) [m, m, rad],
            updated. times: float64 (N,) slip clocks at the action's start [s] (the caller
            advances them). commands: float64 (N, 2) wheel speeds (ω_L, ω_R) [rad/s].
            noise: float64 (N, B, 2·substeps) each robot's next B actions' uniforms in [0, 1),
            in the order of its stream; noise_used: int64 (N,) how many of them it has used
            (< B for every active robot; incremented). active: bool (N,).
            kind, geometry: the observation (:func:`write_observation`).
        rewards, terminated, collided, regions, wheel_speeds (N, 2), observations (N, d): written
            for the active robots only.
    """
    substeps = task.robot.substeps
    log = np.empty((substeps, 6))
    row_noise = np.empty(2 * substeps)
    pose = np.empty(3)  # each robot's pose and noise are copied through these: no views per robot
    for k in range(poses.shape[0]):
        if not active[k]:
            continue
        row = noise_used[k]
        for n in range(2 * substeps):
            row_noise[n] = noise[k, row, n]
        noise_used[k] = row + 1
        pose[0], pose[1], pose[2] = poses[k, 0], poses[k, 1], poses[k, 2]
        outcome = command_transition(
            with_statistics(task, variance_stats[k]), pose, (commands[k, 0], commands[k, 1]),
            times[k], row_noise, log,
        )  # fmt: skip
        poses[k, 0], poses[k, 1], poses[k, 2] = pose[0], pose[1], pose[2]
        rewards[k] = outcome.reward
        terminated[k] = outcome.terminated
        collided[k] = outcome.collided
        regions[k] = outcome.region
        wheel_speeds[k, 0], wheel_speeds[k, 1] = outcome.omega_left, outcome.omega_right
        write_observation(task, kind, pose, outcome.state, geometry, observations[k])


@jit
def observe_poses(
    task: NavigationTask,
    poses: np.ndarray,
    mask: np.ndarray,
    kind: int,
    geometry: tuple[float, float, float, float, float],
    observations: np.ndarray,
) -> None:
    """Write the observation (:func:`write_observation`) of every robot k with ``mask[k]`` at
    its pose ``poses[k]`` float64 (3,) into ``observations[k]`` (after a reset)."""
    for k in range(poses.shape[0]):
        if mask[k]:
            pose = poses[k]
            state = state_of(pose[0], pose[1], pose[2], task.grid)
            write_observation(task, kind, pose, state, geometry, observations[k])
