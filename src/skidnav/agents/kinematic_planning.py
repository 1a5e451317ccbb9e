"""Compiled parts of the thesis's model-based agents: kinematic-model planning on pairs never
visited and planning prioritized around the shortest discovered trajectories (Alhawary (2020),
ch. 7; docs/agents/dyna-kinematic.md, docs/agents/trajectory-prioritized.md).

One planner (:class:`PlannerArrays`) serves ``dyna-kinematic``, ``trajectory-prioritized`` and
``dyna-full``; their configs only change the shares of the three kinds of planning update
(:func:`combined_planning`):

* **trajectory** — the next pair of the sweep lists built from the best trajectories (built in
  Python, :mod:`skidnav.agents.tabular.trajectory_prioritized`): half of this share walks the
  trajectory pairs (backward from the goal), half walks their neighbourhood;
* **frontier** (kinematic) — a visited pair drawn uniformly, a random action predicted from its
  state by the kinematic model, and a random action at the predicted state: so the updates reach
  the states one predicted step around the visited set;
* **replay** — Dyna-Q's uniform replay of a visited pair (:mod:`skidnav.agents.tabular.planning`).

A chosen pair that was visited is answered by the multinomial model; one never visited by the
kinematic model's table (:func:`kinematic_value`), or skipped when the agent has none.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.models.kinematic_prediction import (
    PREDICT_COLLISION,
    PREDICT_GOAL,
    collision_wall_cell,
    feed_rows,
    predict_action,
)
from skidnav.models.multinomial_kernels import (
    MOST_PROBABLE,
    MultinomialArrays,
    hash_find,
    model_target_call,
    most_probable_target,
    split_key,
)
from skidnav.robot.params import KinematicConstants
from skidnav.sim.q_values import td_target, update_toward
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
MAP_CHANGES = 8
N_COUNTERS = 9


class PlannerArrays(NamedTuple):
    """State of the model-based planner (every array is updated in place).

    Attributes:
        pred_next: int32 (n_states, n_actions) kinematic prediction of s′ from the cell centre.
        pred_outcome: int8 (n_states, n_actions) outcome codes of
            :mod:`skidnav.models.kinematic_prediction`.
        pred_row: int16 (n_states, n_actions) the ``reward_stats`` row of each prediction
            (:func:`reward_row`), derived from the two above wherever they are written.
        velocities: (n_regions, n_actions, 3) predicted body velocities [m/s, m/s, rad/s].
        walls: bool (n_x, n_y), cells the agent treats as walls: those whose wall evidence
            outweighs their free evidence (:func:`weigh_cell`), never a known goal.
        goals: bool (n_x, n_y), cells known to be goals.
        stale: bool (n_x, n_y), cells that became or stopped being walls, and goals found, since
            the table was last refreshed.
        wall_evidence: int64 (n_x, n_y), collisions whose guessed wall cell
            (:func:`~skidnav.models.kinematic_prediction.collision_wall_cell`) was this cell.
        free_evidence: int64 (n_x, n_y), real steps that ended with the robot in this cell.
        reward_stats: float64 (n_regions + 2, 2) [sum, count] of real rewards: rows 0..R−1 free
            steps by the region of s′, row R collisions, row R + 1 goal arrivals.
        trajectory_keys: int64 (capacity,) sweep list of trajectory pairs (key s·n_actions + a).
        neighbour_keys: int64 (capacity,) sweep list of neighbourhood pairs.
        episode_keys: int64 (capacity,) pairs of the current episode, in order.
        counters: int64 (N_COUNTERS,) see the module constants (list lengths, cursors, episode
            length, refresh radius [cells], kinematic flag, whether the episode terminated, and
            the map's changes: goals found and cells that became or stopped being walls).
    """

    pred_next: np.ndarray
    pred_outcome: np.ndarray
    pred_row: np.ndarray
    velocities: np.ndarray
    walls: np.ndarray
    goals: np.ndarray
    stale: np.ndarray
    wall_evidence: np.ndarray
    free_evidence: np.ndarray
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
def mean_rewards(stats: np.ndarray) -> np.ndarray:
    """:func:`_mean_reward` of every row of ``reward_stats``, float64 (n_regions + 2,): they do not
    change while planning, so a planning call computes them once."""
    means = np.empty(stats.shape[0])
    for row in range(stats.shape[0]):
        means[row] = _mean_reward(stats, row)
    return means


@inline_jit
def reward_row(next_state: int, outcome: int, n_regions: int, grid: GridShape) -> int:
    """The ``reward_stats`` row whose mean rewards a predicted outcome: the region of the
    predicted state for a free move, row R for a collision, R + 1 for a goal arrival."""
    row = n_regions
    if outcome == PREDICT_GOAL:
        row = n_regions + 1
    elif outcome != PREDICT_COLLISION:
        row = state_region(next_state, grid)
    return row


@jit
def fill_reward_rows(planner: PlannerArrays, grid: GridShape) -> None:
    """``pred_row`` of every prediction in the table (after the whole table was recomputed)."""
    n_regions = planner.reward_stats.shape[0] - 2
    for state in range(planner.pred_next.shape[0]):
        for action in range(planner.pred_next.shape[1]):
            planner.pred_row[state, action] = reward_row(
                planner.pred_next[state, action], planner.pred_outcome[state, action],
                n_regions, grid,
            )  # fmt: skip


@inline_jit
def kinematic_value(
    q: np.ndarray,
    pred_next: np.ndarray,
    pred_row: np.ndarray,
    means: np.ndarray,
    state: int,
    action: int,
    gamma: float,
) -> float:
    """TD target of a pair from the kinematic table ``pred_next`` / ``pred_row`` with the
    learned mean rewards ``means`` (:func:`mean_rewards`; a goal arrival, the last row, is
    terminal). The rows are precomputed (:func:`reward_row`): finding the predicted state's
    region took five divisions, about half of a kinematic update. One path for the arrays, so
    numba prunes their reference counts in the planning loop."""
    row = pred_row[state, action]
    continuation = 0.0 if row == means.shape[0] - 1 else 1.0
    return td_target(q, means[row], pred_next[state, action], continuation, gamma)


@inline_jit
def _next_sweep_key(keys: np.ndarray, counters: np.ndarray, length: int, cursor: int) -> int:
    """Key under a sweep cursor, advancing the cursor cyclically."""
    position = counters[cursor]
    counters[cursor] = (position + 1) % counters[length]
    return keys[position]


@jit
def combined_planning(
    q: np.ndarray,
    model: MultinomialArrays,
    planner: PlannerArrays,
    shares: PlanningShares,
    grid: GridShape,
    rng: np.random.Generator,
) -> int:
    """``shares.n_steps`` planning updates; returns how many values were updated.

    Each update chooses a pair (see the module docstring: the next key of a sweep list with
    probability ``trajectory_share`` once a trajectory exists, else a visited pair drawn
    uniformly, sent to the frontier with probability ``kinematic_share``), then updates it: a
    visited pair toward its multinomial target (one ``rng.random()`` for the model), one never
    visited toward its kinematic target (if the agent has a kinematic model and the state is
    not in a known wall), other pairs are skipped. Written out over arrays bound once, with
    only helpers numba prunes the reference counting of (one exit each; see
    :mod:`skidnav.models.multinomial_kernels`): calling helpers that took the model and the planner
    cost ~0.6 µs per update, 98 % of it."""
    n_pairs = model.counters[0]
    if n_pairs == 0:
        return 0
    counters, pair_key, pair_table = planner.counters, model.pair_key, model.pair_table
    pred_next, pred_row, walls = planner.pred_next, planner.pred_row, planner.walls
    trajectory_keys, neighbour_keys = planner.trajectory_keys, planner.neighbour_keys
    walls_by_cell = walls.reshape(-1)  # cell i·n_y + j is walls[i, j]: one division fewer
    means = mean_rewards(planner.reward_stats)
    cells = q.reshape(-1, 1)  # row s·n_actions + a is q[s, a]
    n_actions, use_kinematic = model.n_actions, counters[USE_KINEMATIC] != 0
    share = shares.trajectory_share if counters[N_TRAJECTORY] > 0 else 0.0
    updates = 0
    for _ in range(shares.n_steps):
        u = rng.random()
        pair = -1
        if u < share and (u < 0.5 * share or counters[N_NEIGHBOURS] == 0):
            key = _next_sweep_key(trajectory_keys, counters, N_TRAJECTORY, TRAJECTORY_CURSOR)
        elif u < share:
            key = _next_sweep_key(neighbour_keys, counters, N_NEIGHBOURS, NEIGHBOUR_CURSOR)
        else:
            pair = int(rng.random() * n_pairs)
            key = pair_key[pair]  # a visited pair: no need to look it up
        state, action = split_key(key, n_actions)
        if pair >= 0 and use_kinematic and (u - share) / (1.0 - share) < shares.kinematic_share:
            state = pred_next[state, int(rng.random() * n_actions)]
            action = int(rng.random() * n_actions)
            key = state * n_actions + action  # a frontier pair, split without dividing
            pair = -1
        if pair < 0:
            pair = hash_find(pair_table, pair_key, key)
        if pair >= 0:
            if shares.mode == MOST_PROBABLE:
                target = most_probable_target(q, model, pair, shares.gamma, rng.random())
            else:
                target = model_target_call(model, q, pair, shares.mode, shares.gamma, rng.random())
        elif use_kinematic and not walls_by_cell[state // grid.n_headings]:
            target = kinematic_value(q, pred_next, pred_row, means, state, action, shares.gamma)
        else:
            continue
        update_toward(cells, key, 0, target, shares.alpha)
        updates += 1
    return updates


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
                    robot, grid,
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
        state = split_key(key, n_actions)[0]
        earlier = position[state]
        if earlier >= 0:
            for k in range(earlier, length):
                position[split_key(out[k], n_actions)[0]] = -1
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
        state, taken = split_key(trajectory[k], n_actions)
        for action in range(n_actions):
            if action != taken:
                out[length] = state * n_actions + action
                length += 1
        if spatial:
            length = _spatial_neighbours(out, length, state, walls, grid, n_actions)
    return out[:length].copy()
