"""Compiled parts of the thesis's model-based agents: kinematic-model planning on pairs never
visited and planning prioritized around the shortest discovered trajectories (SPEC §4 items 3–4).

One planner (:class:`PlannerArrays`) serves ``dyna-kinematic``, ``trajectory-prioritized`` and
``dyna-full``; their configs only change the shares of the three kinds of planning update
(:func:`combined_planning`):

* **trajectory** — the next pair of the sweep lists built from the best trajectories (built in
  Python, :mod:`skidnav.agents.trajectory_prioritized`): half of this share walks the trajectory
  pairs (backward from the goal), half walks their neighbourhood;
* **frontier** (kinematic) — a visited pair drawn uniformly, a random action predicted from its
  state by the kinematic model, and a random action at the predicted state: so the updates reach
  the states one predicted step around the visited set;
* **replay** — Dyna-Q's uniform replay of a visited pair (:mod:`skidnav.kernels.planning`).

A chosen pair that was visited is answered by the multinomial model; one never visited by the
kinematic model's table (:func:`kinematic_target`), or skipped when the agent has none.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.kernels.kinematic_prediction import (
    PREDICT_COLLISION,
    PREDICT_GOAL,
    collision_wall_cell,
    feed_rows,
    predict_action,
)
from skidnav.kernels.multinomial import MultinomialArrays, find_pair, model_target
from skidnav.kernels.tabular import td_target, update_toward
from skidnav.robot.params import KinematicConstants
from skidnav.world.discretization import GridShape, region_of, state_of

# counters columns
N_TRAJECTORY = 0
TRAJECTORY_CURSOR = 1
N_NEIGHBOURS = 2
NEIGHBOUR_CURSOR = 3
EPISODE_LENGTH = 4
REFRESH_RADIUS = 5
USE_KINEMATIC = 6
EPISODE_TERMINATED = 7
N_COUNTERS = 8


class PlannerArrays(NamedTuple):
    """State of the model-based planner (every array is updated in place).

    Attributes:
        pred_next: int32 (n_states, n_actions) kinematic prediction of s′ from the cell centre.
        pred_outcome: int8 (n_states, n_actions) outcome codes of
            :mod:`skidnav.kernels.kinematic_prediction`.
        velocities: (n_regions, n_actions, 3) predicted body velocities [m/s, m/s, rad/s].
        walls, goals: bool (n_x, n_y), cells known to be walls (guessed from collisions) / goals.
        stale: bool (n_x, n_y), walls and goals found since the table was last refreshed.
        reward_stats: float64 (n_regions + 2, 2) [sum, count] of real rewards: rows 0..R−1 free
            steps by the region of s′, row R collisions, row R + 1 goal arrivals.
        trajectory_keys: int64 (capacity,) sweep list of trajectory pairs (key s·n_actions + a).
        neighbour_keys: int64 (capacity,) sweep list of neighbourhood pairs.
        episode_keys: int64 (capacity,) pairs of the current episode, in order.
        counters: int64 (N_COUNTERS,) see the module constants (list lengths, cursors, episode
            length, refresh radius [cells], kinematic flag, whether the episode terminated).
    """

    pred_next: np.ndarray
    pred_outcome: np.ndarray
    velocities: np.ndarray
    walls: np.ndarray
    goals: np.ndarray
    stale: np.ndarray
    reward_stats: np.ndarray
    trajectory_keys: np.ndarray
    neighbour_keys: np.ndarray
    episode_keys: np.ndarray
    counters: np.ndarray


class PlanningShares(NamedTuple):
    """Planning hyperparameters as the kernels take them."""

    n_steps: int
    alpha: float
    gamma: float
    mode: int
    trajectory_share: float
    kinematic_share: float


@jit
def state_region(state: int, grid: GridShape) -> int:
    """Slip region of the centre of a state's cell."""
    cell = state // grid.n_headings
    i = cell // grid.n_y
    j = cell % grid.n_y
    x = (i + 0.5) * grid.arena_width / (grid.n_x - 1)
    y = (j + 0.5) * grid.arena_height / (grid.n_y - 1)
    return region_of(x, y, grid)


@jit
def _mean_reward(stats: np.ndarray, row: int) -> float:
    """Mean of a reward_stats row; falls back to the mean of all free steps, then 0."""
    if stats[row, 1] > 0.0:
        return stats[row, 0] / stats[row, 1]
    n_regions = stats.shape[0] - 2
    total = 0.0
    count = 0.0
    for region in range(n_regions):
        total += stats[region, 0]
        count += stats[region, 1]
    return total / count if count > 0.0 else 0.0


