"""A tabular agent's Q table drawn over the map: the value, preferred heading and greedy action of
each cell (the run file's ``value_map``, ``heading_map`` and ``policy_map`` arrays)."""

from __future__ import annotations

import numpy as np

from skidnav.world.grid import GridMap


def value_maps(q: np.ndarray, grid_map: GridMap) -> tuple[np.ndarray, np.ndarray]:
    """(value, preferred heading bin) per cell from a Q table, each shape (n_x, n_y).

    value = max over headings and actions of Q; the preferred heading is the heading bin where that
    maximum is reached. Walls and cells whose Q entries were never changed (all equal) are
    NaN / −1.
    """
    n_x, n_y = grid_map.occupancy.shape
    per_cell = q.reshape(n_x, n_y, -1)
    per_heading = q.max(axis=1).reshape(n_x, n_y, -1)
    value = per_heading.max(axis=2)
    heading = per_heading.argmax(axis=2).astype(np.int64)
    blank = grid_map.occupancy | (per_cell.max(axis=2) == per_cell.min(axis=2))
    value[blank] = np.nan
    heading[blank] = -1
    return value, heading


def policy_map(q: np.ndarray, grid_map: GridMap, heading_index: int) -> np.ndarray:
    """Greedy action per cell at one heading bin, shape (n_x, n_y) int64.

    The action the agent's greedy policy takes with the robot in the cell at heading bin
    ``heading_index`` (the lowest index among the maxima, as ``TabularAgent.greedy_action``);
    −1 on walls and where the Q values of that state were never changed (all equal).

    >>> walls = np.zeros((3, 3), dtype=bool)
    >>> walls[2, 0] = True
    >>> q = np.zeros((3 * 3 * 2, 4))  # 3 × 3 cells, 2 heading bins, 4 actions
    >>> q[(0 * 3 + 0) * 2 + 1, 2] = 0.5  # cell (0, 0), heading bin 1: turn left is best
    >>> actions = policy_map(q, GridMap(walls, (0, 0), (1, 1)), 1)
    >>> int(actions[0, 0]), int(actions[0, 1]), int(actions[2, 0])  # learned, untouched, wall
    (2, -1, -1)
    """
    n_x, n_y = grid_map.occupancy.shape
    at_heading = q.reshape(n_x, n_y, -1, q.shape[1])[:, :, heading_index, :]
    action = at_heading.argmax(axis=2).astype(np.int64)
    action[grid_map.occupancy | (at_heading.max(axis=2) == at_heading.min(axis=2))] = -1
    result: np.ndarray = action
    return result
