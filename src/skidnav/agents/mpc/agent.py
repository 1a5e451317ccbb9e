"""``mppi-kinematic``: MPPI over the two wheel speeds through the online Bayesian ridge kinematic
model, against the walls found so far, with a cost-to-go over the learned map
(docs/agents/mppi-kinematic.md).

What the agent knows is what every agent of the navigation env gets: the observation (the pose,
or the features whose first four entries hold it), the goal cell, the arena and its
discretization (cells, headings, slip regions), the wheel-speed bound, the control period and
the nominal robot (:class:`~skidnav.robot.params.RobotParams`: the datasheet's wheel radius,
half track and x_ICR, the prior of the kinematic model, as ``dyna-kinematic``'s) and the lidar's
layout (rays and range limit). It never reads the map's walls or the floor's slip: it learns the
robot's kinematics from ``info["kinematic_log"]`` and the walls from ``info["collision"]`` and,
with feature observations, from the lidar ranges they hold (:mod:`skidnav.agents.mpc.laser`).

Per real step: :meth:`MPPIKinematicAgent.act` plans (:class:`~skidnav.agents.mpc.planner.
MPPIPlanner`) and returns the wheel speeds; :meth:`MPPIKinematicAgent.observe` feeds the step's
kinematic log to the model (refitted on its schedule, then the sampled dynamics updated), its
path and collision and the lidar readings of the observations to the map evidence (the
cost-to-go recomputed when the map changed);
:meth:`MPPIKinematicAgent.end_episode` forgets the plan. :meth:`MPPIKinematicAgent.policy` hands
out a frozen copy, a :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`: its model and what
it knew of the map stay as they were, but within a rollout it still marks what its lidar reads
(forgotten at the next rollout), as a navigator that does not learn still sees.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar, NamedTuple

import numpy as np

from skidnav.agents.geometry import geometry_json
from skidnav.agents.mpc.config import MPPIConfig, with_horizon
from skidnav.agents.mpc.costmap import CostMap
from skidnav.agents.mpc.dynamics import (
    SampledDynamics,
    fixed_dynamics,
    lattice_coefficients,
    nominal_speeds,
    prior_dynamics,
    top_speeds,
    true_coefficients_check,
    update_dynamics,
)
from skidnav.agents.mpc.evidence import MapEvidence
from skidnav.agents.mpc.observations import pose_of, ranges_of
from skidnav.agents.mpc.planner import MPPIPlanner
from skidnav.agents.mpc.planning_robot import lattice_robot, map_costs, padded
from skidnav.agents.mpc.policy import MPPIPolicy
from skidnav.agents.saving import generator_state, new_save_paths
from skidnav.errors import UserError, first_line
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.models.kinematic import KinematicModel
from skidnav.robot.params import RobotParams
from skidnav.sim.features import check_lidar
from skidnav.sim.lidar import FULL_TURN, LaserSpec
from skidnav.world.discretization import Discretization

AGENT_NAME = "mppi-kinematic"
SAVE_FORMAT = "skidnav-mppi-agent"
"""The ``"format"`` of a saved agent's JSON (also a policy file: the frozen planner)."""
SAVE_VERSION = 4
"""4: the lidar's field of view (``lidar_fov``); 3: ``temperature`` in seconds. Version 3 files
(no field of view: a full turn) are read as they are, version 2 (``temperature`` in control
steps) by converting it."""
GREEDY_SEED = 0
"""The seed of the frozen planner :meth:`MPPIKinematicAgent.greedy_action` rolls out: every
greedy rollout draws the same numbers, none of the agent's."""


class PlanningView(NamedTuple):
    """A copy of what the planner reads (:meth:`MPPIKinematicAgent.planning_view`): the sampled
    dynamics and the cost map."""

    dynamics: SampledDynamics
    cost_map: CostMap


