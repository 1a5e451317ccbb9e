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
changes.
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
            flags = EDGE_COLLIDES if outcome[s, a] == PREDICT_COLLISION else 0
            if s // n_headings != t // n_headings:
                flags += EDGE_CROSSES
            lattice.reverse_flags[edge] = flags


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
    value, n_headings = lattice.value, grid.n_headings
    start, sources = lattice.reverse_start, lattice.reverse_source
    actions, flags = lattice.reverse_action, lattice.reverse_flags
    value.fill(np.inf)
    settled = np.zeros(value.shape[0], dtype=np.bool_)
    queue = [(0.0, 0)]
    queue.pop()
    for heading in range(n_headings):
        goal_state = (goal_i * grid.n_y + goal_j) * n_headings + heading
        value[goal_state] = 0.0
        heapq.heappush(queue, (0.0, goal_state))
    while len(queue) > 0:
        distance, target = heapq.heappop(queue)
        if settled[target]:
            continue
        settled[target] = True
        target_cell = target // n_headings
        entering = (
            collision_cost * wall_probability[target_cell // grid.n_y, target_cell % grid.n_y]
        )
        for edge in range(start[target], start[target + 1]):
            source = sources[edge]
            cost = lattice.action_steps[actions[edge]]
            if flags[edge] & EDGE_COLLIDES:
                cost += collision_cost
            if flags[edge] & EDGE_CROSSES:
                cost += entering
            if distance + cost < value[source]:
                value[source] = distance + cost
                heapq.heappush(queue, (distance + cost, source))
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
