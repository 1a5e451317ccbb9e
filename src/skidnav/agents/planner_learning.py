"""What real steps teach the planner of the model-based agents
(:class:`~skidnav.agents.kinematic_planning.PlannerArrays`): the reward statistics, the walls and
free cells of the map (by evidence), the goal cells, the episode's pairs and the kinematic samples;
and the refresh of the kinematic table around cells whose map changed (Alhawary (2020), ch. 7;
docs/agents/dyna-kinematic.md).
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import jit
from skidnav.agents.kinematic_planning import (
    EPISODE_LENGTH,
    EPISODE_TERMINATED,
    MAP_CHANGES,
    REFRESH_RADIUS,
    USE_KINEMATIC,
    PlannerArrays,
    reward_row,
    state_region,
)
from skidnav.models.kinematic_prediction import (
    PREDICT_COLLISION,
    collision_wall_cell,
    feed_rows,
    predict_action,
)
from skidnav.robot.params import KinematicConstants
from skidnav.world.discretization import GridShape, state_of


@jit
def _refresh_cell(
    planner: PlannerArrays, i: int, j: int, robot: KinematicConstants, grid: GridShape
) -> None:
    """Recompute the kinematic table and its reward rows for every state of cell (i, j) (as
    :func:`~skidnav.models.kinematic_prediction.prediction_table`)."""
    x0 = (i + 0.5) * grid.arena_width / (grid.n_x - 1)
    y0 = (j + 0.5) * grid.arena_height / (grid.n_y - 1)
    n_actions = planner.pred_next.shape[1]
    n_regions = planner.reward_stats.shape[0] - 2
    for h in range(grid.n_headings):
        state = (i * grid.n_y + j) * grid.n_headings + h
        heading = -np.pi + (h + 0.5) * 2.0 * np.pi / grid.n_headings
        for action in range(n_actions):
            next_state, code = state, PREDICT_COLLISION
            if not planner.walls[i, j]:
                x, y, end_heading, code = predict_action(
                    x0, y0, heading, action, planner.velocities, planner.walls, planner.goals,
                    robot, grid, False,
                )  # fmt: skip
                next_state = state_of(x, y, end_heading, grid)
            planner.pred_next[state, action] = next_state
            planner.pred_outcome[state, action] = code
            planner.pred_row[state, action] = reward_row(next_state, code, n_regions, grid)


@jit
def refresh_stale(planner: PlannerArrays, robot: KinematicConstants, grid: GridShape) -> int:
    """Recompute the table for every cell within ``REFRESH_RADIUS`` cells of a stale cell (a goal
    found, a cell that became or stopped being a wall since the last refresh), then clear
    ``stale``. Returns the cells redone."""
    radius = planner.counters[REFRESH_RADIUS]
    affected = np.zeros(planner.stale.shape, dtype=np.bool_)
    for ci in range(grid.n_x):
        for cj in range(grid.n_y):
            if planner.stale[ci, cj]:
                i0, i1 = max(ci - radius, 0), min(ci + radius + 1, grid.n_x)
                j0, j1 = max(cj - radius, 0), min(cj + radius + 1, grid.n_y)
                affected[i0:i1, j0:j1] = True
    redone = 0
    for i in range(grid.n_x):
        for j in range(grid.n_y):
            if affected[i, j]:
                _refresh_cell(planner, i, j, robot, grid)
                redone += 1
    planner.stale[:, :] = False
    return redone


@jit
def weigh_cell(planner: PlannerArrays, i: int, j: int, wall: int, free: int) -> None:
    """Add ``wall`` collisions and ``free`` sightings of the robot to cell (i, j)'s evidence and
    weigh it: the cell is a wall while its wall evidence exceeds its free evidence (a goal cell
    never is). A cell that changes side is marked stale (the table around it is redone at the
    end of the episode, :func:`refresh_stale`).

    The robot is never inside a wall cell, so one sighting outweighs one wrong guess: a free cell
    guessed as a wall is cleared when the robot is next seen in it, while a real wall's evidence
    only grows. A guess is only a guess: it replays the *expected* motion of the action
    (:func:`~skidnav.models.kinematic_prediction.collision_wall_cell`), and on a slippery floor
    the colliding sub-step's random wheel-speed loss can send the robot into a neighbouring cell.
    """
    planner.wall_evidence[i, j] += wall
    planner.free_evidence[i, j] += free
    evidence = planner.wall_evidence[i, j] > planner.free_evidence[i, j]
    is_wall = evidence and not planner.goals[i, j]
    if is_wall != planner.walls[i, j]:
        planner.walls[i, j] = is_wall
        planner.stale[i, j] = True
        planner.counters[MAP_CHANGES] += 1


@jit
def _learn_map(
    planner: PlannerArrays,
    action: int,
    next_state: int,
    terminated: bool,
    collided: bool,
    pose: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
) -> None:
    """Learn the map from one real step: a discovered goal cell; the cell the robot ended in as
    free evidence; the guessed wall cell of a collision as wall evidence (:func:`weigh_cell`)."""
    cell = next_state // grid.n_headings
    i, j = cell // grid.n_y, cell % grid.n_y
    if terminated and not planner.goals[i, j]:
        planner.goals[i, j] = True
        planner.stale[i, j] = True
        planner.counters[MAP_CHANGES] += 1
    weigh_cell(planner, i, j, 0, 1)
    if collided and planner.counters[USE_KINEMATIC] != 0:
        wi, wj = collision_wall_cell(
            pose[0], pose[1], pose[2], action, planner.velocities, robot, grid
        )
        if wi >= 0:
            weigh_cell(planner, wi, wj, 1, 0)


@jit
def planner_observe(
    planner: PlannerArrays,
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
    collided: bool,
    pose: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
) -> None:
    """Learn from one real step what the planner needs: reward statistics, the episode's pairs,
    and (with pose information, ``pose[0] >= 0``) the map: goal cells, and the evidence of wall
    and free cells (:func:`_learn_map`).

    Args:
        pose: float64 (3,) pose after the step [m, m, rad], or negative x when unknown.
        Others: the real transition; ``collided`` from the env's info.
    """
    n_regions = planner.reward_stats.shape[0] - 2
    if terminated:
        row = n_regions + 1
    elif collided:
        row = n_regions
    else:
        row = state_region(next_state, grid)
    planner.reward_stats[row, 0] += reward
    planner.reward_stats[row, 1] += 1.0
    length = planner.counters[EPISODE_LENGTH]
    planner.episode_keys[length] = state * planner.pred_next.shape[1] + action
    planner.counters[EPISODE_LENGTH] = length + 1
    planner.counters[EPISODE_TERMINATED] = 1 if terminated else 0
    if pose[0] >= 0.0:
        _learn_map(planner, action, next_state, terminated, collided, pose, robot, grid)


@jit
def feed_log(
    data: np.ndarray, counts: np.ndarray, log: np.ndarray, n_rows: int, n_regions: int
) -> int:
    """Feed the first ``n_rows`` rows of a kinematic log to the model buffers."""
    return feed_rows(data, counts, log[:n_rows], n_regions)
