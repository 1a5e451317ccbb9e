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
)
from skidnav.models.multinomial_kernels import MultinomialArrays, hash_find, split_key
from skidnav.models.multinomial_targets import (
    EXPECTED,
    MOST_PROBABLE,
    expected_model_target,
    model_target_call,
    most_probable_target,
)
from skidnav.sim.q_values import td_target, update_toward
from skidnav.world.discretization import GridShape, region_of

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
            outweighs their free evidence
            (:func:`~skidnav.agents.planner_learning.weigh_cell`), never a known goal.
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
    cost ~0.6 µs per update, 98 % of it. The most-probable and expected targets are inlined
    (as a compiled call the expected one, the agents' default, made an update 3–11× slower:
    docs/agents/fast-training.md); the sample target is the compiled call
    :func:`model_target_call`."""
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
        if u < share:  # the next key of a sweep list
            if u < 0.5 * share or counters[N_NEIGHBOURS] == 0:
                key = _next_sweep_key(trajectory_keys, counters, N_TRAJECTORY, TRAJECTORY_CURSOR)
            else:
                key = _next_sweep_key(neighbour_keys, counters, N_NEIGHBOURS, NEIGHBOUR_CURSOR)
            pair = hash_find(pair_table, pair_key, key)
            state, action = split_key(key, n_actions)
        elif use_kinematic and (u - share) / (1.0 - share) < shares.kinematic_share:  # frontier
            origin, _ = split_key(pair_key[int(rng.random() * n_pairs)], n_actions)
            state = pred_next[origin, int(rng.random() * n_actions)]
            action = int(rng.random() * n_actions)
            key = state * n_actions + action  # split without dividing
            pair = hash_find(pair_table, pair_key, key)
        else:  # replay of a visited pair: its slot is drawn, not looked up
            pair = int(rng.random() * n_pairs)
            key = pair_key[pair]
            state, action = split_key(key, n_actions)
        if pair >= 0:
            if shares.mode == MOST_PROBABLE:
                target = most_probable_target(q, model, pair, shares.gamma, rng.random())
            elif shares.mode == EXPECTED:
                rng.random()  # drawn, unused, as in every mode: one random stream for all modes
                target = expected_model_target(q, model, pair, shares.gamma)
            else:
                target = model_target_call(model, q, pair, shares.mode, shares.gamma, rng.random())
        elif use_kinematic and not walls_by_cell[state // grid.n_headings]:
            target = kinematic_value(q, pred_next, pred_row, means, state, action, shares.gamma)
        else:
            continue
        update_toward(cells, key, 0, target, shares.alpha)
        updates += 1
    return updates
