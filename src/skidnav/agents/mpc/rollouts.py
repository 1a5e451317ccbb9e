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
agent's Generator (:mod:`skidnav.agents.mpc.sampling`), so it gives the same numbers compiled
and interpreted (``NUMBA_DISABLE_JIT=1``). Every sum is a plain loop in a fixed order. The
rollouts advance side by side, a block of them one control step at a time
(:data:`BLOCK`), each through the operations it would go through alone: the same costs as one
rollout after another, about 10 % faster (K = 256, H = 40).
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


BLOCK = 16
"""Rollouts advanced side by side, one control step of each in turn: the steps of different
rollouts do not wait on one another, so the processor overlaps them (a rollout alone is one
long chain of dependent operations), while the block's state and rows stay in the cache."""


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
    """The cost of every rollout (module doc), :data:`BLOCK` rollouts at a time, each through
    the same operations in the same order as alone.

    Args:
        pose: float64 (3,) the start (x [m], y [m], heading [rad]).
        controls: float64 (K, H, 2) wheel speeds (ω_L, ω_R) [rad/s] of each control step.
        draws: the rollouts' standard normals. dynamics: the model's arrays.
        cost_map, costs: the learned map and the costs' scalars.
        robot, grid: the robot's timing, arena, scheme and footprint; the discretization.
        out: float64 (K · M,) receives the costs [control steps], M per sequence in a row.
    """
    start_i, start_j = cell_of(pose[0], pose[1], grid)
    xs, ys, headings = np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK)
    cells_i, cells_j = np.empty(BLOCK, np.int64), np.empty(BLOCK, np.int64)
    running = np.empty(BLOCK, np.bool_)  # not yet in the goal cell
    for first in range(0, out.shape[0], BLOCK):
        size = min(BLOCK, out.shape[0] - first)
        for b in range(size):
            xs[b], ys[b], headings[b] = pose[0], pose[1], pose[2]
            cells_i[b], cells_j[b] = start_i, start_j
            running[b] = True
            out[first + b] = 0.0
        advance_block(
            first, size, (xs, ys, headings), (cells_i, cells_j), running, controls, draws,
            dynamics, cost_map, costs, robot, grid, out,
        )  # fmt: skip
        for b in range(size):
            if running[b]:
                out[first + b] += terminal_value(
                    xs[b], ys[b], headings[b], cost_map, costs, grid
                )  # fmt: skip


@jit
def advance_block(
    first: int,
    size: int,
    poses: tuple[np.ndarray, np.ndarray, np.ndarray],
    cells: tuple[np.ndarray, np.ndarray],
    running: np.ndarray,
    controls: np.ndarray,
    draws: RolloutDraws,
    dynamics: SampledDynamics,
    cost_map: CostMap,
    costs: MapCosts,
    robot: KinematicConstants,
    grid: GridShape,
    out: np.ndarray,
) -> None:
    """Rollouts ``first`` to ``first + size − 1`` through the horizon, control step by control
    step, each of them in turn (module doc): their poses in ``poses`` (x [m], y [m], heading
    [rad]: float64 (size,) each), cells in ``cells`` (i, j: int64 (size,) each), whether they
    are still out of the goal cell in ``running`` (size,) and their costs so far in ``out``
    (other arguments as :func:`rollout_costs`), all updated in place."""
    xs, ys, headings = poses
    cells_i, cells_j = cells
    for t in range(controls.shape[1]):
        for b in range(size):
            if not running[b]:
                continue
            r = first + b
            k = r // draws.per_sequence
            left, right = controls[k, t, 0], controls[k, t, 1]
            x, y, heading = xs[b], ys[b], headings[b]
            ci, cj = cells_i[b], cells_j[b]
            cost = out[r]
            twist_region, twist = -1, (0.0, 0.0, 0.0)
            for _ in range(robot.substeps):
                region = region_of(x, y, grid)
                if region != twist_region:  # the same wheels, noise and region: the same twist
                    twist = sampled_twist(
                        dynamics, region, left, right, draws.model, draws.noise, r, t,
                        draws.noise_scale,
                    )  # fmt: skip
                    twist_region = region
                nx, ny, heading = integrate(robot, x, y, heading, twist)
                if robot.footprint_length > 0.0 and footprint_collides(
                    cost_map.blocked, grid, nx, ny, heading, robot.footprint_length,
                    robot.footprint_width,
                ):  # fmt: skip
                    cost += costs.collision_cost
                    break
                i, j = cell_of(nx, ny, grid)
                if (i != ci) | (j != cj):  # entered another cell
                    cost += costs.collision_cost * cost_map.wall_probability[i, j]
                    if cost_map.blocked[i, j]:
                        break
                    ci, cj = i, j
                x, y = nx, ny
            out[r] = cost + 1.0
            xs[b], ys[b], headings[b] = x, y, heading
            cells_i[b], cells_j[b] = ci, cj
            running[b] = (ci != costs.goal_i) | (cj != costs.goal_j)
