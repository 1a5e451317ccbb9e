"""The learned occupancy as costs: wall evidence per cell, and a cost-to-go over the cells.

**Evidence (ours, as ``dyna-kinematic``'s,** :func:`skidnav.agents.planner_learning.
weigh_cell` **, with the lidar's).** The env says that an action collided, not which cell it hit;
slip makes a guess wrong now and then, so a collision is evidence, not a verdict. Every cell
(i, j) counts ``hits`` h, the collisions whose guessed wall cell it was, and ``passes`` f, the free
sub-steps that ended in it; with feature observations also ``ray_ends`` e, the lidar readings
that ended in it, and ``ray_crossings`` r, the rays that crossed it (the inverse sensor model of
:mod:`skidnav.agents.mpc.laser`). Its wall evidence is W = h + w e (w = ``ray_weight``), its free
evidence F = f + r + f₀ (f₀ pseudo-passes, ``free_prior``); its wall probability is
p = W / (W + F), the mean of a Beta(W, F) posterior (0 for a cell without wall evidence:
optimism for cells never seen), and it is *blocked* while W > F. A real wall's evidence only
grows (the robot is never inside it and no ray crosses it); a pass or a crossing ray undoes a
wrong guess. The goal cell is known free: never blocked, p = 0.

**The configuration space of a footprint** (:func:`clearance`, :func:`mark_lethal`; Latombe
1991, *Robot Motion Planning*, §4; as Nav2's inflation layer). Obstacles are the blocked cells'
inscribed discs, the simulator's footprint rule (:mod:`skidnav.sim.footprint`; on BARN's 0.15 m
cells the benchmark's cylinders). A cell's clearance d [m] is the distance from its centre to the
nearest disc; it is *lethal* when d ≤ r_in (``MapCosts.inscribed_radius``: half the footprint's
smaller side plus its padding): the robot's inscribed circle centred there touches the obstacle,
whatever its heading, so its rectangle does too. A point robot (r_in = 0) has the blocked cells as
its lethal ones. The routes below go around the lethal cells; the rollouts check the rectangle
itself against the blocked cells (:mod:`skidnav.agents.mpc.rollouts`). The classical navigator
(:mod:`skidnav.agents.classical.costmap`) inflates with the same two functions.

**Cost-to-go.** Dijkstra's algorithm (Dijkstra 1959) from the goal cell over the 8-connected
cells, a diagonal move only between two cells that are not lethal: entering cell c from a
neighbour costs the centre-to-centre distance over the distance the nominal robot covers in one
control step, plus C · p(c), plus ``blocked_cost`` if c is lethal. So the cost-to-go D is in
control steps at top speed (a lower bound of the time where the floor is slower, i.e.
optimistic), goes around every lethal cell while a way exists and stays finite everywhere. Each
cell's *waypoint* is the next cell of its route (the goal cell's is itself). The field is
recomputed when the map changes: a hit, or a pass through a cell with hits (p changes), or a
lidar reading.

**Terminal value** of a pose (x, y, ψ) (:func:`terminal_value`): by default the value of its
discrete state over the heading-aware lattice (:mod:`skidnav.agents.mpc.lattice`). Over the
cells only (``cost_to_go = "cells"``): follow the route's waypoints
from its cell to the first cell w at least ``lookahead`` metres along the route (or to
the goal); then D(w) + |(x, y) − centre(w)| / step, plus ``heading_weight`` × the time to turn,
at the nominal top yaw rate, from ψ to face the centre of w — or to back towards it, whichever
is the smaller turn (the robot drives backwards as fast as forwards). In the goal cell: 0. The
look-ahead (ours, as the look-ahead point of pure pursuit, Coulter 1992) steadies the aim, whose
bearing to the next cell swings by a radian as the robot crosses its own cell; measured along the
route, not in a straight line, so that it turns with the route around a wall found in front of
the robot instead of pointing through it. (Its benefit is not shown: on the free map the next
cell as the aim reaches the goal as fast, docs/agents/mppi-kinematic.md.)
"""

from __future__ import annotations

import heapq
import math
from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.robot.kinematics import wrap_angle
from skidnav.world.discretization import GridShape, cell_of, state_of


