"""Compiled planning of ``linear-dyna-kinematic``: Q-learning updates of linear action values on
continuous poses imagined near visited ones and moved by the learned kinematic model.

The thesis's kinematic-model planning (Alhawary (2020), ch. 7;
:mod:`skidnav.agents.kinematic_planning` for the tabular agents) carried to tile-coded
continuous observations (docs/agents/linear-dyna.md). One planning update
(:func:`kinematic_planning`):

1. a pose (x [m], y [m], heading [rad]) of the recent-state memory drawn uniformly
   (``rng.random()``), perturbed by independent Gaussians of standard deviation
   ``position_std`` [m] on x and y and ``heading_std`` [rad] on the heading (three
   ``rng.standard_normal()``), the position clipped to the arena;
2. an action drawn uniformly (``rng.random()``);
3. a start in a wall or goal cell the agent knows of is skipped (nothing updated); otherwise the
   next pose is :func:`~skidnav.models.kinematic_prediction.predict_action` of the learned
   body velocities: integrated over the action with the robot's scheme, blocked by known walls as
   the MDP blocks a collision, a known goal cell ending the action a predicted arrival;
4. the reward is the learned mean reward of that outcome (the row of the tabular planner's
   ``reward_stats``, :func:`~skidnav.agents.kinematic_planning.reward_row`, and its mean,
   :func:`~skidnav.agents.kinematic_planning.mean_rewards`): goal arrivals, collisions, or
   free steps by the slip region of the next state's cell;
5. both poses become the env's observation (:func:`observe_pose`: the ``"pose"`` vector, or the
   ``"features"`` vector of :func:`skidnav.sim.features.fill_features`) and their active tiles,
   and :func:`~skidnav.agents.linear.updates.q_learning_update` moves ``q(x, a)`` toward
   ``r̂ + γ · max_a' q(x', a')`` (no bootstrap after a predicted arrival).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents.kinematic_planning import mean_rewards, reward_row
from skidnav.agents.linear.tile_coding import active_tiles
from skidnav.agents.linear.updates import q_learning_update
from skidnav.models.kinematic_prediction import PREDICT_GOAL, predict_action
from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.params import KinematicConstants
from skidnav.sim.features import fill_features
from skidnav.world.discretization import GridShape, cell_of, state_of

OBSERVE_POSE = 0
"""Observation kind code: the env's ``observation="pose"`` vector (x, y, wrapped heading)."""
OBSERVE_FEATURES = 1
"""Observation kind code: the env's ``observation="features"`` vector (pose, goal, ranges)."""


class Observer(NamedTuple):
    """How a pose becomes the agent's observation and its active tiles.

    Attributes:
        kind: :data:`OBSERVE_POSE` or :data:`OBSERVE_FEATURES`.
        occupancy: uint8 (n_x, n_y), 1 = wall: the map the range readings are cast on.
        arena: (W, H) [m]. goal: the goal cell's centre (x, y) [m].
        max_range: the largest range reading [m].
        dimensions: int64 (m,) the tiled dimensions of the observation.
        low, high: float64 (m,) their bounds. tiles: int64 (m,) their tile counts.
    """

    kind: int
    occupancy: np.ndarray
    arena: tuple[float, float]
    goal: tuple[float, float]
    max_range: float
    dimensions: np.ndarray
    low: np.ndarray
    high: np.ndarray
    tiles: np.ndarray


class PlanningScratch(NamedTuple):
    """Work arrays of :func:`kinematic_planning` (no allocation per update).

    Attributes:
        pose: float64 (3,). observation: float64 (observation size,). coded: float64 (m,).
        tiles, next_tiles: int64 (n_tilings,). values: float64 (1, n_actions).
    """

    pose: np.ndarray
    observation: np.ndarray
    coded: np.ndarray
    tiles: np.ndarray
    next_tiles: np.ndarray
    values: np.ndarray


class KinematicPlanning(NamedTuple):
    """Hyperparameters of :func:`kinematic_planning`: updates per call, the weights' step
    (α / n_tilings), γ, and the perturbation's standard deviations [m] and [rad]."""

    n_updates: int
    step: float
    gamma: float
    position_std: float
    heading_std: float


