"""The footprint's collision rule, as the navigator checks it against the cells it knows occupied.

The rule is the simulator's: a rectangle of ``length`` along the heading and ``width`` across it,
centred on the robot's position, collides when it touches the inscribed disc (radius half the
smaller cell side, centred on the cell's centre clipped to the arena) of an occupied cell. On
BARN's 0.15 m cells that disc is the benchmark's cylinder (radius 0.075 m). A footprint of
0 × 0 is a point, which touches the disc of its own cell only.

This module stands in for the simulator's own kernel until it is available
(``skidnav.sim.footprint.footprint_collides``, of the same signature): the controller imports
:func:`footprint_collides` from here, and that one import line is all that changes.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import jit
from skidnav.world.discretization import GridShape, level_index


@jit
def footprint_collides(
    occupancy: np.ndarray,
    grid: GridShape,
    x: float,
    y: float,
    heading: float,
    length: float,
    width: float,
) -> bool:
    """Whether the ``length`` × ``width`` [m] rectangle at (x [m], y [m]) along ``heading``
    [rad] touches the disc of an occupied cell of ``occupancy`` (uint8 or bool (n_x, n_y),
    nonzero = occupied) on ``grid`` (module doc).

    >>> from skidnav.world.discretization import Discretization
    >>> grid = Discretization(n_x=11, n_y=11, arena_width=1.0, arena_height=1.0).grid_shape()
    >>> walls = np.zeros((11, 11), dtype=np.uint8); walls[5, 5] = 1  # disc at (0.55, 0.55), r 0.05
    >>> footprint_collides(walls, grid, 0.31, 0.55, 0.0, 0.4, 0.2)  # front edge at 0.51 m
    True
    >>> footprint_collides(walls, grid, 0.29, 0.55, 0.0, 0.4, 0.2)
    False
    """
    cell_width = grid.arena_width / (grid.n_x - 1)
    cell_height = grid.arena_height / (grid.n_y - 1)
    radius = 0.5 * min(cell_width, cell_height)
    half_length, half_width = 0.5 * length, 0.5 * width
    reach = math.sqrt(half_length * half_length + half_width * half_width) + radius
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    for i in range(
        level_index(x - reach, grid.arena_width, grid.n_x),
        level_index(x + reach, grid.arena_width, grid.n_x) + 1,
    ):
        dx = min((i + 0.5) * cell_width, grid.arena_width) - x
        for j in range(
            level_index(y - reach, grid.arena_height, grid.n_y),
            level_index(y + reach, grid.arena_height, grid.n_y) + 1,
        ):
            if occupancy[i, j] == 0:
                continue
            dy = min((j + 0.5) * cell_height, grid.arena_height) - y
            along = max(abs(cos_h * dx + sin_h * dy) - half_length, 0.0)
            across = max(abs(cos_h * dy - sin_h * dx) - half_width, 0.0)
            if along * along + across * across <= radius * radius:
                return True
    return False
