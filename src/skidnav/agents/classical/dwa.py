"""The local controller: the dynamic window approach over the datasheet robot (or its
effective half track).

Fox, Burgard & Thrun (1997), "The dynamic window approach to collision avoidance", IEEE
Robotics & Automation Magazine 4(1): sample velocity commands, simulate each for a short
horizon, drop those that collide, and take the best of the rest by a weighted sum of heading,
clearance and speed. Here, as in Nav2's DWB controller, the heading term is progress along a
global cost-to-go (:mod:`skidnav.agents.classical.costmap`), so that the robot does not stop in
front of a wall the straight line to the goal runs into. Per control step, from the pose
(x, y, ψ):

1. **Samples** (:mod:`skidnav.agents.classical.window`): forward speeds v and yaw rates ψ̇;
   each (v, ψ̇) becomes wheel speeds by inverting the ICR model (ω_R = (v + c ψ̇)/r,
   ω_L = (v − c ψ̇)/r, c the datasheet's half track or the robot's effective one), scaled
   down together (the same curvature) until both lie within ± Ω. A robot that takes a
   command at once (the kinematic simulator) has every command the wheels allow as its
   window: v ∈ {0, …, v_max} (and one backwards speed), ψ̇ ∈ {−ψ̇_max, …, ψ̇_max}. A robot
   with acceleration limits has Fox et al.'s dynamic window: the commands reachable within a
   control period from its velocity, measured from its own poses.
2. **Rollout** (:func:`choose_command`): each command held for ``steps`` × ``step`` seconds
   through the ICR kinematics without slip (:func:`skidnav.robot.kinematics.body_velocities`
   with the datasheet's r and x_ICR and the controller's c; the exact constant-twist step
   :func:`skidnav.robot.kinematics.exact_step`), the footprint checked at every step against
   the occupied cells (the simulator's rule, :func:`skidnav.sim.footprint.collides`).
3. **Admissible** (Fox et al.'s admissible velocities): a command whose rollout meets no
   occupied cell before the robot, holding it for ``reaction_time`` t_r (a control period)
   and then braking at ``deceleration`` a_b, could stop: the first collision comes no sooner
   than t_r + |v| / a_b.
   **Score** (lower is better, in seconds) of the rollout's part before its first collision:
   D(end) / v_max + w_h |angle from the end heading to the route point ``lookahead`` ahead|
   + w_o max inflation cost along it + w_v (1 − v / v_max), D the cost-to-go of the end
   position (:func:`~skidnav.agents.classical.costmap.route_distance`); a rollout that enters
   the goal's cell ends there with D = 0 and no heading term (the episode would end).
4. **The least bad** when no command is admissible: the command whose first collision
   comes latest, then the one with the fewest colliding steps (out of a contact first),
   then the best score. Turning in place and backing up are among the samples, so this is
   how the robot gets out of a corner.
5. **Recovery** when the robot is stuck (as Nav2's and move_base's recovery behaviours back
   up or spin when the robot makes no progress; :class:`~skidnav.agents.classical.window.
   ProgressCheck`): for ``recovery_time``, among every command of the whole range that moves
   a wheel, admissible or not, the one whose rollout spends the fewest steps in contact, then
   whose first contact comes latest, then the best score. Standing still can be the best
   admissible command for ever (in a gap the padded footprint barely fits, every motion
   touches at once); this backs or turns the robot out of the pinch.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.agents.classical.costmap import route_distance
from skidnav.agents.mpc.costmap import CostMap, MapCosts, cell_centre, lookahead_waypoint
from skidnav.robot.kinematics import body_velocities, exact_step, wrap_angle
from skidnav.sim.footprint import collides
from skidnav.world.discretization import GridShape, cell_of


class Controller(NamedTuple):
    """The scalars of :func:`choose_command` (SI units).

    Attributes:
        wheel_radius: r [m]. half_track: c [m]. x_icr: the datasheet's ICR offset [m].
        steps: footprint checks per rollout. step: time between them [s].
        length, width: the padded footprint [m].
        max_speed: v_max [m/s], the speed term's scale.
        heading_weight: w_h [s/rad]. obstacle_weight: w_o [s]. speed_weight: w_v [s].
        deceleration: a_b [m/s²], the braking the admissibility assumes.
        reaction_time: t_r [s], how long a command holds before the next can brake.
    """

    wheel_radius: float
    half_track: float
    x_icr: float
    steps: int
    step: float
    length: float
    width: float
    max_speed: float
    heading_weight: float
    obstacle_weight: float
    speed_weight: float
    deceleration: float
    reaction_time: float


@inline_jit
def pose_score(
    x: float,
    y: float,
    heading: float,
    speed: float,
    worst: float,
    cost_map: CostMap,
    costs: MapCosts,
    grid: GridShape,
    controller: Controller,
) -> float:
    """The score [s] of a rollout that ends at the pose (x [m], y [m], heading [rad]), driven at
    ``speed`` [m/s] past cells of inflation cost at most ``worst`` (module doc, step 3)."""
    c = controller
    score = c.obstacle_weight * worst + c.speed_weight * (1.0 - speed / c.max_speed)
    aim_i, aim_j = lookahead_waypoint(x, y, cost_map, costs, grid)
    aim_x, aim_y = cell_centre(aim_i, aim_j, grid)
    if aim_x != x or aim_y != y:
        misalignment = abs(wrap_angle(math.atan2(aim_y - y, aim_x - x) - heading))
        score += c.heading_weight * misalignment
    return score + route_distance(x, y, cost_map, grid) / c.max_speed


@jit
def rollout(
    x: float,
    y: float,
    heading: float,
    left: float,
    right: float,
    occupied: np.ndarray,
    cost_map: CostMap,
    costs: MapCosts,
    grid: GridShape,
    controller: Controller,
) -> tuple[int, int, float]:
    """Steps 2 and 3 of the module doc for one command (ω_L, ω_R) [rad/s] from the pose
    (x [m], y [m], heading [rad]): (the first colliding step, 1-based, or ``steps`` + 1 for
    none; the number of colliding steps; the score [s] of its part before the first collision,
    0 plus the obstacle and speed terms if that part enters the goal's cell)."""
    c = controller
    v_x, v_y, yaw_rate = body_velocities(left, right, c.x_icr, c.wheel_radius, c.half_track)
    first, colliding, worst = c.steps + 1, 0, 0.0
    end_x, end_y, end_heading = x, y, heading
    for s in range(1, c.steps + 1):
        x, y, heading = exact_step(x, y, heading, v_x, v_y, yaw_rate, c.step)
        x = min(max(x, 0.0), grid.arena_width)  # the simulator clips the pose to the arena
        y = min(max(y, 0.0), grid.arena_height)
        if collides(occupied, grid, x, y, heading, c.length, c.width):
            colliding += 1
            first = min(first, s)
        if first <= s:
            continue  # only counting the collisions (the recovery's key)
        end_x, end_y, end_heading = x, y, heading
        i, j = cell_of(x, y, grid)
        worst = max(worst, cost_map.wall_probability[i, j])
        if i == costs.goal_i and j == costs.goal_j:  # the episode would end here
            return (
                first,
                colliding,
                c.obstacle_weight * worst + c.speed_weight * (1.0 - v_x / c.max_speed),
            )
    score = pose_score(end_x, end_y, end_heading, v_x, worst, cost_map, costs, grid, c)
    return first, colliding, score


@jit
def choose_command(
    x: float,
    y: float,
    heading: float,
    samples: np.ndarray,
    occupied: np.ndarray,
    cost_map: CostMap,
    costs: MapCosts,
    grid: GridShape,
    controller: Controller,
    recovering: bool = False,
) -> tuple[int, bool]:
    """(the index of the chosen command among ``samples`` float64 (K, 2) [rad/s], whether it
    was admissible) from the pose (x [m], y [m], heading [rad]) (module doc): the best-scoring
    admissible command, else the least bad (step 4); while ``recovering`` (step 5), the
    recovery's choice, admissible or not (``samples`` then those of the recovery). Ties go to
    the first."""
    c = controller
    best, best_score = -1, math.inf
    rescue, rescue_key, rescue_score = 0, -((c.steps + 2) ** 2), math.inf
    for k in range(samples.shape[0]):
        left, right = samples[k, 0], samples[k, 1]
        first, colliding, score = rollout(
            x, y, heading, left, right, occupied, cost_map, costs, grid, c
        )
        speed = abs(0.5 * c.wheel_radius * (left + right))
        if not recovering and (first - 1) * c.step >= c.reaction_time + speed / c.deceleration:
            if score < best_score:
                best, best_score = k, score
            continue
        # recovering: the fewest steps in contact, then the latest first one; else the latest
        # first collision, then the fewest colliding steps
        key = first - colliding * (c.steps + 2) if recovering else first * (c.steps + 2) - colliding
        if key > rescue_key or (key == rescue_key and score < rescue_score):
            rescue, rescue_key, rescue_score = k, key, score
    if best >= 0:
        return best, True
    return rescue, False