@jit
def observe_pose(
    observer: Observer,
    x: float,
    y: float,
    heading: float,
    scratch: PlanningScratch,
    out: np.ndarray,
) -> None:
    """Write the active tiles of the observation of pose (x [m], y [m], heading [rad]) into
    ``out`` int64 (n_tilings,): the env's observation of that pose (``"pose"``: x, y and the
    heading wrapped to [−π, π]; ``"features"``: :func:`~skidnav.sim.features.fill_features`),
    then the tiles of its tiled dimensions (as the agent's ``features``)."""
    observation = scratch.observation
    if observer.kind == OBSERVE_POSE:
        observation[0], observation[1], observation[2] = x, y, wrap_angle(heading)
    else:
        pose = scratch.pose
        pose[0], pose[1], pose[2] = x, y, heading
        fill_features(
            observer.occupancy, observer.arena, observer.goal, pose, observer.max_range,
            observation,
        )  # fmt: skip
    coded = scratch.coded
    for k in range(observer.dimensions.shape[0]):
        coded[k] = observation[observer.dimensions[k]]
    active_tiles(coded, observer.low, observer.high, observer.tiles, out)


@jit
def kinematic_planning(
    w: np.ndarray,
    poses: np.ndarray,
    n_visited: int,
    settings: KinematicPlanning,
    velocities: np.ndarray,
    walls: np.ndarray,
    goals: np.ndarray,
    reward_stats: np.ndarray,
    robot: KinematicConstants,
    grid: GridShape,
    observer: Observer,
    scratch: PlanningScratch,
    rng: np.random.Generator,
) -> int:
    """``settings.n_updates`` kinematic planning updates (module doc); returns how many
    updated a value (starts in known wall or goal cells are skipped).

    Args:
        w: float64 (n_actions, n_features) weights, updated in place.
        poses: float64 (capacity, 3) visited poses (x [m], y [m], heading [rad]); the first
            ``n_visited`` rows filled (≥ 1).
        velocities: float64 (n_regions, n_actions, 3) the kinematic model's predicted body
            velocities (v_x [m/s], v_y [m/s], yaw_rate [rad/s]).
        walls, goals: bool (n_x, n_y), the wall and goal cells the agent knows of.
        reward_stats: float64 (n_regions + 2, 2) [sum, count] of real rewards by outcome row.
        robot, grid: the agent's robot (sub-steps, arena, integrator) and discretization.
        observer, scratch: :class:`Observer`, :class:`PlanningScratch`.
        rng: the agent's generator (five draws per update).
    """
    means = mean_rewards(reward_stats)
    n_regions = reward_stats.shape[0] - 2
    n_actions = w.shape[0]
    width, height = robot.arena_width, robot.arena_height
    tiles, next_tiles = scratch.tiles, scratch.next_tiles
    updates = 0
    for _ in range(settings.n_updates):
        k = int(rng.random() * n_visited)
        x = poses[k, 0] + settings.position_std * rng.standard_normal()
        y = poses[k, 1] + settings.position_std * rng.standard_normal()
        heading = poses[k, 2] + settings.heading_std * rng.standard_normal()
        action = int(rng.random() * n_actions)
        x, y = min(max(x, 0.0), width), min(max(y, 0.0), height)
        i, j = cell_of(x, y, grid)
        if walls[i, j] or goals[i, j]:
            continue
        nx, ny, nh, outcome = predict_action(
            x, y, heading, action, velocities, walls, goals, robot, grid, False
        )
        reward = means[reward_row(state_of(nx, ny, nh, grid), outcome, n_regions, grid)]
        observe_pose(observer, x, y, heading, scratch, tiles)
        observe_pose(observer, nx, ny, nh, scratch, next_tiles)
        q_learning_update(
            w, tiles, action, reward, next_tiles, outcome == PREDICT_GOAL, settings.step,
            settings.gamma, scratch.values,
        )  # fmt: skip
        updates += 1
    return updates
