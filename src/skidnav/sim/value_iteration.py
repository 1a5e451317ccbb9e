"""Compiled parts of the oracle: the true transition model of the discretized navigation MDP,
estimated from the simulator itself, and the expected cost to the goal under it.

:func:`sample_outcomes` draws ``n_samples`` poses uniformly inside each free state's cell and
heading bin, applies every action once from each with fresh slip noise (the one MDP step,
:func:`skidnav.sim.navigation.transition`, at simulated time 0) and records the next state, or
:data:`GOAL_STATE` when the action ended in the goal cell, and the mean of the actions' costs
(:func:`skidnav.sim.navigation.action_cost`: minus the reward without the goal bonus).
``outcomes[s, a, k]`` is then a sample of p(s′ | s, a) with poses spread over the state as a
policy that only sees the state meets them, and ``step_costs[s, a]`` the expected cost c(s, a)
of the action.

:func:`expected_costs` solves the stochastic shortest-path problem on those samples by value
iteration (Bertsekas & Tsitsiklis (1996) §2.2; Sutton & Barto (2018) §4.4):

    V(s) = min_a [ c(s, a) + (1/K) Σ_k V(s′_k) ],   V(goal) = 0,

the expected cost from s to the goal under the best state-feedback policy of the sampled model.
With c ≡ 1 (:func:`expected_actions`) it is the expected number of actions (a collision costs
the action it takes). States that cannot reach the goal keep ``UNREACHABLE``.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import jit
from skidnav.sim.navigation import NavigationTask, draw_noise, transition

GOAL_STATE = -1
"""``outcomes`` entry of a sampled action that ended in the goal cell (terminated)."""
UNREACHABLE = 1e9
"""Expected cost (or actions) of a state from which the sampled model never reaches the goal."""


@jit
def sample_outcomes(
    task: NavigationTask,
    n_samples: int,
    rng: np.random.Generator,
    outcomes: np.ndarray,
    step_costs: np.ndarray,
) -> int:
    """Fill ``outcomes`` int32 (n_states, n_actions, n_samples) with sampled next states and
    ``step_costs`` float64 (n_states, n_actions) with the mean cost of each action over its
    samples (module docs); wall and goal states get −2 and cost 0 everywhere (never a source).
    Returns the actions simulated.

    Pose of sample k in state (i, j, h): x = (i + u₁)·w, y = (j + u₂)·h_c, heading =
    −π + (h + u₃)·2π/n_headings with u uniform in [0, 1), clipped to the arena on the zero-width
    last levels.
    """
    grid = task.grid
    width = grid.arena_width / (grid.n_x - 1)
    height = grid.arena_height / (grid.n_y - 1)
    sector = 2.0 * math.pi / grid.n_headings
    noise = np.empty(2 * task.robot.substeps)
    log = np.empty((task.robot.substeps, 6))
    pose = np.empty(3)
    n_actions = outcomes.shape[1]
    simulated = 0
    step_costs[:] = 0.0
    for state in range(outcomes.shape[0]):
        cell = state // grid.n_headings
        i, j = cell // grid.n_y, cell % grid.n_y
        if task.occupancy[i, j] != 0 or (i == task.goal_i and j == task.goal_j):
            outcomes[state] = -2
            continue
        bin_index = state % grid.n_headings
        for k in range(n_samples):
            x = min((i + rng.random()) * width, grid.arena_width)
            y = min((j + rng.random()) * height, grid.arena_height)
            heading = -math.pi + (bin_index + rng.random()) * sector
            for action in range(n_actions):
                pose[0], pose[1], pose[2] = x, y, heading
                draw_noise(rng, noise)
                outcome = transition(task, pose, action, 0.0, noise, log)
                outcomes[state, action, k] = GOAL_STATE if outcome.terminated else outcome.state
                step_costs[state, action] += outcome.cost
                simulated += 1
        for action in range(n_actions):
            step_costs[state, action] /= n_samples
    return simulated


@jit
def action_values(
    outcomes: np.ndarray, step_costs: np.ndarray, values: np.ndarray, state: int, out: np.ndarray
) -> None:
    """out[a] = c(s, a) + mean over samples of V(s′) for every action of ``state`` (V(goal) = 0):
    the expected cost to the goal after taking a, ``step_costs`` float64 (n_states, n_actions)
    holding c."""
    n_samples = outcomes.shape[2]
    for action in range(outcomes.shape[1]):
        total = 0.0
        for k in range(n_samples):
            successor = outcomes[state, action, k]
            if successor >= 0:
                total += values[successor]
        out[action] = step_costs[state, action] + total / n_samples


@jit
def expected_costs(
    outcomes: np.ndarray, step_costs: np.ndarray, max_sweeps: int, tolerance: float
) -> tuple[np.ndarray, int]:
    """Value iteration (Gauss–Seidel, in state order) for the expected cost to the goal from
    every state, float64 (n_states,), actions costing ``step_costs`` float64 (n_states,
    n_actions); sources are the states whose ``outcomes`` are ≥ −1. Stops when no value changes
    by more than ``tolerance`` [cost] in a sweep. Returns (values, sweeps made); values ≥
    ``UNREACHABLE`` mean the goal is never reached."""
    n_states, n_actions = outcomes.shape[0], outcomes.shape[1]
    values = np.full(n_states, UNREACHABLE)
    after = np.empty(n_actions)
    for sweep in range(1, max_sweeps + 1):
        change = 0.0
        for state in range(n_states):
            if outcomes[state, 0, 0] < -1:
                continue
            action_values(outcomes, step_costs, values, state, after)
            best = min(after.min(), UNREACHABLE)
            change = max(change, abs(best - values[state]))
            values[state] = best
        if change <= tolerance:
            return values, sweep
    return values, max_sweeps


@jit
def expected_actions(
    outcomes: np.ndarray, max_sweeps: int, tolerance: float
) -> tuple[np.ndarray, int]:
    """:func:`expected_costs` with every action costing 1: the expected number of actions to the
    goal from every state [actions]."""
    unit = np.ones((outcomes.shape[0], outcomes.shape[1]))
    return expected_costs(outcomes, unit, max_sweeps, tolerance)


@jit
def oracle_q(outcomes: np.ndarray, step_costs: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The oracle's action values as a Q table, float64 (n_states, n_actions): minus the expected
    cost to the goal after taking a (``values`` solved for the same ``step_costs``: so the
    greedy policy of any agent's evaluation code picks the oracle's action); 0 on wall and goal
    states."""
    n_states, n_actions = outcomes.shape[0], outcomes.shape[1]
    q = np.zeros((n_states, n_actions))
    after = np.empty(n_actions)
    for state in range(n_states):
        if outcomes[state, 0, 0] < -1:
            continue
        action_values(outcomes, step_costs, values, state, after)
        for action in range(n_actions):
            q[state, action] = -after[action]
    return q


