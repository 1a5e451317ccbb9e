"""A heading-aware cost-to-go: Dijkstra over the discrete states (cells × heading bins) through
the learned kinematic model's predictions of the four thesis actions.

Why not the cells alone (:func:`~skidnav.agents.mpc.costmap.route_costs`): a skid-steer robot
turns about a pivot x_ICR ahead of its centre, so a turn in place swings the centre on a circle
of radius x_ICR (5 cm, two cells): in front of a wall the robot must back up before it turns, and
a turn that looks free on the cells runs into the wall beside it. A 2-s horizon cannot find such a
manoeuvre by sampling, and a value over the cells does not ask for it (measured:
docs/agents/mppi-kinematic.md). A value over the states does: from each state's cell centre and
heading-bin centre, the learned model predicts the pose after each of the four actions (forward,
backward, turn left, turn right at ± Ω), each held for each of the ``lattice_durations``
(:func:`~skidnav.models.kinematic_prediction.prediction_table`: the same prediction as
``dyna-kinematic``'s table, the lethal cells as its walls — the blocked ones, dilated by a
footprint's inscribed radius, :mod:`skidnav.agents.mpc.costmap` —, the goal cell as its goal, and
one rule more: a sub-step entering a cell diagonally between two lethal cells that meet at a
corner collides, :func:`~skidnav.world.discretization.squeezes_between_walls`, a gap of no width
that the simulator's rule, checking only the cell a sub-step ends in, lets a point through;
docs/agents/mppi-kinematic.md, "A squeeze between two walls, traced"), and
Dijkstra's algorithm from the goal's states over these transitions gives V(s), the fewest control
steps to the goal through the graph. An action costs its control steps, a predicted collision C
more, and entering another cell C · p of its wall probability, as in the rollouts. Two durations
(ours), 0.5 s and 1 s by default: at top speed a 0.5-s action moves about one cell (1.9 cm) or
turns one heading bin (18°), so the values of neighbouring states differ by a step and their
interpolation slopes smoothly; with 1-s actions alone (1.5 cells) the values came in plateaus two
cells wide, flat for a 2-s horizon (measured: docs/agents/mppi-kinematic.md). The 1-s actions
keep the graph connected where the floor is slow: a 0.5-s action at half speed does not leave
its cell. A state that
does not reach the goal through the graph (or one inside a lethal cell, which predicts itself)
gets the largest finite value plus ``blocked_cost``, so every value is finite.

The terminal value of a pose is V interpolated between the states around it
(:func:`~skidnav.agents.mpc.costmap.interpolated_state_value`; 0 in the goal cell). The
predictions, and with them the reverse graph the search walks (the edges into each state), are
recomputed when the model's fit changes (all of them) or a cell becomes or stops being lethal
(those of the cells within one action's reach of it); the values whenever a wall probability
changes: searched again after the predictions changed, else repaired around the cells whose
probability changed (:func:`repair_distances`, the same values bit for bit).
"""

from __future__ import annotations

import heapq
from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.models.kinematic_prediction import (
    PREDICT_COLLISION,
    action_velocities,
    predict_action,
)
from skidnav.robot.kinematics import N_ACTIONS
from skidnav.robot.params import KinematicConstants
from skidnav.world.discretization import GridShape, state_of


class Lattice(NamedTuple):
    """The state graph and its values: the four actions for each of D durations, action
    ``4 d + a`` being action a held for duration d.

    Attributes:
        velocities: float64 (n_regions, 4, 3) the model's mean body velocities of the four
            actions (v_x [m/s], v_y [m/s], yaw_rate [rad/s]).
        next_state: int32 (n_states, 4 D) predicted next state of each state and action.
        outcome: int8 (n_states, 4 D) the outcome codes of
            :mod:`skidnav.models.kinematic_prediction`.
        action_steps: float64 (4 D,) each action's duration [control steps].
        value: float64 (n_states,) V [control steps].
        reverse_start: int64 (n_states + 1,) the reverse graph of ``next_state``, kept with it
            (:func:`reverse_graph`): the edges into state t are ``reverse_start[t]`` …
            ``reverse_start[t + 1]`` − 1 of the three arrays below.
        reverse_source: int64 (n_states · 4 D,) each edge's source state s.
        reverse_action: int8 (n_states · 4 D,) each edge's action a.
        reverse_flags: int8 (n_states · 4 D,) :data:`EDGE_COLLIDES` if its outcome is a
            predicted collision, plus :data:`EDGE_CROSSES` if s lies in another cell than t.
    """

    velocities: np.ndarray
    next_state: np.ndarray
    outcome: np.ndarray
    action_steps: np.ndarray
    value: np.ndarray
    reverse_start: np.ndarray
    reverse_source: np.ndarray
    reverse_action: np.ndarray
    reverse_flags: np.ndarray


