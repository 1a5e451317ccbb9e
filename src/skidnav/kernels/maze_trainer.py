"""The fused compiled episode on the grid mazes of Sutton & Barto (2018) ch. 8 (used by
:func:`skidnav.agents.fast_training.train_agent_fast` and
:func:`skidnav.agents.fast_training.train_for_steps_fast`).

Each step does what the plain loop (:func:`skidnav.agents.training.run_episode` or
``train_for_steps`` driving :class:`skidnav.envs.mazes.GridMazeEnv`) does, in the same order and
with the same draws, so both give identical numbers:

1. ``epsilon_greedy(q, s, ε, agent_rng)``;
2. the maze's move (:func:`maze_move`, as ``GridMazeEnv.step``: walls ``walls_after`` once the env
   has taken ``change_after`` steps in total; reward +1 and termination at the goal);
3. the agent's learning step, :func:`skidnav.kernels.trainer.classic_learn`;
4. truncation after the env's limit or the trainer's ``max_steps``.

The mazes draw no random numbers, so the agent's generator is the only stream.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.kernels.tabular import epsilon_greedy, greedy_first, inline_jit
from skidnav.kernels.trainer import (
    ELAPSED,
    LENGTH,
    N_TALLY,
    STEPS,
    TERMINATED,
    LearnerArrays,
    LearnerSettings,
    classic_learn,
)

# extra columns of the int64 ``tally`` array (after those of :mod:`skidnav.kernels.trainer`)
TOTAL_STEPS, ENDED = N_TALLY, N_TALLY + 1
N_MAZE_TALLY = N_TALLY + 2

ROW_MOVES = (-1, 1, 0, 0)
COLUMN_MOVES = (0, 0, -1, 1)
"""(row, column) change of actions 0 up, 1 down, 2 left, 3 right (as ``envs.mazes.MOVES``)."""


class MazeArrays(NamedTuple):
    """A grid maze for the compiled loop.

    ``walls_before`` and ``walls_after`` are bool (n_rows, n_cols); the second applies once the env
    has taken ``change_after`` steps in total (a huge number when the walls never change); ``goal``
    is the flat goal state ``row · n_cols + column``.
    """

    walls_before: np.ndarray
    walls_after: np.ndarray
    change_after: int
    goal: int


@inline_jit
def maze_move(maze: MazeArrays, state: int, action: int, total_steps: int) -> int:
    """The next flat state of ``action`` from ``state`` when the env has taken ``total_steps``
    steps so far: a move into a wall or off the grid stays put."""
    walls = maze.walls_after if total_steps >= maze.change_after else maze.walls_before
    n_rows, n_cols = walls.shape
    row = state // n_cols + ROW_MOVES[action]
    column = state % n_cols + COLUMN_MOVES[action]
    if 0 <= row < n_rows and 0 <= column < n_cols and not walls[row, column]:
        return row * n_cols + column
    return state


@jit
def maze_episode(
    maze: MazeArrays,
    state: int,
    agent: LearnerArrays,
    settings: LearnerSettings,
    tally: np.ndarray,
    rewards: np.ndarray,
    budget: int,
    rng: np.random.Generator,
) -> tuple[float, int]:
    """Learn from ``state`` until the episode ends (goal, env limit or ``settings.max_steps``; then
    ``tally[ENDED]`` = 1) or ``budget`` steps are taken. ``tally`` (int64, (N_MAZE_TALLY,)) holds
    the counters of :mod:`skidnav.kernels.trainer` plus the env's ``TOTAL_STEPS``; rewards go to
    ``rewards[0 : steps]`` if ``rewards`` (float64) is not empty. Returns (return, last state)."""
    total = 0.0
    for step in range(budget):
        action = epsilon_greedy(agent.q, state, settings.epsilon, rng)
        next_state = maze_move(maze, state, action, tally[TOTAL_STEPS])
        tally[TOTAL_STEPS] += 1
        tally[ELAPSED] += 1
        tally[LENGTH] += 1
        tally[STEPS] += 1
        terminated = next_state == maze.goal
        reward = 1.0 if terminated else 0.0
        total += reward
        if rewards.shape[0] > 0:
            rewards[step] = reward
        classic_learn(agent, settings, tally, state, action, reward, next_state, terminated, rng)
        state = next_state
        truncated = tally[ELAPSED] >= settings.env_limit or tally[LENGTH] >= settings.max_steps
        if terminated or truncated:
            tally[TERMINATED] = 1 if terminated else 0
            tally[ENDED] = 1
            return total, state
    return total, state


@jit
def maze_greedy(
    maze: MazeArrays, state: int, q: np.ndarray, max_steps: int, env_limit: int, total_steps: int
) -> tuple[int, int, int]:
    """Greedy rollout (``greedy_first``, no learning) from a reset maze with ``total_steps`` taken
    so far: returns (actions taken if the goal was reached else −1, last state, actions taken)."""
    for step in range(1, max_steps + 1):
        state = maze_move(maze, state, greedy_first(q, state), total_steps)
        total_steps += 1
        if state == maze.goal:
            return step, state, step
        if step >= env_limit:
            return -1, state, step
    return -1, state, max_steps
