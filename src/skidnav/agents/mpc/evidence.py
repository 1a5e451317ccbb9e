"""What one real step teaches the map: the free sub-steps' cells, a collision's wall cell and,
with feature observations, the lidar's readings (:mod:`skidnav.agents.mpc.laser`).

The kinematic log of a step holds the body twist (v_x, v_y, yaw_rate) the robot really had in
each free sub-step, so integrating it from the pose before the step with the robot's own scheme
(:func:`skidnav.sim.navigation.integrate`) retraces the step's path: each sub-step's cell gets a
pass. After a collision the robot stands at the last free position with the heading of the
colliding sub-step; the colliding sub-step itself is not logged. Its wall cell is guessed as
``dyna-kinematic`` guesses it (:func:`~skidnav.models.kinematic_prediction.collision_wall_cell`):
repeat the model's predicted sub-step — here the posterior-mean twist of the commanded wheel
speeds, from the retraced pose before the collision — until it leaves the current cell. A robot
with a footprint meets a wall with any part of its rectangle, away from the cell its centre
would enter, so its collisions are no evidence of a cell (as for the classical navigator): its
map is the lidar's.
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import jit
from skidnav.agents.mpc.costmap import CostMap, MapCosts, empty_cost_map, weigh_map
from skidnav.agents.mpc.dynamics import SampledDynamics, sampled_twist
from skidnav.agents.mpc.laser import record_scan
from skidnav.agents.mpc.lattice import (
    REPAIR_BUDGET,
    capped_values,
    cells_near,
    empty_lattice,
    goal_distances,
    lattice_reach,
    refresh_table,
    repair_distances,
)
from skidnav.models.kinematic_prediction import collision_wall_cell
from skidnav.robot.kinematics import N_ACTIONS
from skidnav.robot.params import KinematicConstants
from skidnav.sim.navigation import integrate
from skidnav.world.discretization import GridShape, cell_of, region_of

MAX_GUESS_SUBSTEPS = 1000
"""Most predicted sub-steps repeated to find a collision's wall cell: a cell crossed at a
hundredth of the top speed."""


@jit
def retrace_free_substeps(
    pose: np.ndarray,
    log: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
    hits: np.ndarray,
    ray_ends: np.ndarray,
    passes: np.ndarray,
) -> tuple[float, float, float, bool]:
    """Integrate the logged twists (columns 3–5 of ``log``, float64 (n, 6)) from ``pose``
    (x [m], y [m], heading [rad]) and add a pass to the cell of each sub-step (int64 ``passes``,
    in place). Returns the last pose and whether a cell with wall evidence (``hits`` or
    ``ray_ends``) got a pass (its wall probability changed)."""
    x, y, heading = pose[0], pose[1], pose[2]
    changed = False
    for k in range(log.shape[0]):
        x, y, heading = integrate(robot, x, y, heading, (log[k, 3], log[k, 4], log[k, 5]))
        i, j = cell_of(x, y, grid)
        passes[i, j] += 1
        if hits[i, j] > 0 or ray_ends[i, j] > 0:
            changed = True
    return x, y, heading, changed


@jit
def mean_twist(
    dynamics: SampledDynamics, region: int, omega_left: float, omega_right: float
) -> tuple[float, float, float]:
    """The posterior-mean body twist (v_x, v_y, yaw_rate) of the commanded wheel speeds."""
    return sampled_twist(
        dynamics,
        region,
        omega_left,
        omega_right,
        np.zeros((1, 5)),
        np.zeros((1, 1, 3)),
        0,
        0,
        0.0,
    )


class MapEvidence:
    """Hits, passes, ray ends and ray crossings of every cell and the cost map weighed from them
    (:mod:`skidnav.agents.mpc.costmap`), with the heading-aware lattice
    (:mod:`skidnav.agents.mpc.lattice`) when the terminal value is the states'.

    Args:
        costs: the cost map's scalars (goal cell, step length, weights).
        robot: the robot's timing, arena and scheme. grid: the discretization.
        lattice_robots: ``robot`` timed for each lattice duration (its ``substeps``), or empty
            for the cells' cost-to-go only.
        coefficients: the model's mean coefficients (n_regions, 8) the lattice predicts with.
    """

    def __init__(
        self,
        costs: MapCosts,
        robot: KinematicConstants,
        grid: GridShape,
        lattice_robots: list[KinematicConstants],
        coefficients: np.ndarray,
    ) -> None:
        self.costs, self.robot, self.grid = costs, robot, grid
        self.lattice_robots = lattice_robots
        self.hits = np.zeros((grid.n_x, grid.n_y), dtype=np.int64)
        """int64 (n_x, n_y): collisions whose guessed wall cell was each cell."""
        self.passes = np.zeros((grid.n_x, grid.n_y), dtype=np.int64)
        """int64 (n_x, n_y): free sub-steps that ended in each cell."""
        self.ray_ends = np.zeros((grid.n_x, grid.n_y), dtype=np.int64)
        """int64 (n_x, n_y): lidar readings shorter than the range limit that ended in each
        cell (:mod:`skidnav.agents.mpc.laser`)."""
        self.ray_crossings = np.zeros((grid.n_x, grid.n_y), dtype=np.int64)
        """int64 (n_x, n_y): lidar rays that crossed each cell before their reading."""
        n_states = grid.n_x * grid.n_y * grid.n_headings
        n_regions = coefficients.shape[0]
        steps = [lattice.substeps / robot.substeps for lattice in lattice_robots]
        action_steps = np.repeat(np.array(steps, dtype=np.float64), N_ACTIONS)
        self.lattice = empty_lattice(n_states if lattice_robots else 1, n_regions, action_steps)
        self.distance = np.zeros_like(self.lattice.value)
        """float64 (n_states,): each state's distance to the goal through the lattice, ∞ where
        it does not reach (:func:`~skidnav.agents.mpc.lattice.goal_distances`)."""
        self.supported = np.zeros_like(self.lattice.value)
        """float64 (n_states,): each state's best successor's distance plus the action's cost,
        kept for the repair (:func:`~skidnav.agents.mpc.lattice.repair_distances`)."""
        self.valued_probability = np.zeros((grid.n_x, grid.n_y))
        """float64 (n_x, n_y): the wall probabilities :attr:`distance` was computed with."""
        self.cost_map: CostMap = empty_cost_map(grid.n_x, grid.n_y, self.lattice.value)
        self.reweighs = 0
        """Times the cost map was recomputed."""
        self.table_refreshes = 0
        """Times the lattice's predictions were recomputed."""
        self.coefficients = coefficients
        """The coefficients (n_regions, 8) the lattice predicts with, as of the last change."""
        self.reweigh(coefficients, model_changed=True)

    def reweigh(self, coefficients: np.ndarray, model_changed: bool = False) -> None:
        """Recompute the cost map from the evidence: the wall probabilities, the cells' routes
        and, with a lattice, its predictions (when the blocked cells or, ``model_changed``, the
        model's ``coefficients`` changed: kept as :attr:`coefficients`) and its values."""
        if model_changed:
            self.coefficients = coefficients
        lethal_before = self.cost_map.lethal.copy()
        weigh_map(
            self.hits, self.passes, self.ray_ends, self.ray_crossings, self.costs, self.grid,
            self.cost_map,
        )  # fmt: skip
        self.reweighs += 1
        if not self.lattice_robots:
            return
        changed = lethal_before != self.cost_map.lethal
        if model_changed or changed.any():
            goal = (self.costs.goal_i, self.costs.goal_j)
            if model_changed:
                cells = np.ones_like(changed)
            else:
                longest = max(robot.substeps * robot.dt for robot in self.lattice_robots)
                reach = lattice_reach(self.lattice.velocities, longest, self.grid)
                cells = cells_near(changed, reach)
            refresh_table(
                self.lattice, coefficients, self.cost_map.lethal, goal, self.lattice_robots,
                self.grid, cells,
            )  # fmt: skip
            self.table_refreshes += 1
        self.update_values(refreshed=model_changed or bool(changed.any()))

    def update_values(self, refreshed: bool) -> int:
        """The lattice's values from the wall probabilities: a search over the whole lattice
        after its predictions were ``refreshed`` (or the costs changed with a refit), else a
        repair around the cells whose wall probability changed, the same values bit for bit
        (:func:`~skidnav.agents.mpc.lattice.repair_distances`; a whole search too where the
        repair would set more than :data:`~skidnav.agents.mpc.lattice.REPAIR_BUDGET` of the
        states). Returns the states whose distance was set (all of them after a search)."""
        costs, probability = self.costs, self.cost_map.wall_probability
        n_states = self.distance.shape[0]
        work = -1
        if not refreshed:
            work = repair_distances(
                self.lattice, self.valued_probability, probability, costs.goal_i, costs.goal_j,
                costs.collision_cost, self.grid, self.distance, self.supported,
                int(REPAIR_BUDGET * n_states),
            )  # fmt: skip
        if work < 0:
            goal_distances(
                self.lattice, probability, costs.goal_i, costs.goal_j, costs.collision_cost,
                self.grid, self.distance,
            )  # fmt: skip
            self.supported[:] = self.distance
            work = n_states
        self.valued_probability[:] = probability
        capped_values(self.distance, costs.blocked_cost, self.lattice.value)
        return work

    def record_step(
        self,
        pose: np.ndarray,
        commands: tuple[float, float],
        log: np.ndarray,
        collided: bool,
        dynamics: SampledDynamics,
    ) -> None:
        """Learn from one real step from ``pose`` (x [m], y [m], heading [rad]) commanding
        ``commands`` (ω_L, ω_R) [rad/s]: its free sub-steps ``log`` (n, 6) and whether it
        collided (module doc); the cost map is recomputed if the evidence changed it."""
        x, y, heading, changed = retrace_free_substeps(
            pose, log, self.robot, self.grid, self.hits, self.ray_ends, self.passes
        )
        if collided and self.robot.footprint_length == 0.0:  # module doc
            wall = self.guess_wall(x, y, heading, commands, dynamics)
            if wall is not None:
                self.hits[wall] += 1
                changed = True
        if changed:
            self.reweigh(self.coefficients)

    def record_readings(
        self, pose: np.ndarray, ranges: np.ndarray, max_range: float, field_of_view: float
    ) -> None:
        """Learn from the lidar readings ``ranges`` float64 (k,) [m] (range limit ``max_range``
        [m], spread over ``field_of_view`` [rad] as the env's features spread them) taken at
        ``pose`` (x [m], y [m], heading [rad]): the inverse sensor model of
        :mod:`skidnav.agents.mpc.laser`; the cost map is recomputed if a wall probability
        changed."""
        if ranges.shape[0] == 0:
            return
        changed = record_scan(
            pose[0], pose[1], pose[2], ranges, max_range, field_of_view, 1, self.grid,
            self.ray_ends, self.ray_crossings, self.hits,
        )  # fmt: skip
        if changed:
            self.reweigh(self.coefficients)

    def guess_wall(
        self,
        x: float,
        y: float,
        heading: float,
        commands: tuple[float, float],
        dynamics: SampledDynamics,
    ) -> tuple[int, int] | None:
        """The guessed wall cell of a collision from the pose before the colliding sub-step
        (module doc), or None when the predicted motion does not leave the cell."""
        region = int(region_of(x, y, self.grid))
        twist = mean_twist(dynamics, region, commands[0], commands[1])
        n_regions = dynamics.mean.shape[0]
        velocities = np.tile(np.array(twist, dtype=np.float64), (n_regions, 1, 1))
        # collision_wall_cell rewinds the heading by one predicted sub-step first
        ahead = heading + twist[2] * self.robot.dt
        repeats = self.robot._replace(substeps=MAX_GUESS_SUBSTEPS)
        i, j = collision_wall_cell(x, y, ahead, 0, velocities, repeats, self.grid)
        if i < 0 or (i, j) == (self.costs.goal_i, self.costs.goal_j):
            return None
        return int(i), int(j)
