"""The grid mazes of Sutton & Barto (2018) ch. 8, as small Gymnasium envs (textbook checks).

* :func:`dyna_maze` — Example 8.1 (6 × 9, shortest path 14 steps), optionally scaled up by an
  integer factor for the prioritized-sweeping comparison of Example 8.4.
* :func:`blocking_maze` — Example 8.2: the short path on the right is blocked after 1000 steps and
  a longer one opens on the left.
* :func:`shortcut_maze` — Example 8.3: a shorter path opens on the right after 3000 steps.

>>> env = dyna_maze()
>>> state, info = env.reset(seed=0)
>>> state, env.shortest_path_length()
(18, 14)
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from typing import Any

import gymnasium as gym
import numpy as np

from skidnav.sim.maze import MOVE_COST, MazeArrays

Cell = tuple[int, int]
MOVES = ((-1, 0), (1, 0), (0, -1), (0, 1))
"""(row, column) change of actions 0 up, 1 down, 2 left, 3 right."""


class GridMazeEnv(gym.Env[int, int]):
    """A deterministic grid maze with walls that may change after a number of steps.

    ## Description
    The agent moves between the free cells of an ``n_rows × n_cols`` grid from ``start`` to
    ``goal`` (Sutton & Barto (2018) Example 8.1). Moves into a wall or off the grid leave it where
    it is. If ``change_after`` is set, the walls become ``walls_after`` once the env has taken that
    many steps in total (counted across episodes), as in Examples 8.2 and 8.3.

    ## Action Space
    ``Discrete(4)``: 0 up (row − 1), 1 down (row + 1), 2 left (column − 1), 3 right (column + 1).

    ## Observation Space
    ``Discrete(n_rows · n_cols)``: the flat cell ``row · n_cols + column``.

    ## Rewards
    +1 on reaching the goal, 0 for every other step. ``info["cost"]`` is 1 for every move
    (:data:`~skidnav.sim.maze.MOVE_COST`): the discounted goal reward is earned
    soonest on the shortest path.

    ## Starting State
    Always ``start``.

    ## Episode End
    Terminated on reaching the goal. Truncated after ``max_episode_steps`` actions if given.

    ## Arguments
    ``n_rows``, ``n_cols``; ``walls`` (row, column) cells; ``start``, ``goal``; ``change_after``
    (steps) and ``walls_after``; ``max_episode_steps``; ``render_mode`` ("ansi" or None).

    ## Version History
    v0: first version; ``info["cost"]`` added.
    """

    metadata = {"render_modes": ["ansi"]}  # noqa: RUF012 (Gymnasium's convention)

    def __init__(
        self,
        n_rows: int,
        n_cols: int,
        walls: Iterable[Cell],
        start: Cell,
        goal: Cell,
        *,
        change_after: int | None = None,
        walls_after: Iterable[Cell] = (),
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
    ) -> None:
        if n_rows < 1 or n_cols < 1:
            raise ValueError(f"expected a grid of at least 1 × 1, got {n_rows} × {n_cols}")
        self.n_rows, self.n_cols = n_rows, n_cols
        self.start, self.goal = start, goal
        self._walls_before = self._wall_grid(walls)
        self._walls_after = self._wall_grid(walls_after) if change_after is not None else None
        for name, cell in (("start", start), ("goal", goal)):
            if not self._inside(cell) or self._walls_before[cell]:
                raise ValueError(f"expected a free {name} cell inside the grid, got {cell}")
        self.change_after = change_after
        self.max_episode_steps = max_episode_steps
        self.render_mode = render_mode
        self.observation_space = gym.spaces.Discrete(n_rows * n_cols)  # type: ignore[assignment]
        self.action_space = gym.spaces.Discrete(4)  # type: ignore[assignment]
        self.total_steps = 0
        """Steps taken since construction (not reset by :meth:`reset`)."""
        self._cell = start
        self._episode_steps = 0

    def _inside(self, cell: Cell) -> bool:
        return 0 <= cell[0] < self.n_rows and 0 <= cell[1] < self.n_cols

    def _wall_grid(self, walls: Iterable[Cell]) -> np.ndarray:
        grid = np.zeros((self.n_rows, self.n_cols), dtype=np.bool_)
        for cell in walls:
            if not self._inside(cell):
                raise ValueError(f"expected wall cells inside the grid, got {cell}")
            grid[cell] = True
        return grid

    @property
    def walls(self) -> np.ndarray:
        """Current wall grid, bool (n_rows, n_cols)."""
        if self._walls_after is not None and self.total_steps >= (self.change_after or 0):
            return self._walls_after
        return self._walls_before

    def state_of(self, cell: Cell) -> int:
        """Flat state of a (row, column) cell."""
        return cell[0] * self.n_cols + cell[1]

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        self._cell = self.start
        self._episode_steps = 0
        return self.state_of(self._cell), {}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        if not self.action_space.contains(action):
            raise ValueError(f"expected an action in 0..3, got {action!r}")
        d_row, d_col = MOVES[int(action)]
        target = (self._cell[0] + d_row, self._cell[1] + d_col)
        if self._inside(target) and not self.walls[target]:
            self._cell = target
        self.total_steps += 1
        self._episode_steps += 1
        terminated = self._cell == self.goal
        truncated = (
            not terminated
            and self.max_episode_steps is not None
            and self._episode_steps >= self.max_episode_steps
        )
        reward = 1.0 if terminated else 0.0
        return self.state_of(self._cell), reward, terminated, truncated, {"cost": MOVE_COST}

    def maze_arrays(self) -> MazeArrays:
        """The maze for the compiled loop of :mod:`skidnav.sim.maze` (walls arrays
        shared, not copied)."""
        never = np.iinfo(np.int64).max
        after = self._walls_after if self._walls_after is not None else self._walls_before
        change = never if self._walls_after is None else int(self.change_after or 0)
        return MazeArrays(self._walls_before, after, change, self.state_of(self.goal))

    def progress(self) -> tuple[int, int, int]:
        """(flat state, steps of the current episode, steps in all): what a compiled loop needs
        to continue from here."""
        return self.state_of(self._cell), self._episode_steps, self.total_steps

    def restore_progress(self, state: int, episode_steps: int, total_steps: int) -> None:
        """Put the env where a compiled loop left it (the inverse of :meth:`progress`)."""
        self._cell = divmod(int(state), self.n_cols)
        self._episode_steps = int(episode_steps)
        self.total_steps = int(total_steps)

    def shortest_path_length(self) -> int:
        """Fewest actions from start to goal with the current walls (breadth-first), or −1."""
        walls = self.walls
        distance = {self.start: 0}
        frontier = deque([self.start])
        while frontier:
            cell = frontier.popleft()
            if cell == self.goal:
                return distance[cell]
            for d_row, d_col in MOVES:
                nxt = (cell[0] + d_row, cell[1] + d_col)
                if self._inside(nxt) and not walls[nxt] and nxt not in distance:
                    distance[nxt] = distance[cell] + 1
                    frontier.append(nxt)
        return -1

    def render(self) -> str | None:
        """Text picture: ``#`` wall, ``S`` start, ``G`` goal, ``A`` agent, ``.`` free."""
        if self.render_mode != "ansi":
            return None
        rows = []
        for row in range(self.n_rows):
            line = ""
            for col in range(self.n_cols):
                cell = (row, col)
                marks = (
                    (cell == self._cell, "A"),
                    (cell == self.goal, "G"),
                    (cell == self.start, "S"),
                )
                line += next((mark for hit, mark in marks if hit), "#" if self.walls[cell] else ".")
            rows.append(line)
        return "\n".join(rows)