@jit
def kinematic_target(
    q: np.ndarray, planner: PlannerArrays, state: int, action: int, gamma: float, grid: GridShape
) -> float:
    """TD target of a pair from the kinematic table; rewards are the learned means of
    ``reward_stats`` (goal arrival: terminal)."""
    next_state = planner.pred_next[state, action]
    outcome = planner.pred_outcome[state, action]
    n_regions = planner.reward_stats.shape[0] - 2
    if outcome == PREDICT_GOAL:
        return _mean_reward(planner.reward_stats, n_regions + 1)
    if outcome == PREDICT_COLLISION:
        reward = _mean_reward(planner.reward_stats, n_regions)
    else:
        reward = _mean_reward(planner.reward_stats, state_region(next_state, grid))
    return td_target(q, reward, next_state, 1.0, gamma)


@jit
def _update_pair(
    q: np.ndarray,
    model: MultinomialArrays,
    planner: PlannerArrays,
    state: int,
    action: int,
    shares: PlanningShares,
    grid: GridShape,
    rng: np.random.Generator,
) -> int:
    """One planning update of (state, action): multinomial if visited, else kinematic (if on and
    the state is not in a known wall). Returns 1 if a value was updated, else 0."""
    pair = find_pair(model, state, action)
    if pair >= 0:
        target = model_target(model, q, pair, shares.mode, shares.gamma, rng.random())
    elif planner.counters[USE_KINEMATIC] != 0:
        cell = state // grid.n_headings
        if planner.walls[cell // grid.n_y, cell % grid.n_y]:
            return 0
        target = kinematic_target(q, planner, state, action, shares.gamma, grid)
    else:
        return 0
    update_toward(q, state, action, target, shares.alpha)
    return 1


@jit
def _next_sweep_key(keys: np.ndarray, counters: np.ndarray, length: int, cursor: int) -> int:
    """Key under a sweep cursor, advancing the cursor cyclically."""
    position = counters[cursor]
    counters[cursor] = (position + 1) % counters[length]
    return keys[position]


@jit
def _choose_pair(
    model: MultinomialArrays,
    planner: PlannerArrays,
    shares: PlanningShares,
    rng: np.random.Generator,
) -> int:
    """Key s·n_actions + a of the next pair to update (see the module docstring)."""
    counters = planner.counters
    n_actions = model.n_actions
    has_sweep = counters[N_TRAJECTORY] > 0
    share = shares.trajectory_share if has_sweep else 0.0
    u = rng.random()
    if u < share:
        if u < 0.5 * share or counters[N_NEIGHBOURS] == 0:
            return _next_sweep_key(
                planner.trajectory_keys, counters, N_TRAJECTORY, TRAJECTORY_CURSOR
            )
        return _next_sweep_key(planner.neighbour_keys, counters, N_NEIGHBOURS, NEIGHBOUR_CURSOR)
    pair = int(rng.random() * model.counters[0])
    key = model.pair_key[pair]
    rest = (u - share) / (1.0 - share)
    if counters[USE_KINEMATIC] == 0 or rest >= shares.kinematic_share:
        return key
    predicted = planner.pred_next[key // n_actions, int(rng.random() * n_actions)]
    return predicted * n_actions + int(rng.random() * n_actions)


@jit
def combined_planning(
    q: np.ndarray,
    model: MultinomialArrays,
    planner: PlannerArrays,
    shares: PlanningShares,
    grid: GridShape,
    rng: np.random.Generator,
) -> int:
    """``shares.n_steps`` planning updates; returns how many values were updated."""
    if model.counters[0] == 0:
        return 0
    updates = 0
    n_actions = model.n_actions
    for _ in range(shares.n_steps):
        key = _choose_pair(model, planner, shares, rng)
        updates += _update_pair(
            q, model, planner, key // n_actions, key % n_actions, shares, grid, rng
        )
    return updates


@jit
def _refresh_cell(
    planner: PlannerArrays, i: int, j: int, robot: KinematicConstants, grid: GridShape
) -> None:
    """Recompute the kinematic table for every state of cell (i, j) (as
    :func:`~skidnav.kernels.kinematic_prediction.prediction_table`)."""
    x0 = (i + 0.5) * grid.arena_width / (grid.n_x - 1)
    y0 = (j + 0.5) * grid.arena_height / (grid.n_y - 1)
    n_actions = planner.pred_next.shape[1]
    for h in range(grid.n_headings):
        state = (i * grid.n_y + j) * grid.n_headings + h
        heading = -np.pi + (h + 0.5) * 2.0 * np.pi / grid.n_headings
        for action in range(n_actions):
            if planner.walls[i, j]:
                planner.pred_next[state, action] = state
                planner.pred_outcome[state, action] = PREDICT_COLLISION
                continue
            x, y, end_heading, code = predict_action(
                x0, y0, heading, action, planner.velocities, planner.walls, planner.goals,
                robot, grid,
            )  # fmt: skip
            planner.pred_next[state, action] = state_of(x, y, end_heading, grid)
            planner.pred_outcome[state, action] = code


@jit
def refresh_stale(planner: PlannerArrays, robot: KinematicConstants, grid: GridShape) -> int:
    """Recompute the table for every cell within ``REFRESH_RADIUS`` cells of a stale cell (a wall
    or goal discovered since the last refresh), then clear ``stale``. Returns the cells redone."""
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
    """Record a discovered goal or wall cell and mark it stale (the table around it is redone
    at the end of the episode, :func:`refresh_stale`)."""
    cell = next_state // grid.n_headings
    i, j = cell // grid.n_y, cell % grid.n_y
    if terminated and not planner.goals[i, j]:
        planner.goals[i, j] = True
        planner.stale[i, j] = True
    if collided and planner.counters[USE_KINEMATIC] != 0:
        wi, wj = collision_wall_cell(
            pose[0], pose[1], pose[2], action, planner.velocities, robot, grid
        )
        if wi >= 0 and not planner.walls[wi, wj] and not planner.goals[wi, wj]:
            planner.walls[wi, wj] = True
            planner.stale[wi, wj] = True


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
    and (with pose information, ``pose[0] >= 0``) discovered goal and wall cells.

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


@jit
def loop_erase(keys: np.ndarray, n_actions: int, n_states: int) -> np.ndarray:
    """Loop-erased copy of an episode's pairs (keys s·n_actions + a, in order).

    Whenever a state recurs, the pairs since its earlier visit (a loop) are dropped, so every
    state appears once and each kept pair still led, in reality, to the next kept state.
    """
    position = np.full(n_states, -1, dtype=np.int64)
    out = np.empty(keys.shape[0], dtype=np.int64)
    length = 0
    for key in keys:
        state = key // n_actions
        earlier = position[state]
        if earlier >= 0:
            for k in range(earlier, length):
                position[out[k] // n_actions] = -1
            length = earlier
        position[state] = length
        out[length] = key
        length += 1
    return out[:length].copy()


@jit
def _spatial_neighbours(
    out: np.ndarray, length: int, state: int, walls: np.ndarray, grid: GridShape, n_actions: int
) -> int:
    """Append every action at the states one cell (same heading bin) or one heading bin (same
    cell) away from ``state``, skipping known wall cells; returns the new length."""
    cell, h = state // grid.n_headings, state % grid.n_headings
    i, j = cell // grid.n_y, cell % grid.n_y
    for di in range(-1, 2):
        for dj in range(-1, 2):
            for dh in range(-1, 2):
                same_cell = di == 0 and dj == 0
                if (same_cell and dh == 0) or (not same_cell and dh != 0):
                    continue
                ni, nj = i + di, j + dj
                if ni < 0 or nj < 0 or ni >= grid.n_x or nj >= grid.n_y or walls[ni, nj]:
                    continue
                neighbour = (ni * grid.n_y + nj) * grid.n_headings + (h + dh) % grid.n_headings
                for action in range(n_actions):
                    out[length] = neighbour * n_actions + action
                    length += 1
    return length


@jit
def neighbourhood_keys(
    trajectory: np.ndarray, walls: np.ndarray, grid: GridShape, n_actions: int, spatial: bool
) -> np.ndarray:
    """Pairs around a trajectory, walked backward from its last pair: first the other actions at
    each trajectory state, then (if ``spatial``: the states are skid-steer poses) every action at
    the states one cell (8-neighbourhood, same heading bin) or one heading bin away; states in
    known wall cells are left out. May repeat."""
    out = np.empty(trajectory.shape[0] * n_actions * 27, dtype=np.int64)
    length = 0
    for k in range(trajectory.shape[0] - 1, -1, -1):
        state = trajectory[k] // n_actions
        for action in range(n_actions):
            if action != trajectory[k] % n_actions:
                out[length] = state * n_actions + action
                length += 1
        if spatial:
            length = _spatial_neighbours(out, length, state, walls, grid, n_actions)
    return out[:length].copy()