REPAIR_BUDGET = 0.25
"""The share of the lattice's states a repair of the values may set before it gives way to a
whole search (:func:`repair_distances`): per state it sets, a repair costs about four times
what a search does (a state whose distance rises is set twice, and the states before it search
their edges again; measured 1.1 µs against 0.28 µs in a maze run at 1-s actions), so a change
that moves the values of more than a quarter of the lattice is cheaper searched, and a repair
that stops there costs at most about twice a search (docs/agents/mppi-kinematic.md, "The
values' repair")."""
EDGE_COLLIDES = 1
"""Flag of a reverse edge whose action is predicted to collide (it costs C more)."""
EDGE_CROSSES = 2
"""Flag of a reverse edge that enters another cell (it costs C · p of that cell more)."""


def empty_lattice(n_states: int, n_regions: int, action_steps: np.ndarray) -> Lattice:
    """A lattice of ``n_states`` states whose actions last ``action_steps`` (4 D,) control
    steps, nothing predicted yet."""
    n_actions = action_steps.shape[0]
    n_edges = n_states * n_actions
    return Lattice(
        np.zeros((n_regions, N_ACTIONS, 3)), np.zeros((n_states, n_actions), dtype=np.int32),
        np.zeros((n_states, n_actions), dtype=np.int8), np.asarray(action_steps, np.float64),
        np.zeros(n_states), np.zeros(n_states + 1, dtype=np.int64),
        np.zeros(n_edges, dtype=np.int64), np.zeros(n_edges, dtype=np.int8),
        np.zeros(n_edges, dtype=np.int8),
    )  # fmt: skip


def refresh_table(
    lattice: Lattice,
    coefficients: np.ndarray,
    walls: np.ndarray,
    goal: tuple[int, int],
    robots: list[KinematicConstants],
    grid: GridShape,
    cells: np.ndarray,
) -> None:
    """Predict the actions of every state of the cells ``cells`` (bool (n_x, n_y)) (module
    doc) with the mean ``coefficients`` (n_regions, 8), ``robots[d]`` timed for duration d (its
    ``substeps``), the cells ``walls`` bool (n_x, n_y) (the lethal ones) as walls."""
    action_velocities(coefficients, robots[0].wheel_speed, lattice.velocities)
    goals = np.zeros_like(walls)
    goals[goal] = True
    for duration, robot in enumerate(robots):
        robust_predictions(
            lattice.velocities, walls, goals, robot, grid, cells, N_ACTIONS * duration,
            lattice.next_state, lattice.outcome,
        )  # fmt: skip
    reverse_graph(lattice, grid.n_headings)


@jit
def robust_predictions(
    velocities: np.ndarray,
    walls: np.ndarray,
    goals: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
    cells: np.ndarray,
    first_column: int,
    next_state: np.ndarray,
    outcome: np.ndarray,
) -> None:
    """The four actions of every state of the cells ``cells`` into columns ``first_column``
    … + 3 of ``next_state`` and ``outcome``: the next state predicted from the cell's centre
    and the heading bin's centre (:func:`~skidnav.models.kinematic_prediction.predict_action`),
    and a collision if the prediction from the centre *or from any of the four points a quarter
    cell from it* runs into a wall (module doc). States of a wall cell predict themselves with
    a collision."""
    width, height = grid.arena_width / (grid.n_x - 1), grid.arena_height / (grid.n_y - 1)
    bin_width = 2.0 * np.pi / grid.n_headings
    for i in range(grid.n_x):
        for j in range(grid.n_y):
            if not cells[i, j]:
                continue
            for h in range(grid.n_headings):
                state = (i * grid.n_y + j) * grid.n_headings + h
                heading = -np.pi + (h + 0.5) * bin_width
                for action in range(N_ACTIONS):
                    column = first_column + action
                    if walls[i, j]:
                        next_state[state, column], outcome[state, column] = state, PREDICT_COLLISION
                        continue
                    x, y, turned, code = predict_action(
                        (i + 0.5) * width, (j + 0.5) * height, heading, action, velocities,
                        walls, goals, robot, grid, True,
                    )  # fmt: skip
                    for corner in range(4 if code != PREDICT_COLLISION else 0):
                        dx = (0.25 if corner % 2 == 0 else -0.25) * width
                        dy = (0.25 if corner < 2 else -0.25) * height
                        if predict_action(
                            (i + 0.5) * width + dx, (j + 0.5) * height + dy, heading, action,
                            velocities, walls, goals, robot, grid, True,
                        )[3] == PREDICT_COLLISION:  # fmt: skip
                            code = PREDICT_COLLISION
                            break
                    next_state[state, column] = state_of(x, y, turned, grid)
                    outcome[state, column] = code


