"""The navigator's map: occupancy from the laser, inflated by the footprint, and the route to
the goal over it.

1. **Occupancy** (Thrun, Burgard & Fox 2005, *Probabilistic Robotics*, §9.2, the inverse range
   sensor model; the project's one implementation, :func:`skidnav.agents.mpc.laser.record_scan`).
   Every reading counts a crossing in the cells its ray crossed and, short of the range limit,
   an end in the cell where it stopped. A cell is *occupied* while its ends outnumber its
   crossings; a cell no ray reached is free (optimistic), as the cells rays crossed.
2. **Inflation** (the configuration space of a footprint; as Nav2's inflation layer, whose
   costs decay exponentially away from the obstacles). Each cell's clearance d [m] is the
   distance from its centre to the nearest occupied cell's inscribed disc (the footprint rule's
   disc, :mod:`skidnav.sim.footprint`), as far as ``inflation_radius``. A cell is
   *lethal* when d ≤ r_in, the footprint's inscribed radius (half its smaller side, plus the
   padding): a robot centred there touches the obstacle whatever its heading (the configuration
   space of :mod:`skidnav.agents.mpc.costmap`, which ``mppi-kinematic`` plans in too). Beyond,
   its inflation cost is exp(−k (d − r_in)) ∈ (0, 1] up to d = ``inflation_radius``, then 0.
3. **Route** (Dijkstra 1959): the cost-to-go D [m] of every cell to the goal's cell over the
   8-connected cells, :func:`skidnav.agents.mpc.costmap.route_costs`, the project's one
   Dijkstra: entering a cell costs the centre-to-centre length, plus ``inflation_weight`` ×
   its inflation cost cell sides, plus :data:`LETHAL_CELLS` cell sides if it is lethal, and
   no diagonal move cuts past a lethal cell. It reads the inflation cost where
   ``mppi-kinematic`` keeps a wall probability and the lethal cells as its own lethal ones
   (:class:`~skidnav.agents.mpc.costmap.CostMap`); D stays finite, so a goal walled in still
   has a gradient.

The route is recomputed only when the occupied cells (or the goal's cell) change: a reading
that only confirms free space changes nothing.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import jit
from skidnav.agents.mpc.costmap import (
    CostMap,
    MapCosts,
    cell_centre,
    clearance,
    empty_cost_map,
    mark_lethal,
    route_costs,
)
from skidnav.world.discretization import GridShape, cell_of

LETHAL_CELLS = 10_000.0
"""Extra cost of entering a lethal cell [cell sides]: any detour of fewer cells is preferred."""


def new_cost_map(n_x: int, n_y: int) -> CostMap:
    """An empty map of ``n_x`` × ``n_y`` cells: nothing occupied, no inflation."""
    return empty_cost_map(n_x, n_y, np.zeros(1))


def route_settings(
    goal: tuple[int, int], grid: GridShape, inflation_weight: float, lookahead: float
) -> MapCosts:
    """The scalars :func:`~skidnav.agents.mpc.costmap.route_costs` and
    :func:`~skidnav.agents.mpc.costmap.lookahead_waypoint` read, for costs in metres: a step of
    1 m; ``inflation_weight`` [cell sides] as the cost of a probability 1 and
    :data:`LETHAL_CELLS` as the blocked cost, in metres on ``grid``; the look-ahead [m]."""
    side = min(grid.arena_width / (grid.n_x - 1), grid.arena_height / (grid.n_y - 1))
    return MapCosts(
        goal_i=int(goal[0]), goal_j=int(goal[1]), step_length=1.0, turn_step=1.0,
        collision_cost=float(inflation_weight) * side, blocked_cost=LETHAL_CELLS * side,
        free_prior=0.0,
        ray_weight=0.0, heading_weight=0.0, lookahead=float(lookahead), use_states=False,
    )  # fmt: skip


@jit
def update_occupancy(ray_ends: np.ndarray, ray_crossings: np.ndarray, occupied: np.ndarray) -> bool:
    """Set ``occupied`` uint8 (n_x, n_y) to the cells whose ends outnumber their crossings
    (int64 (n_x, n_y) each; module doc, step 1); whether any cell changed."""
    changed = False
    for i in range(occupied.shape[0]):
        for j in range(occupied.shape[1]):
            now = 1 if ray_ends[i, j] > ray_crossings[i, j] else 0
            if now != occupied[i, j]:
                occupied[i, j] = now
                changed = True
    return changed


@jit
def inflate(
    occupied: np.ndarray,
    grid: GridShape,
    inscribed_radius: float,
    inflation_radius: float,
    cost_scaling: float,
    cost_map: CostMap,
) -> None:
    """Fill ``cost_map.lethal`` with the lethal cells of ``occupied`` uint8 (n_x, n_y) and
    ``cost_map.wall_probability`` with their inflation costs (module doc, step 2; the clearance
    and the lethal rule are the configuration space of :mod:`skidnav.agents.mpc.costmap`), for a
    footprint of inscribed radius ``inscribed_radius`` [m], costs reaching ``inflation_radius``
    [m] from the obstacles with the decay ``cost_scaling`` [1/m]; ``cost_map.blocked`` holds
    the occupied cells."""
    distances = clearance(occupied, grid, max(inscribed_radius, inflation_radius))
    mark_lethal(distances, inscribed_radius, cost_map.lethal)
    for i in range(occupied.shape[0]):
        for j in range(occupied.shape[1]):
            cost_map.blocked[i, j] = occupied[i, j] != 0
            d = distances[i, j]
            if d <= inscribed_radius:
                cost_map.wall_probability[i, j] = 1.0
            elif d <= inflation_radius:
                cost_map.wall_probability[i, j] = math.exp(-cost_scaling * (d - inscribed_radius))
            else:
                cost_map.wall_probability[i, j] = 0.0


@jit
def route_distance(x: float, y: float, cost_map: CostMap, grid: GridShape) -> float:
    """The cost-to-go [m] of the position (x, y) [m]: D of the next cell on its cell's route,
    plus the straight distance to that cell's centre (continuous in the position within a
    cell, where D alone is a step)."""
    i, j = cell_of(x, y, grid)
    next_i, next_j = cost_map.waypoint[i, j, 0], cost_map.waypoint[i, j, 1]
    centre_x, centre_y = cell_centre(next_i, next_j, grid)
    distance = math.sqrt((centre_x - x) ** 2 + (centre_y - y) ** 2)
    value: float = cost_map.cost_to_go[next_i, next_j] + distance
    return value


def replan(
    occupied: np.ndarray,
    grid: GridShape,
    cost_map: CostMap,
    costs: MapCosts,
    inscribed_radius: float,
    inflation_radius: float,
    cost_scaling: float,
) -> None:
    """Steps 2 and 3 of the module doc: inflate ``occupied`` into ``cost_map``, then its
    cost-to-go and waypoints to the goal cell of ``costs``."""
    inflate(occupied, grid, inscribed_radius, inflation_radius, cost_scaling, cost_map)
    route_costs(cost_map, costs, grid)
