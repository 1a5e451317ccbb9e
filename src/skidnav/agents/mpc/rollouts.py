"""The K × H rollouts of one MPPI step in one compiled batch: the cost of every sampled
wheel-speed sequence through each of its M draws of the learned kinematic model.

Rollout r (of K · M) drives sequence k = r // M through its own model draw. It starts at the
robot's pose and, for each control step t, holds the wheel speeds ``controls[k, t]`` (already
within the action bounds) for ``robot.substeps`` sub-steps of ``robot.dt``. Each sub-step reads
the slip region under the robot, takes the twist of the rollout's model draw
(:func:`~skidnav.agents.mpc.dynamics.sampled_twist`), integrates it with the robot's scheme
(explicit Euler or the exact constant-twist step, the pose clipped to the arena:
:func:`skidnav.sim.navigation.integrate`, as the simulator) and, on entering another cell, pays
the collision cost C · p of its wall probability; a blocked cell stops the motion for the rest
of the control step, as a wall stops the simulated robot (position of the last free sub-step,
heading of the colliding one). A robot with a footprint (``robot.footprint_length`` ×
``footprint_width`` > 0, padded by the agent) collides as the simulator's does
(:func:`skidnav.sim.footprint.footprint_collides`): a sub-step whose rectangle touches the
inscribed disc of a blocked cell costs C and stops the motion likewise, whether or not its
centre entered another cell — so a gap narrower than the robot is a wall to it. Each control
step costs 1 (time); a control step ending in the goal cell ends the rollout (the episode would
terminate) with no further cost. Within a
control step the twist changes only with the region (the wheels and the noise are the step's),
so it is computed again only when the rollout enters another region: the same numbers, 1.5×
faster at 1-s control steps of 10 sub-steps. A rollout that
does not reach the goal adds the terminal value of its last pose
(:func:`~skidnav.agents.mpc.costmap.terminal_value`). The planner reduces the M costs of a
sequence to one (their mean or their worst: :mod:`skidnav.agents.mpc.planner`).

The kernel draws nothing: the sequences' standard normals are drawn beforehand from the
agent's Generator (:mod:`skidnav.agents.mpc.planner`), so it gives the same numbers compiled
and interpreted (``NUMBA_DISABLE_JIT=1``). Every sum is a plain loop in a fixed order.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents.mpc.costmap import CostMap, MapCosts, terminal_value
from skidnav.agents.mpc.dynamics import SampledDynamics, sampled_twist
from skidnav.robot.params import KinematicConstants
from skidnav.sim.footprint import footprint_collides
from skidnav.sim.navigation import integrate
from skidnav.world.discretization import GridShape, cell_of, region_of


class RolloutDraws(NamedTuple):
    """The pre-drawn standard normals of one batch.

    Attributes:
        model: float64 (K · M, 5), each rollout's draw of the model's slopes (rollout r drives
            sequence r // M).
        noise: float64 (K · M, H, 3), each control step's draw of the model's noise (v_x, v_y,
            yaw rate).
        noise_scale: 1/√(sub-steps per control step); 0: no noise.
        per_sequence: M ≥ 1, the model draws of each sequence.
    """

    model: np.ndarray
    noise: np.ndarray
    noise_scale: float
    per_sequence: int


@jit
def rollout_costs(
    pose: np.ndarray,
    controls: np.ndarray,
    draws: RolloutDraws,
    dynamics: SampledDynamics,
    cost_map: CostMap,
    costs: MapCosts,
    robot: KinematicConstants,
    grid: GridShape,
    out: np.ndarray,
) -> None:
    """The cost of every rollout (module doc).

    Args:
        pose: float64 (3,) the start (x [m], y [m], heading [rad]).
        controls: float64 (K, H, 2) wheel speeds (ω_L, ω_R) [rad/s] of each control step.
        draws: the rollouts' standard normals. dynamics: the model's arrays.
        cost_map, costs: the learned map and the costs' scalars.
        robot, grid: the robot's timing, arena, scheme and footprint; the discretization.
        out: float64 (K · M,) receives the costs [control steps], M per sequence in a row.
    """
    for r in range(out.shape[0]):
        out[r] = sequence_cost(pose, controls, r, draws, dynamics, cost_map, costs, robot, grid)


@jit
def sequence_cost(
    pose: np.ndarray,
    controls: np.ndarray,
    r: int,
    draws: RolloutDraws,
    dynamics: SampledDynamics,
    cost_map: CostMap,
    costs: MapCosts,
    robot: KinematicConstants,
    grid: GridShape,
) -> float:
    """The cost of rollout ``r``: sequence r // M through model draw r (arguments as
    :func:`rollout_costs`)."""
    x, y, heading = pose[0], pose[1], pose[2]
    ci, cj = cell_of(x, y, grid)
    k = r // draws.per_sequence
    model = draws.model[r]
    cost = 0.0
    for t in range(controls.shape[1]):
        left, right = controls[k, t, 0], controls[k, t, 1]
        noise = draws.noise[r, t]
        twist_region, twist = -1, (0.0, 0.0, 0.0)
        for _ in range(robot.substeps):
            region = region_of(x, y, grid)
            if region != twist_region:  # the same wheels, noise and region: the same twist
                twist = sampled_twist(
                    dynamics, region, left, right, model, noise, draws.noise_scale
                )
                twist_region = region
            nx, ny, heading = integrate(robot, x, y, heading, twist)
            if robot.footprint_length > 0.0 and footprint_collides(
                cost_map.blocked, grid, nx, ny, heading, robot.footprint_length,
                robot.footprint_width,
            ):  # fmt: skip
                cost += costs.collision_cost
                break
            i, j = cell_of(nx, ny, grid)
            if i != ci or j != cj:
                cost += costs.collision_cost * cost_map.wall_probability[i, j]
                if cost_map.blocked[i, j]:
                    break
                ci, cj = i, j
            x, y = nx, ny
        cost += 1.0
        if ci == costs.goal_i and cj == costs.goal_j:
            return cost
    return cost + terminal_value(x, y, heading, cost_map, costs, grid)