class CostMap(NamedTuple):
    """The learned map as the rollouts read it; every array (n_x, n_y) indexed [i, j].

    Attributes:
        wall_probability: float64 p of each cell (module doc).
        blocked: bool, the cells whose wall evidence outweighs their free evidence.
        lethal: bool, the cells the routes and the lattice treat as walls: the blocked cells
            dilated by the footprint's inscribed radius (module doc; a point robot's are its
            blocked cells). The classical navigator's lethal cells, of its occupied ones.
        cost_to_go: float64 D [control steps] to the goal.
        waypoint: int64 (n_x, n_y, 2), the next cell (i, j) of each cell's route.
        state_value: float64 (n_states,) the heading-aware cost-to-go [control steps] of each
            discrete state (:mod:`skidnav.agents.mpc.lattice`), or (1,) when the terminal value
            is the cells'.
    """

    wall_probability: np.ndarray
    blocked: np.ndarray
    lethal: np.ndarray
    cost_to_go: np.ndarray
    waypoint: np.ndarray
    state_value: np.ndarray


class MapCosts(NamedTuple):
    """The scalars of the cost map and the terminal value.

    Attributes:
        goal_i, goal_j: the goal cell.
        step_length: the nominal robot's distance in one control step at top speed [m].
        turn_step: its turn in one control step at top yaw rate [rad].
        collision_cost: C [cost units]. blocked_cost: extra cost of a lethal cell.
        free_prior: f₀ [passes]. ray_weight: w, the wall evidence of one lidar reading's end
            [collisions]. heading_weight: weight of the terminal turn time.
        lookahead: how far along the route the terminal value aims [m].
        use_states: the terminal value is the states' (:mod:`skidnav.agents.mpc.lattice`),
            else the cells'.
        inscribed_radius: r_in [m] of the footprint the lethal cells are dilated by (module
            doc); 0: a point robot, its lethal cells the blocked ones.
    """

    goal_i: int
    goal_j: int
    step_length: float
    turn_step: float
    collision_cost: float
    blocked_cost: float
    free_prior: float
    ray_weight: float
    heading_weight: float
    lookahead: float
    use_states: bool
    inscribed_radius: float = 0.0


def empty_cost_map(n_x: int, n_y: int, state_value: np.ndarray) -> CostMap:
    """A cost map of ``n_x`` × ``n_y`` cells with no evidence (:func:`weigh_map` fills it),
    holding ``state_value`` (the lattice's values, or a (1,) placeholder)."""
    return CostMap(
        np.zeros((n_x, n_y)), np.zeros((n_x, n_y), dtype=np.bool_),
        np.zeros((n_x, n_y), dtype=np.bool_), np.zeros((n_x, n_y)),
        np.zeros((n_x, n_y, 2), dtype=np.int64), state_value,
    )  # fmt: skip


@jit
def weigh_map(
    hits: np.ndarray,
    passes: np.ndarray,
    ray_ends: np.ndarray,
    ray_crossings: np.ndarray,
    costs: MapCosts,
    grid: GridShape,
    cost_map: CostMap,
) -> None:
    """Fill ``cost_map`` from the evidence ``hits``, ``passes``, ``ray_ends`` and
    ``ray_crossings`` (int64 (n_x, n_y)): the wall probabilities, the blocked cells, the
    lethal cells, then the cost-to-go and waypoints (module doc)."""
    for i in range(hits.shape[0]):
        for j in range(hits.shape[1]):
            wall = float(hits[i, j]) + costs.ray_weight * float(ray_ends[i, j])
            free = float(passes[i, j]) + float(ray_crossings[i, j]) + costs.free_prior
            goal = i == costs.goal_i and j == costs.goal_j
            known = wall > 0.0 and not goal
            cost_map.wall_probability[i, j] = wall / (wall + free) if known else 0.0
            cost_map.blocked[i, j] = known and wall > free
    if costs.inscribed_radius > 0.0:
        distances = clearance(cost_map.blocked, grid, costs.inscribed_radius)
        mark_lethal(distances, costs.inscribed_radius, cost_map.lethal)
        cost_map.lethal[costs.goal_i, costs.goal_j] = False  # known free, as it is not blocked
    else:
        cost_map.lethal[:, :] = cost_map.blocked
    route_costs(cost_map, costs, grid)


