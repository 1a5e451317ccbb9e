"""The navigation MDP as compiled kernels: one action of the skid-steer robot, with slip, collisions
and reward (Alhawary (2020), App. A.1; docs/simulator.md). The Gymnasium env (through
:func:`skidnav.sim.task.step_arrays`), the batch simulator, the fused trainers all call
:func:`transition`, and the simulated robot server (:func:`skidnav.sim.task.drive_substep`) its
sub-step, so there is one implementation of the dynamics.

One action = ``substeps`` sub-steps of ``dt`` seconds. In each sub-step (:func:`substep`), with the
robot in coarse region ρ at simulated time t:

1. η = η₀[ρ] · max(0, 1 + A sin(2π t / P + φ[ρ])) (the slip field, possibly drifting);
2. each wheel's commanded speed loses u·η in magnitude, u from the ``noise`` array of uniforms in
   [0, 1) (two per sub-step: left, right). Callers fill ``noise`` with ``rng.random(2·substeps)``
   (the env) or the same draws one by one inside a compiled loop (the trainers): same stream,
   same numbers, and no Generator crosses the Python/numba boundary on every step;
3. the ICR model with the region's x_ICR[ρ], effective wheel radius r[ρ] and half track c[ρ] (the
   robot's own unless the floor was calibrated, :mod:`skidnav.robot.floors`) gives (v_x, v_y,
   yaw_rate); the robot's integrator (explicit Euler or the exact constant-twist step,
   ``RobotParams.integrator``) advances the pose, which is clipped to the arena;
4. if the new position lies in a wall cell (for a robot with a footprint: if its rectangle touches a
   wall cell's disc, :mod:`skidnav.sim.footprint`) the motion stops: the position stays at the last
   free
   sub-step, the heading of the colliding sub-step is kept, and the action is a collision;
   otherwise the sub-step is logged as (ρ, ω_L_cmd, ω_R_cmd, v_x, v_y, yaw_rate).

Reward (thesis, :func:`action_reward`, also the real-time loop's): +10 and termination if the
robot ends the action in the goal cell (or within the goal disc of a task that has one,
:func:`at_goal`); −10 after a collision; otherwise −1 − 10·var, var being
the wheel-speed variance of the region where the action ends: the slip field's true η²/12
(default) or, with ``observed_variance``, the running sample variance of wheel speeds measured
during forward actions in that region (the thesis's choice).

Cost (:func:`action_cost`): minus the reward without the goal bonus. An action costs 1 + 10·var
(a free step), 10 (a collision), and the action that reaches the goal costs what a free step
ending there would: the +10 is the same on every path that reaches the goal, so it changes no
choice between them. An episode that reaches the goal has return 10 + c_g − (its summed cost),
c_g the goal action's cost (the same on every path on a stationary floor), so the summed cost
ranks paths as the undiscounted return does; on a floor with var ≈ 0 it is the number of
actions plus 9 per collision, and on a slippery floor a longer path may cost less.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.robot.kinematics import (
    apply_slip,
    body_velocities,
    commanded_wheel_speeds,
    pose_step,
)
from skidnav.robot.params import KinematicConstants
from skidnav.sim.footprint import collides, footprint_collides
from skidnav.world.discretization import (
    GridShape,
    cell_of,
    region_of,
    state_of,
)

LOG_COLUMNS = ("region", "omega_left_cmd", "omega_right_cmd", "v_x", "v_y", "yaw_rate")
"""Columns of the kinematic log: one row per free sub-step."""


class RewardScheme(NamedTuple):
    """Reward constants (thesis values by default)."""

    goal: float = 10.0
    collision: float = -10.0
    step: float = -1.0
    variance_weight: float = 10.0
    observed_variance: bool = False


class NavigationTask(NamedTuple):
    """Everything the kernels need to simulate the navigation MDP (numba-friendly).

    Attributes:
        robot: kinematic constants (SI units).
        grid: discretization levels and arena size.
        occupancy: uint8 (n_x, n_y), 1 = wall.
        goal_i, goal_j: goal cell.
        goal_x, goal_y, goal_radius: a goal disc (centre [m], radius [m]); with a radius > 0 an
            action terminates the episode when it ends within it (the BARN rule,
            :mod:`skidnav.world.barn`), with 0 (the default) when it ends in the goal cell.
        eta: base wheel-speed loss scale per flat region, shape (n_regions,) [rad/s].
        x_icr: ICR offset per flat region, shape (n_regions,) [m].
        wheel_radius, half_track: effective wheel radius r and half track c per flat region,
            shape (n_regions,) [m].
        drift_phase: drift phase per flat region, shape (n_regions,) [rad].
        drift_amplitude: relative drift amplitude A (0 = stationary slip).
        drift_period: drift period P [s].
        rewards: the reward scheme.
        variance_stats: float64 (n_regions, 3) running (count, mean, M2) of wheel speeds measured
            in forward actions; updated in place by :func:`transition` when the reward uses the
            observed variance.
    """

    robot: KinematicConstants
    grid: GridShape
    occupancy: np.ndarray
    goal_i: int
    goal_j: int
    goal_x: float
    goal_y: float
    goal_radius: float
    eta: np.ndarray
    x_icr: np.ndarray
    wheel_radius: np.ndarray
    half_track: np.ndarray
    drift_phase: np.ndarray
    drift_amplitude: float
    drift_period: float
    rewards: RewardScheme
    variance_stats: np.ndarray


class Outcome(NamedTuple):
    """Result of one action: reward, termination, collision, logged rows, last wheel speeds
    [rad/s], the flat state and slip region where the action ended, and its cost
    (:func:`action_cost`)."""

    reward: float
    terminated: bool
    collided: bool
    n_logged: int
    omega_left: float
    omega_right: float
    state: int
    region: int
    cost: float


@inline_jit
def drifted_slip(eta: float, phase: float, amplitude: float, period: float, time: float) -> float:
    """η [rad/s] scaled by the drift factor max(0, 1 + A sin(2π t / P + φ)) at time ``time`` [s]
    (unchanged when the amplitude A is 0); ``phase`` φ [rad], ``period`` P [s].

    Scalars only: the branch of an inlined helper that reads ``task`` arrays keeps numba from
    pruning their reference counts, which cost about as much as the rest of a sub-step.
    """
    if amplitude > 0.0:
        eta *= max(0.0, 1.0 + amplitude * math.sin(2.0 * math.pi * time / period + phase))
    return eta


@inline_jit
def slip_scale(task: NavigationTask, region: int, time: float) -> float:
    """η of ``region`` at simulated time ``time`` [s] (rad/s)."""
    return drifted_slip(
        task.eta[region], task.drift_phase[region], task.drift_amplitude, task.drift_period, time
    )


@inline_jit
def region_slip(
    task: NavigationTask, region: int, time: float
) -> tuple[float, float, float, float]:
    """The floor of ``region`` at simulated time ``time`` [s] as :func:`substep` takes it: η
    [rad/s], x_ICR [m], effective wheel radius r [m] and half track c [m]."""
    return (
        slip_scale(task, region, time), task.x_icr[region], task.wheel_radius[region],
        task.half_track[region],
    )  # fmt: skip


@inline_jit
def _record_wheel_speed(stats: np.ndarray, region: int, value: float) -> None:
    """Welford update of the running wheel-speed statistics of one region."""
    stats[region, 0] += 1.0
    delta = value - stats[region, 1]
    stats[region, 1] += delta / stats[region, 0]
    stats[region, 2] += delta * (value - stats[region, 1])


@inline_jit
def region_variance(task: NavigationTask, region: int, time: float) -> float:
    """Wheel-speed variance of a region [rad²/s²]: observed or true η²/12 (see module doc)."""
    if task.rewards.observed_variance:
        count = task.variance_stats[region, 0]
        return task.variance_stats[region, 2] / (count - 1.0) if count > 1.0 else 0.0
    eta = slip_scale(task, region, time)
    return eta * eta / 12.0


@inline_jit
def integrate(
    robot: KinematicConstants,
    x: float,
    y: float,
    heading: float,
    twist: tuple[float, float, float],
) -> tuple[float, float, float]:
    """One sub-step of the robot's integrator (Euler or exact, ``robot.dt`` seconds) from pose
    (x [m], y [m], heading [rad]) with body twist (v_x, v_y [m/s], yaw_rate [rad/s]); the new
    position is clipped to the arena [0, W] × [0, H]."""
    v_x, v_y, yaw_rate = twist
    new_x, new_y, new_heading = pose_step(
        x, y, heading, v_x, v_y, yaw_rate, robot.dt, robot.exact_integration
    )
    new_x = min(max(new_x, 0.0), robot.arena_width)
    new_y = min(max(new_y, 0.0), robot.arena_height)
    return new_x, new_y, new_heading


@inline_jit
def _log_row(
    log: np.ndarray,
    row: int,
    region: int,
    commands: tuple[float, float],
    twist: tuple[float, float, float],
) -> None:
    """Write one free sub-step as row ``row`` of the kinematic log (see :data:`LOG_COLUMNS`)."""
    log[row, 0] = region
    log[row, 1] = commands[0]
    log[row, 2] = commands[1]
    log[row, 3] = twist[0]
    log[row, 4] = twist[1]
    log[row, 5] = twist[2]


@inline_jit
def substep(
    robot: KinematicConstants,
    slip: tuple[float, float, float, float],
    pose: tuple[float, float, float],
    commands: tuple[float, float],
    noise: tuple[float, float],
) -> tuple[float, float, float, float, float, tuple[float, float, float]]:
    """One sub-step of ``robot.dt`` seconds (steps 2–3 of the module doc) from ``pose`` (x [m],
    y [m], heading [rad]) on a floor whose region there has ``slip`` (η [rad/s] at this time,
    x_ICR [m], effective r and c [m]: :func:`region_slip`), driven by the wheel speeds
    ``commands`` (ω_L, ω_R) [rad/s]; ``noise``: (left, right) uniforms in [0, 1). The caller
    checks the new position against the walls (step 4).

    Returns:
        (x, y, heading) after the sub-step, clipped to the arena; ω_L and ω_R after slip
        [rad/s]; the body twist (v_x, v_y, yaw_rate).

    Scalars only: numba reference-counts every array an inlined helper receives, on every call
    (the occupancy grid here would cost a tenth of the batch simulator's speed).
    """
    eta, x_icr, wheel_radius, half_track = slip
    omega_left = apply_slip(commands[0], noise[0] * eta)
    omega_right = apply_slip(commands[1], noise[1] * eta)
    twist = body_velocities(omega_left, omega_right, x_icr, wheel_radius, half_track)
    new_x, new_y, new_heading = integrate(robot, pose[0], pose[1], pose[2], twist)
    return new_x, new_y, new_heading, omega_left, omega_right, twist


@inline_jit
def hits_wall(task: NavigationTask, x: float, y: float, heading: float) -> bool:
    """Whether the robot of ``task`` at pose (x [m], y [m], heading [rad]) collides with a wall:
    its position in a wall cell for a point robot, its footprint touching a wall cell's disc
    otherwise (:mod:`skidnav.sim.footprint`)."""
    robot = task.robot
    return collides(
        task.occupancy, task.grid, x, y, heading, robot.footprint_length, robot.footprint_width
    )


@inline_jit
def at_goal(
    x: float,
    y: float,
    grid: GridShape,
    goal_cell: tuple[int, int],
    goal_disc: tuple[float, float, float],
) -> bool:
    """Whether a position (x, y) [m] ends the episode: within ``goal_disc`` (x [m], y [m],
    radius [m]) when its radius is > 0, else in ``goal_cell`` (i, j) of ``grid``.

    Scalars only (see :func:`drifted_slip`)."""
    goal_x, goal_y, radius = goal_disc
    if radius > 0.0:
        dx, dy = x - goal_x, y - goal_y
        return dx * dx + dy * dy <= radius * radius
    i, j = cell_of(x, y, grid)
    return i == goal_cell[0] and j == goal_cell[1]


@inline_jit
def is_forward_drive(commands: tuple[float, float]) -> bool:
    """Whether the wheel speeds ``commands`` (ω_L, ω_R) [rad/s] drive straight forward: equal
    and positive — the discrete forward action, or a continuous one at any speed. The thesis
    measures the floor's wheel-speed variance during such drives (here, the env's and the
    real-time loop's)."""
    return commands[0] == commands[1] and commands[0] > 0.0


@inline_jit
def records_variance(rewards: RewardScheme, commands: tuple[float, float]) -> bool:
    """Whether an action commanding ``commands`` adds its wheel speeds to the observed variance
    (``variance="observed"``): a forward drive (:func:`is_forward_drive`)."""
    return rewards.observed_variance and is_forward_drive(commands)


@inline_jit
def simulate_action(
    task: NavigationTask,
    pose: np.ndarray,
    commands: tuple[float, float],
    time: float,
    noise: np.ndarray,
    log: np.ndarray,
) -> tuple[bool, int, float, float]:
    """Move the robot through one action, updating ``pose`` (x, y, heading) in place.

    Args:
        task: the MDP. pose: float64 (3,) [m, m, rad]. commands: the wheel speeds (ω_L, ω_R)
            [rad/s] held through the action (a discrete action's :func:`commanded_wheel_speeds`).
            time: simulated time at the start of the action [s]. noise: float64 (2·substeps,)
            uniforms in [0, 1). log: float64 (≥ substeps, 6) receiving one row per free sub-step
            (see :data:`LOG_COLUMNS`).

    Returns:
        (collided, rows logged, ω_L and ω_R of the last sub-step [rad/s]).
    """
    robot, grid = task.robot, task.grid
    record = records_variance(task.rewards, commands)
    x, y, heading = pose[0], pose[1], pose[2]
    region = region_of(x, y, grid)
    omega_left = omega_right = 0.0
    n_logged = 0
    collided = False
    for k in range(robot.substeps):
        slip = region_slip(task, region, time + k * robot.dt)
        new_x, new_y, heading, omega_left, omega_right, twist = substep(
            robot, slip, (x, y, heading), commands, (noise[2 * k], noise[2 * k + 1])
        )
        # :func:`hits_wall` (:func:`skidnav.sim.footprint.collides`), spelled out: a call given
        # the task's arrays costs their reference counts on every sub-step (a tenth of the batch
        # simulator's speed, measured)
        if robot.footprint_length > 0.0:
            hit = footprint_collides(
                task.occupancy, grid, new_x, new_y, heading, robot.footprint_length,
                robot.footprint_width,
            )  # fmt: skip
        else:
            i, j = cell_of(new_x, new_y, grid)
            hit = task.occupancy[i, j] != 0
        if hit:
            collided = True
            break
        x, y = new_x, new_y
        _log_row(log, n_logged, region, commands, twist)
        n_logged += 1
        if record:
            _record_wheel_speed(task.variance_stats, region, omega_left)
            _record_wheel_speed(task.variance_stats, region, omega_right)
        region = region_of(x, y, grid)  # the next sub-step's region (shares x / W with cell_of)
    pose[0], pose[1], pose[2] = x, y, heading
    return collided, n_logged, omega_left, omega_right


@inline_jit
def action_reward(rewards: RewardScheme, at_goal: bool, collided: bool, variance: float) -> float:
    """The reward of an action (Alhawary (2020), App. A.1.2; docs/simulator.md): ``rewards.goal`` if
    it ended in the goal cell (the episode terminates), else ``rewards.collision`` after a
    collision, else ``rewards.step − rewards.variance_weight · variance``, ``variance`` [rad²/s²]
    being the wheel-speed variance of the region where it ended (whichever estimate the caller
    uses)."""
    if at_goal:
        return rewards.goal
    if collided:
        return rewards.collision
    return rewards.step - rewards.variance_weight * variance


@inline_jit
def action_cost(rewards: RewardScheme, at_goal: bool, collided: bool, variance: float) -> float:
    """The cost of an action (module doc): minus :func:`action_reward` without the goal bonus,
    i.e. ``−rewards.collision`` after a collision that did not end in the goal cell, else
    ``−rewards.step + rewards.variance_weight · variance`` (a free step, and the action that
    reached the goal: its bonus is the same on every path there). ``variance`` [rad²/s²] as
    there."""
    return -action_reward(rewards, False, collided and not at_goal, variance)


@inline_jit
def command_transition(
    task: NavigationTask,
    pose: np.ndarray,
    commands: tuple[float, float],
    time: float,
    noise: np.ndarray,
    log: np.ndarray,
) -> Outcome:
    """One step of the MDP driven by the wheel speeds ``commands`` (ω_L, ω_R) [rad/s]: simulate
    the action, then score it (see module doc); arguments as :func:`simulate_action`."""
    collided, n_logged, omega_left, omega_right = simulate_action(
        task, pose, commands, time, noise, log
    )
    return score_action(task, pose, time, collided, n_logged, omega_left, omega_right)


@inline_jit
def transition(
    task: NavigationTask,
    pose: np.ndarray,
    action: int,
    time: float,
    noise: np.ndarray,
    log: np.ndarray,
) -> Outcome:
    """One step of the MDP for a discrete action 0–3 (:func:`command_transition` of its wheel
    speeds, :func:`commanded_wheel_speeds`)."""
    commands = commanded_wheel_speeds(action, task.robot.wheel_speed)
    return command_transition(task, pose, commands, time, noise, log)


@inline_jit
def score_action(
    task: NavigationTask,
    pose: np.ndarray,
    time: float,
    collided: bool,
    n_logged: int,
    omega_left: float,
    omega_right: float,
) -> Outcome:
    """The :class:`Outcome` of an action that started at ``time`` [s] and left the robot at
    ``pose`` (x [m], y [m], heading [rad]): state, region, goal, reward and cost (module doc), for
    any robot that moved it (this kernel's, or the physical one of :mod:`skidnav.physics`)."""
    state = state_of(pose[0], pose[1], pose[2], task.grid)
    region = region_of(pose[0], pose[1], task.grid)
    terminated = at_goal(
        pose[0], pose[1], task.grid, (task.goal_i, task.goal_j),
        (task.goal_x, task.goal_y, task.goal_radius),
    )  # fmt: skip
    end_time = time + task.robot.dt * task.robot.substeps
    variance = region_variance(task, region, end_time)
    reward = action_reward(task.rewards, terminated, collided, variance)
    cost = action_cost(task.rewards, terminated, collided, variance)
    return Outcome(
        reward, terminated, collided, n_logged, omega_left, omega_right, state, region, cost
    )


@inline_jit
def draw_noise(rng: np.random.Generator, noise: np.ndarray) -> None:
    """Fill ``noise`` with ``rng.random()`` draws, in order (identical to ``rng.random(n)``)."""
    for k in range(noise.shape[0]):
        noise[k] = rng.random()


@jit
def pose_state(task: NavigationTask, pose: np.ndarray) -> int:
    """Flat state index of a pose."""
    return state_of(pose[0], pose[1], pose[2], task.grid)


@jit
def simulate_batch(
    task: NavigationTask,
    poses: np.ndarray,
    actions: np.ndarray,
    time: float,
    rng: np.random.Generator,
    rewards: np.ndarray,
    states: np.ndarray,
) -> int:
    """Apply ``actions[k]`` to robot ``poses[k]`` for every k (independent robots, one shared
    floor); writes rewards (float64 (n,)) and next states (int64 (n,)); returns collisions."""
    log = np.empty((task.robot.substeps, 6))
    noise = np.empty(2 * task.robot.substeps)
    pose = np.empty(3)  # each robot's pose is copied through it: no view of ``poses`` per robot
    collisions = 0
    for k in range(poses.shape[0]):
        draw_noise(rng, noise)
        pose[0], pose[1], pose[2] = poses[k, 0], poses[k, 1], poses[k, 2]
        outcome = transition(task, pose, actions[k], time, noise, log)
        poses[k, 0], poses[k, 1], poses[k, 2] = pose[0], pose[1], pose[2]
        rewards[k] = outcome.reward
        states[k] = outcome.state
        if outcome.collided:
            collisions += 1
    return collisions
