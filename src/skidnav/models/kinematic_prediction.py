"""Compiled kernels of the learned kinematic model: feeding samples and predicting actions.

The learned model (:mod:`skidnav.models.kinematic`) reduces, after each refit, to a table of
predicted body velocities ``velocities[region, action] = (v_x, v_y, yaw_rate)`` [m/s, m/s, rad/s].
These kernels integrate it over one action exactly as the simulator integrates the true
kinematics (``substeps`` sub-steps of ``dt`` seconds, explicit Euler or the exact constant-twist
step, pose clipped to the arena, the slip region re-read at every sub-step; see
:mod:`skidnav.sim.navigation`). A sub-step entering a wall cell the agent already knows of stops
the motion (a predicted collision: position of the last free sub-step, heading of the colliding
one, as the simulator); an action ending in a known goal cell is a predicted arrival.

Sample buffers: ``data`` has shape (n_regions, window, 5) with columns
``[omega_left_cmd, omega_right_cmd, v_x, v_y, yaw_rate]``; ``counts[region]`` is the number of
samples ever fed to a region, so the newest sample of a region sits at row
``(counts[region] − 1) % window`` (a ring buffer: a sliding window of the last ``window`` samples).
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import jit
from skidnav.robot.kinematics import commanded_wheel_speeds
from skidnav.robot.params import KinematicConstants
from skidnav.sim.navigation import integrate
from skidnav.world.discretization import (
    GridShape,
    cell_of,
    region_of,
    squeezes_between_walls,
    state_of,
)

PREDICT_FREE = 0
"""Outcome code: the predicted action ends without touching a known wall or goal."""
PREDICT_COLLISION = 1
"""Outcome code: a predicted sub-step enters a known wall cell (the motion stops before it)."""
PREDICT_GOAL = 2
"""Outcome code: the predicted action ends in a known goal cell (the episode would terminate)."""


@jit
def feed_rows(data: np.ndarray, counts: np.ndarray, rows: np.ndarray, n_regions: int) -> int:
    """Append kinematic-log rows to the per-region ring buffers.

    Args:
        data: (n_regions, window, 5) float64 buffers, updated in place.
        counts: (n_regions,) int64 samples ever fed per region, updated in place.
        rows: (n, 6) float64 kinematic log ``[region, ω_L cmd, ω_R cmd, v_x, v_y, yaw_rate]``.
        n_regions: number of regions; rows with a region outside [0, n_regions) are skipped.

    Returns:
        The number of rows stored.
    """
    window = data.shape[1]
    stored = 0
    for k in range(rows.shape[0]):
        region = int(rows[k, 0])
        if region < 0 or region >= n_regions:
            continue
        slot = counts[region] % window
        for column in range(5):
            data[region, slot, column] = rows[k, column + 1]
        counts[region] += 1
        stored += 1
    return stored


@jit
def predict_action(
    x: float,
    y: float,
    heading: float,
    action: int,
    velocities: np.ndarray,
    walls: np.ndarray,
    goals: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
    corners: bool,
) -> tuple[float, float, float, int]:
    """Integrate the predicted body velocities over one action from a pose.

    Args:
        x, y: start position [m]. heading: start heading [rad].
        action: 0 forward, 1 backward, 2 left, 3 right.
        velocities: (n_regions, n_actions, 3) predicted (v_x [m/s], v_y [m/s], yaw_rate [rad/s]).
        walls, goals: (n_x, n_y) bool, the wall and goal cells known to the agent.
        robot: sub-step length, count, arena size and integration scheme.
        grid: the discretization.
        corners: a sub-step that enters a cell diagonally between two walls meeting at a
            corner collides too (:func:`~skidnav.world.discretization.squeezes_between_walls`);
            False: only a sub-step into a wall cell does, the simulator's rule.

    Returns:
        (x, y, heading, outcome) with outcome :data:`PREDICT_FREE`, :data:`PREDICT_COLLISION`
        (position of the last free sub-step, heading of the colliding one) or
        :data:`PREDICT_GOAL`.
    """
    i, j = cell_of(x, y, grid)
    for _ in range(robot.substeps):
        region = region_of(x, y, grid)
        twist = (
            velocities[region, action, 0],
            velocities[region, action, 1],
            velocities[region, action, 2],
        )
        nx, ny, nh = integrate(robot, x, y, heading, twist)
        next_i, next_j = cell_of(nx, ny, grid)
        if walls[next_i, next_j] or (
            corners and squeezes_between_walls(walls, i, j, next_i, next_j)
        ):
            return x, y, nh, PREDICT_COLLISION
        x, y, heading = nx, ny, nh
        i, j = next_i, next_j
    if goals[i, j]:
        return x, y, heading, PREDICT_GOAL
    return x, y, heading, PREDICT_FREE


@jit
def prediction_table(
    velocities: np.ndarray,
    walls: np.ndarray,
    goals: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
    next_state: np.ndarray,
    outcome: np.ndarray,
) -> None:
    """Predict every (state, action) from the state's cell centre and heading-bin centre.

    Args:
        velocities, walls, goals, robot, grid: as :func:`predict_action`.
        next_state: (n_states, n_actions) int32 output, the predicted next state.
        outcome: (n_states, n_actions) int8 output, the outcome code. States inside a known wall
            cell predict themselves with :data:`PREDICT_COLLISION`.
    """
    cell_width = grid.arena_width / (grid.n_x - 1)
    cell_height = grid.arena_height / (grid.n_y - 1)
    bin_width = 2.0 * np.pi / grid.n_headings
    n_actions = next_state.shape[1]
    for i in range(grid.n_x):
        for j in range(grid.n_y):
            x0 = (i + 0.5) * cell_width
            y0 = (j + 0.5) * cell_height
            for h in range(grid.n_headings):
                state = (i * grid.n_y + j) * grid.n_headings + h
                heading0 = -np.pi + (h + 0.5) * bin_width
                for action in range(n_actions):
                    if walls[i, j]:
                        next_state[state, action] = state
                        outcome[state, action] = PREDICT_COLLISION
                        continue
                    x, y, heading, code = predict_action(
                        x0, y0, heading0, action, velocities, walls, goals, robot, grid, False
                    )
                    next_state[state, action] = state_of(x, y, heading, grid)
                    outcome[state, action] = code


@jit
def action_velocities(coefficients: np.ndarray, wheel_speed: float, out: np.ndarray) -> None:
    """Predicted body velocities of each region and action from regression coefficients.

    Args:
        coefficients: (n_regions, 8) ``[vx_wl, vx_wr, vx_b, yaw_wl, yaw_wr, yaw_b, vy_yaw, vy_b]``:
            v_x = vx_wl·ω_L + vx_wr·ω_R + vx_b, yaw_rate likewise, v_y = vy_yaw·yaw_rate + vy_b.
        wheel_speed: commanded wheel-speed magnitude [rad/s].
        out: (n_regions, n_actions, 3) output (v_x [m/s], v_y [m/s], yaw_rate [rad/s]).
    """
    for region in range(coefficients.shape[0]):
        c = coefficients[region]
        for action in range(out.shape[1]):
            omega_left, omega_right = commanded_wheel_speeds(action, wheel_speed)
            v_x = c[0] * omega_left + c[1] * omega_right + c[2]
            yaw_rate = c[3] * omega_left + c[4] * omega_right + c[5]
            out[region, action, 0] = v_x
            out[region, action, 1] = c[6] * yaw_rate + c[7]
            out[region, action, 2] = yaw_rate


@jit
def collision_wall_cell(
    x: float,
    y: float,
    heading: float,
    action: int,
    velocities: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
) -> tuple[int, int]:
    """Guess the wall cell a real collision ran into (ours: the simulator does not report it).

    After a collision the simulator leaves the robot at the position of the last free sub-step
    with the heading of the colliding sub-step. Rewinding the heading by the predicted yaw rate and
    repeating that sub-step with the predicted velocities (up to ``substeps`` times, in case the
    prediction is slower than the real motion) gives the first other cell: the guessed wall.

    Args:
        x, y, heading: pose reported after the collision [m, m, rad].
        action, velocities, robot, grid: as :func:`predict_action`.

    Returns:
        (i, j) of the guessed wall cell, or (−1, −1) when the prediction never leaves the
        current cell.
    """
    region = region_of(x, y, grid)
    twist = (
        velocities[region, action, 0],
        velocities[region, action, 1],
        velocities[region, action, 2],
    )
    ci, cj = cell_of(x, y, grid)
    heading = heading - twist[2] * robot.dt
    for _ in range(robot.substeps):
        x, y, heading = integrate(robot, x, y, heading, twist)
        i, j = cell_of(x, y, grid)
        if i != ci or j != cj:
            return i, j
    return -1, -1
