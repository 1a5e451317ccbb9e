"""The grid mazes of Sutton & Barto (2018) ch. 8 for compiled code: their walls and goal
(:class:`MazeArrays`, built by :meth:`skidnav.envs.mazes.GridMazeEnv.maze_arrays`) and their move
(:func:`maze_move`, as ``GridMazeEnv.step``), driven by
:func:`skidnav.agents.tabular.env_steps.maze_step`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit

ROW_MOVES = (-1, 1, 0, 0)
COLUMN_MOVES = (0, 0, -1, 1)
"""(row, column) change of actions 0 up, 1 down, 2 left, 3 right (as ``envs.mazes.MOVES``)."""
MOVE_COST = 1.0
"""The cost of every move of a maze, the goal's included: its discounted goal reward is earned
soonest on the shortest path, so the cost it ranks paths by is their number of moves."""


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
