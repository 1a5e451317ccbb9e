"""The collision rule of a robot with a footprint: its rectangle against the walls' discs.

A point robot (the thesis robot, footprint 0 × 0) collides when its position enters a wall cell.
A robot with a footprint (:attr:`skidnav.robot.params.RobotParams.footprint_length` ×
``footprint_width``, a rectangle along and across its heading, centred on its position) collides
when the rectangle touches the inscribed disc of a wall cell: the disc of radius min(w, h) / 2
[m] centred on the cell's centre (w × h the cell's size), the centre clipped to the arena as
:meth:`skidnav.world.discretization.Discretization.cell_centre` clips it. On the converted BARN
worlds a wall cell's disc is the benchmark's cylinder itself (radius 0.075 m on a 0.15 m
lattice, :mod:`skidnav.world.barn`), so the robot meets the obstacles the benchmark's robot meets;
on a wall of adjacent cells the discs touch, and no robot wider than nothing passes between them.

The test (:func:`rectangle_touches_disc`) is the distance from the disc's centre, in the robot's
frame, to the rectangle: the disc touches the rectangle when that distance is at most its
radius. Only the cells within the rectangle's circumradius plus the disc's radius are visited:
7 × 7 cells for the Jackal on BARN's 0.15 m cells.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.world.discretization import GridShape, cell_of, level_index


@inline_jit
def rectangle_touches_disc(
    u: float, v: float, half_length: float, half_width: float, radius: float
) -> bool:
    """Whether a disc of ``radius`` [m] centred at (u, v) [m] in a rectangle's frame touches the
    rectangle [−half_length, half_length] × [−half_width, half_width] [m].

    >>> touches = [rectangle_touches_disc(u, 0.0, 0.2, 0.1, 0.1) for u in (0.3, 0.31)]
    >>> touches
    [True, False]
    """
    du = max(abs(u) - half_length, 0.0)
    dv = max(abs(v) - half_width, 0.0)
    return du * du + dv * dv <= radius * radius


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
    """Whether a robot whose footprint is ``length`` × ``width`` [m] (along and across its
    heading), at position (x, y) [m] with heading ``heading`` [rad], touches the disc of a wall
    cell of ``occupancy`` (uint8 or bool (n_x, n_y), nonzero = wall) on the grid ``grid``
    (module doc)."""
    cell_w = grid.arena_width / (grid.n_x - 1)
    cell_h = grid.arena_height / (grid.n_y - 1)
    radius = 0.5 * min(cell_w, cell_h)
    half_length, half_width = 0.5 * length, 0.5 * width
    reach = math.sqrt(half_length * half_length + half_width * half_width) + radius
    i_low = level_index(x - reach, grid.arena_width, grid.n_x)
    i_high = level_index(x + reach, grid.arena_width, grid.n_x)
    j_low = level_index(y - reach, grid.arena_height, grid.n_y)
    j_high = level_index(y + reach, grid.arena_height, grid.n_y)
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    for i in range(i_low, i_high + 1):
        centre_x = min((i + 0.5) * cell_w, grid.arena_width)
        for j in range(j_low, j_high + 1):
            if occupancy[i, j] == 0:
                continue
            dx = centre_x - x
            dy = min((j + 0.5) * cell_h, grid.arena_height) - y
            u = cos_h * dx + sin_h * dy
            v = -sin_h * dx + cos_h * dy
            if rectangle_touches_disc(u, v, half_length, half_width, radius):
                return True
    return False


@jit
def collides(
    occupancy: np.ndarray,
    grid: GridShape,
    x: float,
    y: float,
    heading: float,
    length: float,
    width: float,
) -> bool:
    """The collision rule of a robot at pose (x [m], y [m], heading [rad]) among the walls
    ``occupancy`` (nonzero = wall) of ``grid``: with a footprint ``length`` × ``width`` [m] > 0,
    :func:`footprint_collides`; a point robot (0 × 0), when its position is in a wall cell."""
    if length > 0.0:
        return footprint_collides(occupancy, grid, x, y, heading, length, width)
    i, j = cell_of(x, y, grid)
    return bool(occupancy[i, j] != 0)