@jit
def clearance(occupied: np.ndarray, grid: GridShape, reach: float) -> np.ndarray:
    """float64 (n_x, n_y): each cell's clearance d [m] (module doc) from the nonzero cells of
    ``occupied`` (uint8 or bool (n_x, n_y)) on ``grid``, computed as far as ``reach`` [m]
    (+inf beyond it)."""
    n_x, n_y = occupied.shape
    width, height = grid.arena_width / (n_x - 1), grid.arena_height / (n_y - 1)
    radius = 0.5 * min(width, height)
    distances = np.full((n_x, n_y), np.inf)
    span_i, span_j = math.ceil((reach + radius) / width), math.ceil((reach + radius) / height)
    for i in range(n_x):
        for j in range(n_y):
            if occupied[i, j] == 0:
                continue
            x, y = cell_centre(i, j, grid)
            for ci in range(max(i - span_i, 0), min(i + span_i + 1, n_x)):
                for cj in range(max(j - span_j, 0), min(j + span_j + 1, n_y)):
                    cx, cy = cell_centre(ci, cj, grid)
                    distance = math.sqrt((cx - x) ** 2 + (cy - y) ** 2) - radius
                    distances[ci, cj] = min(distances[ci, cj], distance)
    return distances


@jit
def mark_lethal(distances: np.ndarray, inscribed_radius: float, lethal: np.ndarray) -> None:
    """Set ``lethal`` bool (n_x, n_y) to the cells whose clearance ``distances`` [m]
    (:func:`clearance`) is at most ``inscribed_radius`` [m] (module doc)."""
    for i in range(lethal.shape[0]):
        for j in range(lethal.shape[1]):
            lethal[i, j] = distances[i, j] <= inscribed_radius


@inline_jit
def _entering_cost(cost_map: CostMap, costs: MapCosts, i: int, j: int) -> float:
    """The evidence's cost of entering cell (i, j) in the cost-to-go."""
    cost: float = costs.collision_cost * cost_map.wall_probability[i, j]
    if cost_map.lethal[i, j]:
        cost += costs.blocked_cost
    return cost


@jit
def route_costs(cost_map: CostMap, costs: MapCosts, grid: GridShape) -> None:
    """Dijkstra from the goal cell (module doc): ``cost_map.cost_to_go`` and ``waypoint``."""
    n_x, n_y = cost_map.lethal.shape
    width, height = grid.arena_width / (grid.n_x - 1), grid.arena_height / (grid.n_y - 1)
    cost_map.cost_to_go.fill(np.inf)
    settled = np.zeros((n_x, n_y), dtype=np.bool_)
    cost_map.cost_to_go[costs.goal_i, costs.goal_j] = 0.0
    cost_map.waypoint[costs.goal_i, costs.goal_j, 0] = costs.goal_i
    cost_map.waypoint[costs.goal_i, costs.goal_j, 1] = costs.goal_j
    queue = [(0.0, costs.goal_i * n_y + costs.goal_j)]
    while len(queue) > 0:
        distance, index = heapq.heappop(queue)
        i, j = index // n_y, index % n_y
        if settled[i, j]:
            continue
        settled[i, j] = True
        entering = _entering_cost(cost_map, costs, i, j)  # to enter (i, j) from a neighbour
        for di in range(-1, 2):
            for dj in range(-1, 2):
                ni, nj = i + di, j + dj
                if (di == 0 and dj == 0) or not (0 <= ni < n_x and 0 <= nj < n_y):
                    continue
                if di != 0 and dj != 0 and (cost_map.lethal[ni, j] or cost_map.lethal[i, nj]):
                    continue  # no corner cutting past a lethal cell
                length = math.sqrt((di * width) ** 2 + (dj * height) ** 2) / costs.step_length
                candidate = distance + length + entering
                if candidate < cost_map.cost_to_go[ni, nj]:
                    cost_map.cost_to_go[ni, nj] = candidate
                    cost_map.waypoint[ni, nj, 0] = i
                    cost_map.waypoint[ni, nj, 1] = j
                    heapq.heappush(queue, (candidate, ni * n_y + nj))


@inline_jit
def cell_centre(i: int, j: int, grid: GridShape) -> tuple[float, float]:
    """Centre (x, y) [m] of cell (i, j), clipped to the arena
    (:meth:`~skidnav.world.discretization.Discretization.cell_centre`)."""
    x = (i + 0.5) * grid.arena_width / (grid.n_x - 1)
    y = (j + 0.5) * grid.arena_height / (grid.n_y - 1)
    return min(x, grid.arena_width), min(y, grid.arena_height)


