"""What the lidar readings of one observation teach the map: an inverse sensor model in evidence
counts.

Occupancy-grid mapping (Thrun, Burgard & Fox 2005, *Probabilistic Robotics*, §9.2, Table 9.2,
the inverse range sensor model): a reading z along a ray says that the cells the ray crossed
before z are free and, when z is shorter than the range limit, that the cell where it ended is
occupied; a reading at the limit says nothing of the cell beyond. Thrun et al. add log-odds
l_free or l_occ per reading; here each cell counts them — ``ray_crossings`` r, the rays that
crossed it, and ``ray_ends`` e, the readings that ended in it — and the map weighs them with the
collisions and passes as pseudo-counts of a Beta posterior (:mod:`skidnav.agents.mpc.costmap`),
the counting form of the same update (a reading adds a fixed amount of evidence whatever the
cell's state before). Cells no ray reached keep no evidence: optimistic, as before.

Ray k of an observation with k_max rays starts at the robot's position along ψ + 2π k / k_max,
the layout of the env's lidar (:func:`skidnav.sim.lidar.lidar_ranges`); a laser of a narrower
field of view φ spreads them over the sector centred on the heading, both edges included,
ψ − φ/2 + φ k / (k_max − 1) (:func:`skidnav.sim.lidar.lidar_scan`, :func:`record_scan`).
The crossed cells are found by stepping along the ray ``RAY_STEP`` of a cell at a time up to
the reading, each cell counted once per ray; the end cell is the one just past the reading (the
simulated lidar stops where a ray enters a wall cell or meets the arena's border, so the point
``END_NUDGE`` metres beyond lies in that cell).
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.world.discretization import GridShape, cell_of

RAY_STEP = 0.25
"""Step along a ray [cells, of the smaller side] between the points whose cells it crosses."""
END_NUDGE = 1e-6
"""How far past a reading [m] its end cell is looked up: into the wall cell the reading met."""


@jit
def record_rays(
    x: float,
    y: float,
    heading: float,
    ranges: np.ndarray,
    max_range: float,
    grid: GridShape,
    ray_ends: np.ndarray,
    ray_crossings: np.ndarray,
    hits: np.ndarray,
) -> bool:
    """Add the evidence of the readings ``ranges`` float64 (k,) [m] taken at the pose
    (x [m], y [m], heading [rad]) with range limit ``max_range`` [m] to ``ray_ends`` and
    ``ray_crossings`` (int64 (n_x, n_y), in place; module doc), the rays over a full turn.
    Returns whether a cell with wall evidence (a hit or a reading's end) was crossed, or a
    reading ended anywhere: whether a wall probability changed."""
    return record_scan(
        x, y, heading, ranges, max_range, 2.0 * math.pi, 1, grid, ray_ends, ray_crossings, hits
    )


@inline_jit
def ray_angle(heading: float, k: int, n_rays: int, field_of_view: float) -> float:
    """Direction [rad] of ray k of ``n_rays`` over ``field_of_view`` [rad] centred on
    ``heading`` [rad] (module doc; the layout of :func:`skidnav.sim.lidar.lidar_scan`)."""
    if field_of_view >= 2.0 * math.pi:
        return heading + 2.0 * math.pi * k / n_rays
    if n_rays == 1:
        return heading
    return heading + field_of_view * (k / (n_rays - 1) - 0.5)


@jit
def record_scan(
    x: float,
    y: float,
    heading: float,
    ranges: np.ndarray,
    max_range: float,
    field_of_view: float,
    stride: int,
    grid: GridShape,
    ray_ends: np.ndarray,
    ray_crossings: np.ndarray,
    hits: np.ndarray,
) -> bool:
    """:func:`record_rays` of a laser of any ``field_of_view`` [rad] in (0, 2π] (module doc),
    reading only every ``stride``-th ray (rays 0, s, 2s, …; 1: all of them). Returns whether a
    cell with wall evidence was crossed or a reading ended anywhere."""
    width, height = grid.arena_width / (grid.n_x - 1), grid.arena_height / (grid.n_y - 1)
    step = RAY_STEP * min(width, height)
    n_rays = ranges.shape[0]
    changed = False
    for k in range(0, n_rays, stride):
        angle = ray_angle(heading, k, n_rays, field_of_view)
        dx, dy = math.cos(angle), math.sin(angle)
        reading = min(max(ranges[k], 0.0), max_range)
        last_i, last_j = cell_of(x, y, grid)
        travelled = step
        while travelled < reading - END_NUDGE:
            i, j = cell_of(x + travelled * dx, y + travelled * dy, grid)
            if i != last_i or j != last_j:
                ray_crossings[i, j] += 1
                changed = changed or hits[i, j] > 0 or ray_ends[i, j] > 0
                last_i, last_j = i, j
            travelled += step
        if reading < max_range:
            beyond = reading + END_NUDGE
            i, j = cell_of(x + beyond * dx, y + beyond * dy, grid)
            ray_ends[i, j] += 1
            changed = True
    return changed
