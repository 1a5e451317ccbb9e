"""The classical navigator's map and route: the laser's occupancy, the footprint's inflation, and
Dijkstra around a wall."""

from __future__ import annotations

import math

import numpy as np

from skidnav.agents.classical.costmap import (
    LETHAL_CELLS,
    new_cost_map,
    replan,
    route_settings,
    update_occupancy,
)
from skidnav.agents.mpc.laser import record_rays, record_scan
from skidnav.sim.lidar import LaserSpec
from skidnav.world.discretization import Discretization, cell_of

GRID = Discretization(n_x=11, n_y=11, arena_width=1.0, arena_height=1.0).grid_shape()
"""1 m × 1 m in cells of 0.1 m (10 × 10 cells and the border lines)."""


def test_inflation_is_lethal_within_the_inscribed_radius_then_decays_to_zero() -> None:
    occupied = np.zeros((11, 11), dtype=np.uint8)
    occupied[5, 5] = 1  # a disc of radius 0.05 m at (0.55, 0.55)
    cost_map = new_cost_map(11, 11)
    replan(occupied, GRID, cost_map, route_settings((0, 0), GRID, 1.0, 0.5), 0.1, 0.3, 10.0)
    lethal = cost_map.lethal
    # clearance: centre distance − 0.05; lethal up to 0.1 m, i.e. the cell and its 8 neighbours
    assert lethal[4:7, 4:7].all() and lethal.sum() == 9
    two_away = cost_map.wall_probability[7, 5]  # clearance 0.2 − 0.05 = 0.15 m
    assert math.isclose(two_away, math.exp(-10.0 * (0.15 - 0.1)), rel_tol=1e-12)
    assert cost_map.wall_probability[9, 5] == 0.0  # clearance 0.35 m > 0.3 m


def test_dijkstra_goes_around_a_wall_and_never_through_a_lethal_cell() -> None:
    """A wall across the arena at x = 0.5 m with a gap at the top: from the left half the route
    to a goal on the right climbs to the gap."""
    occupied = np.zeros((11, 11), dtype=np.uint8)
    occupied[5, :8] = 1
    cost_map = new_cost_map(11, 11)
    goal = (8, 1)
    replan(occupied, GRID, cost_map, route_settings(goal, GRID, 0.0, 0.5), 0.0, 0.0, 0.0)
    assert cost_map.cost_to_go[goal] == 0.0
    start = (2, 1)
    assert 1.2 < cost_map.cost_to_go[start] < 2.0  # up to the gap and down: ~1.5 m, not 0.6 m
    cell, visited = start, [start]
    while cell != goal:
        cell = tuple(int(v) for v in cost_map.waypoint[cell])
        visited.append(cell)
    assert all(not cost_map.lethal[c] for c in visited) and max(j for _, j in visited) >= 8
    walled = np.ones((11, 11), dtype=np.uint8)  # walled in: finite, through lethal cells
    walled[goal] = walled[start] = 0
    replan(walled, GRID, cost_map, route_settings(goal, GRID, 0.0, 0.5), 0.0, 0.0, 0.0)
    assert LETHAL_CELLS * 0.1 < cost_map.cost_to_go[start] < np.inf


def test_the_laser_marks_the_cells_it_ends_in_and_clears_those_it_crosses() -> None:
    """A 90° scan of 3 rays from (0.55, 0.55) heading +y: rays along 45°, 90° and 135°; the
    middle one ends at 0.25 m, where it enters the cell above (the simulated lidar stops where a
    ray enters a wall cell), the others reach the range limit and mark nothing."""
    spec = LaserSpec(rays=3, max_range=0.4, field_of_view=math.pi / 2)
    np.testing.assert_allclose(
        spec.angles(math.pi / 2), [math.pi / 4, math.pi / 2, 3 * math.pi / 4]
    )
    ends = np.zeros((11, 11), dtype=np.int64)
    crossings = np.zeros((11, 11), dtype=np.int64)
    ranges = np.array([0.4, 0.25, 0.4])
    record_scan(
        0.55,
        0.55,
        math.pi / 2,
        ranges,
        0.4,
        spec.field_of_view,
        1,
        GRID,
        ends,
        crossings,
        np.zeros_like(ends),
    )
    occupied = np.zeros((11, 11), dtype=np.uint8)
    assert update_occupancy(ends, crossings, occupied)
    assert occupied.sum() == 1 and occupied[cell_of(0.55, 0.8 + 1e-6, GRID)] == 1
    assert crossings[5, 6] == 1 and crossings[5, 7] == 1  # the middle ray's free cells
    # a full turn read with stride 1 is record_rays, number for number
    full = np.array([0.3, 0.25, 0.2, 0.35])
    counts = [np.zeros((11, 11), dtype=np.int64) for _ in range(4)]
    record_rays(0.55, 0.55, 0.3, full, 0.4, GRID, counts[0], counts[1], counts[0] * 0)
    record_scan(
        0.55, 0.55, 0.3, full, 0.4, 2 * math.pi, 1, GRID, counts[2], counts[3], counts[0] * 0
    )
    np.testing.assert_array_equal(counts[0], counts[2])
    np.testing.assert_array_equal(counts[1], counts[3])
    # crossings that outnumber the ends clear a cell again
    crossings[cell_of(0.55, 0.8 + 1e-6, GRID)] += 2
    assert update_occupancy(ends, crossings, occupied) and occupied.sum() == 0