@inline_jit
def lookahead_waypoint(
    x: float, y: float, cost_map: CostMap, costs: MapCosts, grid: GridShape
) -> tuple[int, int]:
    """The first cell of the route from (x, y) [m] at least ``lookahead`` [m] along the route
    (from (x, y) to the centre of its waypoint, then centre to centre), or the goal cell if the
    route ends sooner."""
    i, j = cell_of(x, y, grid)
    along = 0.0
    from_x, from_y = x, y
    for _ in range(grid.n_x * grid.n_y):
        if i == costs.goal_i and j == costs.goal_j:
            break
        i, j = cost_map.waypoint[i, j, 0], cost_map.waypoint[i, j, 1]
        centre_x, centre_y = cell_centre(i, j, grid)
        along += math.sqrt((centre_x - from_x) ** 2 + (centre_y - from_y) ** 2)
        if along >= costs.lookahead:
            break
        from_x, from_y = centre_x, centre_y
    return i, j


@inline_jit
def _corner(position: float, extent: float, levels: int) -> tuple[int, float]:
    """The lower of the two cell centres around ``position`` [m] on an axis of ``levels``
    cells over ``extent`` [m], and the position's fraction of the way to the upper one."""
    scaled = position / extent * (levels - 1) - 0.5
    lower = min(max(math.floor(scaled), 0), levels - 2)
    return lower, min(max(scaled - lower, 0.0), 1.0)


@inline_jit
def interpolated_state_value(
    x: float, y: float, heading: float, cost_map: CostMap, grid: GridShape
) -> float:
    """The states' value at a pose, interpolated trilinearly between the 8 states around it
    (cell centres in x and y, bin centres in heading, cyclic), leaving out the states of
    lethal cells (walls, whose values are not a route's); the value of the pose's own state
    when all 8 are lethal. Inlined: a compiled call per rollout that takes the cost map's
    arrays counts a reference of each in and out, 7 % of the rollouts' time (K = 256,
    H = 40)."""
    i0, fx = _corner(x, grid.arena_width, grid.n_x)
    j0, fy = _corner(y, grid.arena_height, grid.n_y)
    turns = (wrap_angle(heading) + math.pi) / (2.0 * math.pi) * grid.n_headings - 0.5
    k0 = math.floor(turns)
    fh = turns - k0
    total, weights = 0.0, 0.0
    for di in range(2):
        for dj in range(2):
            if cost_map.lethal[i0 + di, j0 + dj]:
                continue
            w_cell = (fx if di else 1.0 - fx) * (fy if dj else 1.0 - fy)
            for dk in range(2):
                k = (k0 + dk) % grid.n_headings
                weight = w_cell * (fh if dk else 1.0 - fh)
                state = ((i0 + di) * grid.n_y + j0 + dj) * grid.n_headings + k
                total += weight * cost_map.state_value[state]
                weights += weight
    if weights > 0.0:
        return total / weights
    own: float = cost_map.state_value[state_of(x, y, heading, grid)]
    return own


@inline_jit
def terminal_value(
    x: float, y: float, heading: float, cost_map: CostMap, costs: MapCosts, grid: GridShape
) -> float:
    """Cost-to-go [control steps] of the pose (x [m], y [m], heading [rad]) (module doc)."""
    i, j = cell_of(x, y, grid)
    if i == costs.goal_i and j == costs.goal_j:
        return 0.0
    if costs.use_states:
        return interpolated_state_value(x, y, heading, cost_map, grid)
    return route_value(x, y, heading, cost_map, costs, grid)


@jit
def route_value(
    x: float, y: float, heading: float, cost_map: CostMap, costs: MapCosts, grid: GridShape
) -> float:
    """The cells' cost-to-go [control steps] of the pose (x [m], y [m], heading [rad]) out of
    the goal cell (module doc). Not inlined into :func:`terminal_value`: the arrays it reads
    would be reference-counted at every terminal value of the states' too."""
    wi, wj = lookahead_waypoint(x, y, cost_map, costs, grid)
    target_x, target_y = cell_centre(wi, wj, grid)
    dx, dy = target_x - x, target_y - y
    value: float = cost_map.cost_to_go[wi, wj] + math.sqrt(dx * dx + dy * dy) / costs.step_length
    if costs.heading_weight > 0.0:
        turn = abs(wrap_angle(math.atan2(dy, dx) - heading))
        value += costs.heading_weight * min(turn, math.pi - turn) / costs.turn_step
    return value