def cells_near(changed: np.ndarray, radius: int) -> np.ndarray:
    """bool (n_x, n_y): the cells within ``radius`` cells (in i and in j) of a cell of
    ``changed``."""
    near = np.zeros_like(changed)
    for i, j in np.argwhere(changed):
        near[max(i - radius, 0) : i + radius + 1, max(j - radius, 0) : j + radius + 1] = True
    return near


@jit
def reverse_graph(lattice: Lattice, n_headings: int) -> None:
    """The reverse graph of ``lattice.next_state`` (n_states, n_actions) into its ``reverse_*``
    arrays: the edges (s, a) into each state t in increasing order of s · n_actions + a, with
    their flags (:class:`Lattice`; ``n_headings`` states per cell). Kept with the predictions,
    so that :func:`state_values`, run whenever a wall probability changes, reads each state's
    edges in one sequence instead of building them again."""
    next_state, outcome = lattice.next_state, lattice.outcome
    start = lattice.reverse_start
    n_states, n_actions = next_state.shape
    start.fill(0)
    for s in range(n_states):
        for a in range(n_actions):
            start[next_state[s, a] + 1] += 1
    for t in range(n_states):
        start[t + 1] += start[t]
    filled = start[:-1].copy()
    for s in range(n_states):
        for a in range(n_actions):
            t = next_state[s, a]
            edge = filled[t]
            filled[t] += 1
            lattice.reverse_source[edge] = s
            lattice.reverse_action[edge] = a
            lattice.reverse_flags[edge] = _edge_flags(outcome[s, a], s, t, n_headings)


@jit
def state_values(
    lattice: Lattice,
    wall_probability: np.ndarray,
    goal_i: int,
    goal_j: int,
    collision_cost: float,
    blocked_cost: float,
    grid: GridShape,
) -> None:
    """Dijkstra from the goal cell's states over the lattice (module doc) into
    ``lattice.value``."""
    goal_distances(lattice, wall_probability, goal_i, goal_j, collision_cost, grid, lattice.value)
    _cap_unreached(lattice.value, blocked_cost)


@jit
def goal_distances(
    lattice: Lattice,
    wall_probability: np.ndarray,
    goal_i: int,
    goal_j: int,
    collision_cost: float,
    grid: GridShape,
    distance: np.ndarray,
) -> None:
    """Dijkstra from the goal cell's states over the lattice into ``distance`` float64
    (n_states,): each state's fewest control steps to the goal (module doc), ∞ where the graph
    does not reach it."""
    n_headings = grid.n_headings
    start, sources = lattice.reverse_start, lattice.reverse_source
    distance.fill(np.inf)
    settled = np.zeros(distance.shape[0], dtype=np.bool_)
    queue = [(0.0, 0)]
    queue.pop()
    for heading in range(n_headings):
        goal_state = (goal_i * grid.n_y + goal_j) * n_headings + heading
        distance[goal_state] = 0.0
        heapq.heappush(queue, (0.0, goal_state))
    while len(queue) > 0:
        reached, target = heapq.heappop(queue)
        if settled[target]:
            continue
        settled[target] = True
        entering = _entering(target, wall_probability, collision_cost, grid)
        for edge in range(start[target], start[target + 1]):
            source = sources[edge]
            cost = _edge_cost(lattice, edge, collision_cost, entering)
            if reached + cost < distance[source]:
                distance[source] = reached + cost
                heapq.heappush(queue, (reached + cost, source))


