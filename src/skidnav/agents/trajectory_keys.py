"""The pairs swept by trajectory-prioritized planning: an episode's pairs with its loops erased,
and the spatial neighbourhood of the best trajectories (Alhawary (2020), ch. 7;
docs/agents/trajectory-prioritized.md). Pairs are keys s·n_actions + a, int64.
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import jit
from skidnav.models.multinomial_kernels import split_key
from skidnav.world.discretization import GridShape


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