DYNA_MAZE_WALLS: tuple[Cell, ...] = ((1, 2), (2, 2), (3, 2), (4, 5), (0, 7), (1, 7), (2, 7))
"""Walls of the Dyna Maze (Example 8.1), (row, column)."""


def dyna_maze(scale: int = 1, max_episode_steps: int | None = None) -> GridMazeEnv:
    """The Dyna Maze of Example 8.1 (6 × 9, start (2, 0), goal (0, 8)); ``scale`` > 1 turns each
    cell into a ``scale × scale`` block (Example 8.4's larger mazes), start and goal at the
    top-left cell of their blocks."""
    if scale < 1:
        raise ValueError(f"expected scale >= 1, got {scale}")
    walls = [
        (row * scale + i, col * scale + j)
        for row, col in DYNA_MAZE_WALLS
        for i in range(scale)
        for j in range(scale)
    ]
    return GridMazeEnv(
        6 * scale,
        9 * scale,
        walls,
        (2 * scale, 0),
        (0, 8 * scale),
        max_episode_steps=max_episode_steps,
    )


def _row_wall(row: int, columns: range) -> list[Cell]:
    return [(row, col) for col in columns]


def blocking_maze(change_after: int = 1000) -> GridMazeEnv:
    """Example 8.2: wall on row 3 over columns 0–7 (gap on the right); after ``change_after`` steps
    it covers columns 1–8 (gap on the left). Start (5, 3), goal (0, 8)."""
    return GridMazeEnv(
        6,
        9,
        _row_wall(3, range(0, 8)),
        (5, 3),
        (0, 8),
        change_after=change_after,
        walls_after=_row_wall(3, range(1, 9)),
    )


def shortcut_maze(change_after: int = 3000) -> GridMazeEnv:
    """Example 8.3: wall on row 3 over columns 1–8 (gap on the left); after ``change_after`` steps
    it covers columns 1–7, opening a shorter path on the right. Start (5, 3), goal (0, 8)."""
    return GridMazeEnv(
        6,
        9,
        _row_wall(3, range(1, 9)),
        (5, 3),
        (0, 8),
        change_after=change_after,
        walls_after=_row_wall(3, range(1, 8)),
    )