@jit
def _entering(
    state: int, wall_probability: np.ndarray, collision_cost: float, grid: GridShape
) -> float:
    """C · p of the cell of ``state``: the cost of entering it from another cell."""
    cell = state // grid.n_headings
    return collision_cost * float(wall_probability[cell // grid.n_y, cell % grid.n_y])


@jit
def _edge_cost(lattice: Lattice, edge: int, collision_cost: float, entering: float) -> float:
    """The cost of the reverse ``edge`` (module doc): :func:`_action_cost` of its action and
    flags."""
    action = lattice.reverse_action[edge]
    return _action_cost(
        lattice.action_steps[action], lattice.reverse_flags[edge], collision_cost, entering
    )


@jit
def _action_cost(steps: float, flags: int, collision_cost: float, entering: float) -> float:
    """An action's cost (module doc): its ``steps`` [control steps], plus C if ``flags`` say
    it is predicted to collide, plus ``entering`` (:func:`_entering` of its next state) if it
    enters another cell; summed in this order wherever an action is costed."""
    cost = steps
    if flags & EDGE_COLLIDES:
        cost += collision_cost
    if flags & EDGE_CROSSES:
        cost += entering
    return cost


@jit
def _edge_flags(code: int, source: int, target: int, n_headings: int) -> int:
    """The flags of the action from state ``source`` to ``target`` with outcome ``code``:
    :data:`EDGE_COLLIDES` if a predicted collision, plus :data:`EDGE_CROSSES` if the two
    states lie in different cells."""
    flags = EDGE_COLLIDES if code == PREDICT_COLLISION else 0
    if source // n_headings != target // n_headings:
        flags += EDGE_CROSSES
    return flags


@jit
def _best_successor(
    lattice: Lattice,
    state: int,
    wall_probability: np.ndarray,
    collision_cost: float,
    grid: GridShape,
    distance: np.ndarray,
) -> float:
    """min over the actions of ``state`` of (the distance of its next state + the action's
    cost), each sum rounded as :func:`goal_distances` rounds it (∞ if none reaches)."""
    best = np.inf
    for action in range(lattice.next_state.shape[1]):
        target = lattice.next_state[state, action]
        if not distance[target] < np.inf:
            continue
        flags = _edge_flags(lattice.outcome[state, action], state, target, grid.n_headings)
        entering = _entering(target, wall_probability, collision_cost, grid)
        cost = _action_cost(lattice.action_steps[action], flags, collision_cost, entering)
        best = min(best, distance[target] + cost)
    return best


@jit
def repair_distances(
    lattice: Lattice,
    before: np.ndarray,
    after: np.ndarray,
    goal_i: int,
    goal_j: int,
    collision_cost: float,
    grid: GridShape,
    distance: np.ndarray,
    supported: np.ndarray,
    budget: int,
) -> int:
    """:func:`goal_distances` again after the wall probabilities changed from ``before`` to
    ``after`` (float64 (n_x, n_y)), the graph unchanged, repairing only the states the change
    reaches: Lifelong Planning A* without a heuristic (Koenig, Likhachev & Furcy 2004,
    "Lifelong Planning A*"; the dynamic shortest paths of Ramalingam & Reps 1996).
    ``distance`` (n_states,) holds the distances before the change, ``supported`` (n_states,)
    each state's :func:`_best_successor` over them (0 in the goal cell): equal to ``distance``
    after a search, and again after the repair. A change of one edge's term updates its
    source's ``supported`` in O(1) when the term falls, and by :func:`_best_successor` only when
    the term that was the least rises.

    The result is :func:`goal_distances`'s bit for bit: with every edge's cost positive, the
    distances d(s) = min over the edges of the rounded d(next) + cost (0 in the goal cell, ∞
    where the graph does not reach) have one solution in floating point, and both algorithms
    end at it (tested on random changes). Returns the states whose distance was set (the
    repair's work), or −1 once more than ``budget`` were: the repair then stops, ``distance``
    and ``supported`` half repaired, for a whole search to replace (:data:`REPAIR_BUDGET`)."""
    goal_cell = goal_i * grid.n_y + goal_j
    queue = [(0.0, 0)]
    queue.pop()
    _changed_cells(
        lattice, before, after, goal_cell, collision_cost, grid, distance, supported, queue
    )
    work = 0
    while len(queue) > 0:
        key, state = heapq.heappop(queue)
        if supported[state] == distance[state] or key != min(supported[state], distance[state]):
            continue  # consistent, or an entry superseded by a later push
        work += 1
        if work > budget:
            return -1
        reached = distance[state]
        if supported[state] < reached:
            distance[state] = supported[state]
        else:
            distance[state] = np.inf
            if supported[state] < np.inf:
                heapq.heappush(queue, (supported[state], state))
        entering = _entering(state, after, collision_cost, grid)
        _terms_into(
            lattice, state, reached, distance[state], entering, entering, goal_cell, after,
            collision_cost, grid, distance, supported, queue,
        )  # fmt: skip
    return work


@jit
def _changed_cells(
    lattice: Lattice,
    before: np.ndarray,
    after: np.ndarray,
    goal_cell: int,
    collision_cost: float,
    grid: GridShape,
    distance: np.ndarray,
    supported: np.ndarray,
    queue: list[tuple[float, int]],
) -> None:
    """The start of :func:`repair_distances`: the edges into each cell whose wall probability
    went from ``before`` to ``after`` change their terms (:func:`_terms_into`)."""
    n_headings = grid.n_headings
    for i in range(grid.n_x):
        for j in range(grid.n_y):
            if before[i, j] == after[i, j]:
                continue
            cell = i * grid.n_y + j
            was, now = collision_cost * before[i, j], collision_cost * after[i, j]
            for target in range(cell * n_headings, (cell + 1) * n_headings):
                if distance[target] < np.inf:
                    reached = distance[target]
                    _terms_into(
                        lattice, target, reached, reached, was, now, goal_cell, after,
                        collision_cost, grid, distance, supported, queue,
                    )  # fmt: skip


@jit
def _terms_into(
    lattice: Lattice,
    target: int,
    reached_was: float,
    reached_now: float,
    entering_was: float,
    entering_now: float,
    goal_cell: int,
    wall_probability: np.ndarray,
    collision_cost: float,
    grid: GridShape,
    distance: np.ndarray,
    supported: np.ndarray,
    queue: list[tuple[float, int]],
) -> None:
    """The terms of the edges into ``target`` changed: its distance from ``reached_was`` to
    ``reached_now``, the cost of entering its cell from ``entering_was`` to ``entering_now``;
    :func:`_retermed` for each edge's source outside the goal cell."""
    for edge in range(lattice.reverse_start[target], lattice.reverse_start[target + 1]):
        source = lattice.reverse_source[edge]
        if source // grid.n_headings == goal_cell:
            continue
        old = reached_was + _edge_cost(lattice, edge, collision_cost, entering_was)
        new = reached_now + _edge_cost(lattice, edge, collision_cost, entering_now)
        _retermed(
            lattice, source, old, new, wall_probability, collision_cost, grid, distance,
            supported, queue,
        )  # fmt: skip


@jit
def _retermed(
    lattice: Lattice,
    state: int,
    old: float,
    new: float,
    wall_probability: np.ndarray,
    collision_cost: float,
    grid: GridShape,
    distance: np.ndarray,
    supported: np.ndarray,
    queue: list[tuple[float, int]],
) -> None:
    """One term of ``state``'s :func:`_best_successor` went from ``old`` to ``new``: keep
    ``supported[state]`` the least term (lower it, or search its edges again if the least rose)
    and queue ``state`` if it now differs from its distance."""
    if new < supported[state]:
        supported[state] = new
    elif new > old and old == supported[state]:
        supported[state] = _best_successor(
            lattice, state, wall_probability, collision_cost, grid, distance
        )
    else:
        return
    if supported[state] != distance[state]:
        heapq.heappush(queue, (min(supported[state], distance[state]), state))


@jit
def capped_values(distance: np.ndarray, blocked_cost: float, value: np.ndarray) -> None:
    """``distance`` (n_states,) into ``value`` (n_states,), the states that do not reach the
    goal at the largest finite distance plus ``blocked_cost`` (module doc)."""
    value[:] = distance
    _cap_unreached(value, blocked_cost)


@jit
def _cap_unreached(value: np.ndarray, blocked_cost: float) -> None:
    """Replace the values of states that do not reach the goal (∞) by the largest finite value
    plus ``blocked_cost``."""
    largest = 0.0
    for s in range(value.shape[0]):
        if value[s] < np.inf:
            largest = max(largest, value[s])
    for s in range(value.shape[0]):
        if not value[s] < np.inf:
            value[s] = largest + blocked_cost


def lattice_reach(velocities: np.ndarray, longest: float, grid: GridShape) -> int:
    """The radius [cells, in i and j] around a cell that became or stopped being lethal whose
    states' predictions must be redone: the farthest the body centre moves in the longest
    lattice action (``longest`` [s]) at the fastest of ``velocities`` (n_regions, 4, 3), from a
    point a quarter cell off a cell's centre, in cells, plus one."""
    speed = float(np.hypot(velocities[..., 0], velocities[..., 1]).max())
    width, height = grid.arena_width / (grid.n_x - 1), grid.arena_height / (grid.n_y - 1)
    reach = speed * longest + 0.25 * float(np.hypot(width, height))
    return int(np.ceil(reach / min(width, height))) + 1