@jit
def start_costs(
    task: NavigationTask,
    start: np.ndarray,
    action_values: np.ndarray,
    cost_values: np.ndarray,
    n_samples: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """The expected actions and the expected cost to the goal after each first action from the
    exact pose ``start`` (x [m], y [m], heading [rad]), float64 (2, n_actions): over
    ``n_samples`` slip-noise draws, the mean of 1 + V(s′) (row 0, ``action_values`` V solved
    with unit costs) and of c + V(s′) (row 1, ``cost_values`` solved with the costs, c the
    action's :func:`~skidnav.sim.navigation.action_cost`); V(goal) = 0. The start pose is
    one point, not a state's spread of poses, so its first step is simulated from that point,
    each draw scored for both."""
    n_actions = 4
    first = np.empty((2, n_actions))
    noise = np.empty(2 * task.robot.substeps)
    log = np.empty((task.robot.substeps, 6))
    pose = np.empty(3)
    for action in range(n_actions):
        actions = spent = cost = 0.0
        for _ in range(n_samples):
            pose[0], pose[1], pose[2] = start[0], start[1], start[2]
            draw_noise(rng, noise)
            outcome = transition(task, pose, action, 0.0, noise, log)
            spent += outcome.cost
            if not outcome.terminated:
                actions += action_values[outcome.state]
                cost += cost_values[outcome.state]
        first[0, action] = 1.0 + actions / n_samples
        first[1, action] = spent / n_samples + cost / n_samples
    return first