class MPPIKinematicAgent:
    """The model-based wheel-speed agent (module doc).

    Args:
        robot: the nominal robot: prior of the model, timing (``dt``, ``substeps``: the control
            period), arena, integration scheme, wheel-speed bound.
        discretization: cells, heading bins and slip regions of the arena.
        goal: the goal cell (i, j).
        config: hyperparameters (default :class:`MPPIConfig`).
        rng: the source of every random draw (default: a fresh one).
        true_coefficients: only for ``kinematic_model = "true"`` — tests and references: the
            simulator's own coefficients per slip region, float64 (n_regions, 8) (columns of
            :data:`~skidnav.models.kinematic_regression.N_COEFFICIENTS`), planned with and never
            learned.
        lidar_rays, lidar_range, lidar_fov: the layout of the feature observations' range
            readings: rays spread over ``lidar_fov`` [rad] in (0, 2π] (2π: evenly over a full
            turn from the heading; narrower: a sector centred on it, both edges included),
            readings of at most ``lidar_range`` [m] (:mod:`skidnav.sim.lidar`).
    """

    name: ClassVar[str] = AGENT_NAME

    def __init__(
        self,
        robot: RobotParams,
        discretization: Discretization,
        goal: tuple[int, int],
        config: MPPIConfig | None = None,
        rng: np.random.Generator | None = None,
        *,
        true_coefficients: np.ndarray | None = None,
        lidar_rays: int = 8,
        lidar_range: float = 0.3,
        lidar_fov: float = FULL_TURN,
    ) -> None:
        self.config = with_horizon(config or MPPIConfig(), robot.action_duration)
        """Its hyperparameters, the horizon in control steps of the robot's control period."""
        check_lidar(lidar_rays, lidar_range)
        LaserSpec(max(int(lidar_rays), 1), float(lidar_range), lidar_fov)  # checks the sector
        self.lidar_rays, self.lidar_range = int(lidar_rays), float(lidar_range)
        self.lidar_fov = float(lidar_fov)
        self.robot, self.discretization = robot, discretization
        self.goal = _checked_goal(goal, discretization)
        self.rng = rng if rng is not None else np.random.default_rng()
        self.kernel_robot = padded(robot, self.config.footprint_padding).kernel_constants()
        """The robot the rollouts drive: its timing, arena, scheme and padded footprint."""
        self.kernel_grid = discretization.grid_shape()
        self.model = KinematicModel(robot, discretization, self.config.kinematic_config())
        self.dynamics = self._initial_dynamics(true_coefficients)
        lattice = self._lattice_coefficients()
        self.costs = map_costs(self.config, robot, self.goal, self.route_speeds(lattice))
        lattice_robots = []
        if self.config.cost_to_go == "states":
            lattice_robots = [
                lattice_robot(robot, duration) for duration in self.config.lattice_durations
            ]
        self.evidence = MapEvidence(
            self.costs, self.kernel_robot, self.kernel_grid, lattice_robots, lattice
        )
        self.planner = MPPIPlanner(self.config, self.kernel_robot, self.kernel_grid, self.rng)
        self.steps = 0
        """Real steps observed."""
        self.episode_steps = 0
        """Real steps observed in the current episode (its first observation's readings are
        learned with its first step)."""
        self.episodes = 0
        """Episodes ended (:meth:`end_episode`)."""
        self.rollouts = 0
        """Sequences rolled out through the model while acting (K per action)."""
        self._greedy: MPPIPolicy | None = None  # the frozen planner of the greedy rollout

    def _initial_dynamics(self, true_coefficients: np.ndarray | None) -> SampledDynamics:
        """The dynamics the agent starts with, the model held as ``kinematic_model`` asks."""
        source = self.config.kinematic_model
        if source == "true":
            coefficients = true_coefficients_check(true_coefficients, self.model.grid.n_regions)
            self.model.hold()
            return fixed_dynamics(coefficients)
        if true_coefficients is not None:
            raise ValueError(f"expected no true coefficients with kinematic_model {source!r}")
        if source == "prior":
            self.model.hold()
        return prior_dynamics(self.model, self.config.prior_spread)

    @classmethod
    def from_env(
        cls,
        env: Any,
        config: MPPIConfig | None = None,
        rng: np.random.Generator | None = None,
        *,
        true_coefficients: np.ndarray | None = None,
    ) -> MPPIKinematicAgent:
        """An agent for the navigation env ``env`` (wrapped or not): it reads the env's robot,
        discretization, goal cell and lidar layout — nothing of its walls or floor."""
        nav = env.unwrapped
        features = nav.features
        return cls(
            nav.robot, nav.discretization, tuple(nav.grid_map.goal), config, rng,
            true_coefficients=true_coefficients, lidar_rays=features.lidar_rays,
            lidar_range=features.lidar_range, lidar_fov=features.field_of_view,
        )  # fmt: skip

    @property
    def planning_updates(self) -> int:
        """Model rollouts so far (the family's planning work, as a training log counts it)."""
        return self.rollouts

    # -- acting and learning --------------------------------------------------------------

    def act(self, observation: Any) -> np.ndarray:
        """The wheel speeds (ω_L, ω_R) [rad/s] to command at ``observation`` (one MPPI step),
        float64 (2,): :meth:`act_on` the agent's own dynamics and map, uncopied."""
        return self.act_on(observation, PlanningView(self.dynamics, self.evidence.cost_map))

    def planning_view(self) -> PlanningView:
        """What :meth:`act` plans with, copied: the sampled dynamics and the cost map as they are
        now. A learner off the control path (``skidnav robot run``, realtime/control/learner.py)
        hands each new view to the control path, which plans on it (:meth:`act_on`) while the
        agent goes on learning."""
        return PlanningView(
            SampledDynamics(*(np.copy(array) for array in self.dynamics)),
            CostMap(*(np.copy(array) for array in self.evidence.cost_map)),
        )

    def act_on(self, observation: Any, view: PlanningView) -> np.ndarray:
        """:meth:`act` on a :meth:`planning_view` instead of the agent's own model and map: the
        wheel speeds (ω_L, ω_R) [rad/s], float64 (2,). Only the plan and the Generator move, so
        it may run beside :meth:`observe` in another thread."""
        pose = pose_of(observation, self.lidar_rays)
        left, right = self.planner.step(pose, view.dynamics, view.cost_map, self.costs)
        self.rollouts += self.config.samples
        return np.array([left, right])

    def greedy_action(self, observation: Any) -> np.ndarray:
        """The wheel speeds (ω_L, ω_R) [rad/s], float64 (2,), that the agent's planner frozen as
        it is now commands at ``observation``: the greedy evaluation, which learns nothing and
        draws none of the agent's numbers. The frozen planner (:meth:`policy` seeded
        :data:`GREEDY_SEED`) is made at the first call after the agent last learned or a greedy
        rollout started (:meth:`start_greedy_rollout`), and keeps its plan between calls."""
        if self._greedy is None:
            self._greedy = self.policy(GREEDY_SEED)
        return np.array(self._greedy.wheel_speeds(observation))

    def start_greedy_rollout(self) -> None:
        """A greedy rollout starts: the next :meth:`greedy_action` freezes the planner afresh
        (:class:`~skidnav.agents.greedy.RolloutState`)."""
        self._greedy = None

    def observe(
        self,
        observation: Any,
        action: Any,
        reward: float,
        next_observation: Any,
        terminated: bool,
        truncated: bool,
        info: Mapping[str, Any],
    ) -> None:
        """Learn from one real step: the kinematic log to the model (refit on its schedule),
        the path and a collision to the map evidence, and the lidar readings of
        ``next_observation`` (and of ``observation`` at an episode's first step) when they are
        features. ``reward``, ``terminated`` and ``truncated`` teach nothing here (the goal cell
        is known; costs are the agent's own)."""
        pose = pose_of(observation, self.lidar_rays)
        commands = _commands(action, self.robot.wheel_speed)
        log = np.asarray(info.get("kinematic_log", np.zeros((0, 6))), dtype=np.float64)
        log = log.reshape(-1, 6)
        self.steps += 1
        self.episode_steps += 1
        self._greedy = None  # the frozen planner no longer is the agent's
        self.model.feed(log)
        if self.model.maybe_refit():
            self.refresh_model()
        collided = bool(info.get("collision", False))
        self.evidence.record_step(pose, commands, log, collided, self.dynamics)
        seen = [next_observation] if self.episode_steps > 1 else [observation, next_observation]
        for each in seen:
            self.evidence.record_readings(
                pose_of(each, self.lidar_rays), ranges_of(each, self.lidar_rays),
                self.lidar_range, self.lidar_fov,
            )  # fmt: skip

    def refresh_model(self) -> None:
        """After a refit: the sampled dynamics from the model, then :meth:`refresh_costs`."""
        update_dynamics(self.dynamics, self.model)
        self.refresh_costs()

    def refresh_costs(self) -> None:
        """After the model changed (a refit, a load): the route's speeds (``route_speed``), the
        cost map's scalars and the cost map with the lattice recomputed."""
        lattice = self._lattice_coefficients()
        self.costs = map_costs(self.config, self.robot, self.goal, self.route_speeds(lattice))
        self.evidence.costs = self.costs
        self.evidence.reweigh(lattice, model_changed=True)

    def _lattice_coefficients(self) -> np.ndarray:
        """The lattice's coefficients (n_regions, 8) now: the model's mean, guarded as
        ``lattice_guard`` asks (:func:`~skidnav.agents.mpc.dynamics.lattice_coefficients`)."""
        return lattice_coefficients(self.model, self.dynamics.mean, self.config.lattice_guard)

    def route_speeds(self, lattice: np.ndarray) -> tuple[float, float]:
        """The top forward speed [m/s] and turn rate [rad/s] of the cells' cost-to-go: the
        nominal robot's, or with ``route_speed = "learned"`` after a refit the model's
        (:func:`~skidnav.agents.mpc.dynamics.top_speeds` of ``lattice``, the lattice's
        coefficients (n_regions, 8): its mean where fast commands informed it,
        :meth:`_lattice_coefficients`)."""
        if self.config.route_speed == "learned" and self.model.refits > 0:
            learned = top_speeds(lattice, self.robot.wheel_speed)
            if learned is not None:
                return learned
        return nominal_speeds(self.robot)

    def end_episode(self) -> None:
        """Forget the plan (the next episode starts from rest)."""
        self.planner.reset()
        self.episodes += 1
        self.episode_steps = 0
        self._greedy = None

    def policy(self, seed: int = 0) -> MPPIPolicy:
        """The agent's planner frozen as it is now (its model and map copied), drawing from a
        Generator of its own seeded with ``seed``: later learning does not change it."""
        return MPPIPolicy(self, seed)

    # -- saving ---------------------------------------------------------------------------

    def state_arrays(self) -> dict[str, np.ndarray]:
        """Everything learned, as named arrays for the ``.npz``: the model's samples and fit,
        the sampled dynamics, the map evidence and the plan."""
        dynamics = {f"dynamics_{name}": array for name, array in self.dynamics._asdict().items()}
        return {
            **self.model.state_arrays(),
            **dynamics,
            "hits": self.evidence.hits,
            "passes": self.evidence.passes,
            "ray_ends": self.evidence.ray_ends,
            "ray_crossings": self.evidence.ray_crossings,
            "plan": self.planner.plan,
        }

    def metadata(self) -> dict[str, Any]:
        """The ``.json``: format, agent, config, geometry, goal, observation layout, counters
        and the Generator's state."""
        return {
            "format": SAVE_FORMAT,
            "version": SAVE_VERSION,
            "agent": self.name,
            "config": self.config.to_dict(),
            "geometry": geometry_json(self.robot, self.discretization),
            "goal": list(self.goal),
            "lidar_rays": self.lidar_rays,
            "lidar_range": self.lidar_range,
            "lidar_fov": self.lidar_fov,
            "counters": {
                "steps": self.steps,
                "episodes": self.episodes,
                "rollouts": self.rollouts,
                "episode_steps": self.episode_steps,
            },
            "rng": generator_state(self.rng),
        }

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.npz`` (:meth:`state_arrays`) and ``path.json`` (:meth:`metadata`), each
        atomically, never pickle; read back by :func:`skidnav.agents.mpc.loading.load_mppi_agent`.
        Returns both paths."""
        npz_path, json_path = new_save_paths(path)
        write_npz_atomic(npz_path, self.state_arrays(), compress=True)
        write_atomic(json_path, json.dumps(self.metadata(), indent=1).encode("utf-8"))
        return npz_path, json_path


def _checked_goal(goal: Any, grid: Discretization) -> tuple[int, int]:
    """``goal`` as a cell (i, j) of ``grid``; ValueError otherwise."""
    cell = tuple(goal) if isinstance(goal, tuple | list) else ()
    if len(cell) != 2 or not all(
        isinstance(v, int | np.integer) and not isinstance(v, bool) and 0 <= v < n
        for v, n in zip(cell, (grid.n_x, grid.n_y), strict=True)
    ):
        raise ValueError(
            f"expected a goal cell (i, j) of the {grid.n_x} × {grid.n_y} grid, got {goal!r}"
        )
    return int(cell[0]), int(cell[1])


def _commands(action: Any, limit: float) -> tuple[float, float]:
    """The wheel speeds an action commanded, clipped to ± ``limit`` as the env clips them."""
    left, right = np.asarray(action, dtype=np.float64).reshape(2).tolist()
    return min(max(left, -limit), limit), min(max(right, -limit), limit)


def make_mppi_agent(
    env: Any,
    config: MPPIConfig | Mapping[str, Any] | None = None,
    rng: np.random.Generator | None = None,
    **context: Any,
) -> MPPIKinematicAgent:
    """:meth:`MPPIKinematicAgent.from_env` with ``config`` a config, a mapping of its fields or
    None; UserError in one line naming the agent for a bad config."""
    try:
        if not isinstance(config, MPPIConfig):
            config = MPPIConfig.from_mapping(config or {})
        return MPPIKinematicAgent.from_env(env, config, rng, **context)
    except (ValueError, TypeError) as error:
        raise UserError(f"agent {AGENT_NAME!r}: {first_line(error)}") from None
