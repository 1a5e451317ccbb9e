"""Linear Dyna plus the thesis's kinematic-model planning on continuous poses
(``linear-dyna-kinematic``; docs/agents/linear-dyna.md, "linear-dyna-kinematic").

After each real step (s, a, r, s′) with the env's ``info``:

1. everything ``linear-dyna`` does (:mod:`skidnav.agents.linear.dyna`): the Q-learning
   update, the linear model's LMS updates, the features of s into the recent-state memory,
   ``planning_steps`` updates through the linear model;
2. the pose of s (x [m], y [m], heading [rad], read from the observation) into a second ring
   buffer, row for row beside the features;
3. what the tabular ``dyna-kinematic`` learns from the step, with its own code
   (:mod:`skidnav.agents.tabular.model_based`, :mod:`skidnav.agents.kinematic_planning`):
   the free sub-steps of ``info["kinematic_log"]`` fed to the per-region Bayesian ridge
   :class:`~skidnav.models.kinematic.KinematicModel`; the reward into the reward statistics of its
   outcome (free step by region, collision, goal arrival); the goal cell of a termination and the
   wall cell a collision ran into (guessed from the pose) marked as known;
4. ``kinematic_steps`` updates of
   :func:`skidnav.agents.linear.kinematic_planning.kinematic_planning`: a remembered pose perturbed
   by a Gaussian, a random action, the next pose predicted by the kinematic model against the known
   walls and goals, the learned mean reward, and the Q-learning update of the two poses'
   observations.

At the end of an episode the kinematic model refits on its schedule (as ``dyna-kinematic``'s).
The geometry (robot, discretization, map for the range readings, goal cell) comes from the
navigation ``task`` (``env.unwrapped.task``), as for the tabular agent; without one the agent is
``linear-dyna`` (no pose memory, no kinematic model). Kinematic planning starts with the first
real step whose ``info`` carries a ``kinematic_log``. With ``kinematic_steps = 0`` the agent is
``linear-dyna`` bit for bit (same weights, same generator state).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

from skidnav.agents import kinematic_planning as kp
from skidnav.agents.config import KinematicModelFields, check
from skidnav.agents.geometry import geometry_from_json, geometry_from_task, geometry_json
from skidnav.agents.linear.config import (
    MAX_LINEAR_PLANNING_STEPS,
    LinearConfig,
    LinearDynaConfig,
)
from skidnav.agents.linear.dyna import LinearDynaAgent
from skidnav.agents.linear.kinematic_planning import (
    OBSERVE_FEATURES,
    OBSERVE_POSE,
    KinematicPlanning,
    Observer,
    PlanningScratch,
    kinematic_planning,
    observe_pose,
)
from skidnav.agents.planner_learning import planner_observe
from skidnav.agents.planner_state import (
    check_planner_counters,
    check_planner_map,
    hold_kinematic_model,
    true_kinematics_from_json,
)
from skidnav.errors import CorruptFileError, shown
from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_files import check_model_size
from skidnav.robot.params import RobotParams
from skidnav.sim.navigation import NavigationTask
from skidnav.world.discretization import Discretization

MAX_CELLS = 2**22
"""Most cells (n_x · n_y) of the map an agent keeps (a saved file cannot ask for more)."""


@dataclass(frozen=True)
class LinearDynaKinematicConfig(LinearDynaConfig, KinematicModelFields):
    """Linear Dyna plus kinematic-model planning from perturbed visited poses
    (:class:`~skidnav.agents.config.KinematicModelFields` for the kinematic model, as
    ``dyna-kinematic``)."""

    kinematic_steps: int = 10
    """Kinematic planning updates after each real step, in [0, 100,000] (0 = linear-dyna)."""
    kinematic_position_std: float = 0.02
    """Standard deviation of the Gaussian added to a remembered x and y [m] (≥ 0; about a
    cell of the default 25-level grid, 2.6 cm)."""
    kinematic_heading_std: float = 0.3
    """Standard deviation of the Gaussian added to a remembered heading [rad] (≥ 0; about a
    heading bin of the default 20, 0.31 rad)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(
            isinstance(self.kinematic_steps, int)
            and not isinstance(self.kinematic_steps, bool)
            and 0 <= self.kinematic_steps <= MAX_LINEAR_PLANNING_STEPS,
            f"an integer kinematic_steps in [0, {MAX_LINEAR_PLANNING_STEPS:,}]",
            self.kinematic_steps,
        )
        for name in ("kinematic_position_std", "kinematic_heading_std"):
            value = getattr(self, name)
            check(
                isinstance(value, int | float) and math.isfinite(value) and value >= 0,
                f"a finite {name} >= 0",
                value,
            )
        self.kinematic_config()  # validates the kinematic model's fields


class KinematicContext(NamedTuple):
    """What the agent knows of the arena besides its experience: the nominal robot (the
    kinematic model's prior, the integrator), the discretization, the map the observation's
    range readings are cast on (uint8 (n_x, n_y), 1 = wall), the goal cell (i, j), and for
    ``kinematic_model = "true"`` the simulator's true kinematics (float64 (n_regions, 4, 3),
    the kinematic env's ``true_kinematics``; else None)."""

    robot: RobotParams
    discretization: Discretization
    occupancy: np.ndarray
    goal_cell: tuple[int, int]
    true_kinematics: np.ndarray | None = None

    @classmethod
    def of_task(
        cls, task: NavigationTask, true_kinematics: np.ndarray | None = None
    ) -> KinematicContext:
        """The context of a navigation task (``env.unwrapped.task``)."""
        robot, grid = geometry_from_task(task)
        occupancy = np.ascontiguousarray(task.occupancy != 0, dtype=np.uint8)
        goal = (int(task.goal_i), int(task.goal_j))
        return cls(robot, grid, occupancy, goal, true_kinematics)


class LinearDynaKinematicAgent(LinearDynaAgent):
    """Linear Dyna whose planning also moves perturbed visited poses through the learned
    kinematic model (module doc).

    Args (beyond :class:`~skidnav.agents.linear.agent.LinearAgent`'s):
        task: the navigation task of the env (``env.unwrapped.task``): robot, discretization,
            map and goal. None: no geometry, the agent is ``linear-dyna``.
        context: the same as a :class:`KinematicContext` (the loader's way; ``task`` wins).
        true_kinematics: with ``task``, the simulator's true kinematics for
            ``kinematic_model = "true"`` (:class:`KinematicContext`).

    With a geometry the observation must be the skid-steer env's ``"pose"`` (3 values, bounds
    [0, W] × [0, H] × [−π, π]) or ``"features"`` (7 + k values, x ≤ W, y ≤ H; the range of its
    readings read from the bounds); ValueError otherwise.
    """

    name: ClassVar[str] = "linear-dyna-kinematic"
    config_class: ClassVar[type[LinearConfig]] = LinearDynaKinematicConfig

    def __init__(
        self,
        low: np.ndarray,
        high: np.ndarray,
        n_actions: int,
        config: LinearConfig | None = None,
        rng: np.random.Generator | None = None,
        *,
        task: NavigationTask | None = None,
        context: KinematicContext | None = None,
        true_kinematics: np.ndarray | None = None,
    ) -> None:
        if task is not None:
            context = KinematicContext.of_task(task, true_kinematics)
        self.context = context
        super().__init__(low, high, n_actions, config, rng)

    def _check_sizes(self) -> None:
        super()._check_sizes()
        if self.context is None:
            return
        grid = self.context.discretization
        if grid.n_x * grid.n_y > MAX_CELLS:
            raise ValueError(f"expected at most {MAX_CELLS:,} cells, got {grid.n_x * grid.n_y:,}")
        if self.n_actions != 4:
            raise ValueError(f"expected 4 actions with a navigation task, got {self.n_actions}")
        if self.context.occupancy.shape != (grid.n_x, grid.n_y):
            raise ValueError(
                f"expected a map of {grid.n_x} × {grid.n_y} cells, "
                f"got {self.context.occupancy.shape}"
            )

    @property
    def _config(self) -> LinearDynaKinematicConfig:
        config = self.config
        assert isinstance(config, LinearDynaKinematicConfig)
        return config

    def _allocate(self) -> None:
        super()._allocate()
        self.kinematic: KinematicModel | None = None
        if self.context is None:
            return
        robot, grid = self.context.robot, self.context.discretization
        self.observer = self._observer()
        self.kinematic = KinematicModel(robot, grid, self._config.kinematic_config())
        hold_kinematic_model(
            self.kinematic, self._config.kinematic_model, self.context.true_kinematics
        )
        self.kernel_robot, self.kernel_grid = robot.kernel_constants(), grid.grid_shape()
        shape = (grid.n_x, grid.n_y)
        self.planner = kp.PlannerArrays(
            pred_next=np.zeros((1, self.n_actions), dtype=np.int32),
            pred_outcome=np.zeros((1, self.n_actions), dtype=np.int8),
            pred_row=np.zeros((1, self.n_actions), dtype=np.int16),
            velocities=self.kinematic.velocities,
            walls=np.zeros(shape, dtype=np.bool_),
            goals=np.zeros(shape, dtype=np.bool_),
            stale=np.zeros(shape, dtype=np.bool_),
            wall_evidence=np.zeros(shape, dtype=np.int64),
            free_evidence=np.zeros(shape, dtype=np.int64),
            reward_stats=np.zeros((grid.n_regions + 2, 2)),
            trajectory_keys=np.zeros(1, dtype=np.int64),
            neighbour_keys=np.zeros(1, dtype=np.int64),
            episode_keys=np.zeros(1, dtype=np.int64),
            counters=np.zeros(kp.N_COUNTERS, dtype=np.int64),
        )
        """The tabular planner's bookkeeping (walls, goals, reward statistics, the kinematic
        flag); its table is unused (predictions are made from poses) and its episode list is
        not kept (one slot, rewound after each step)."""
        self.visited_poses = np.zeros((self._config.planning_memory, 3))
        """Poses of the most recent states, float64 (planning_memory, 3) (x [m], y [m],
        heading [rad]): row ``(step − 1) mod planning_memory`` beside ``visited``."""
        self._scratch = PlanningScratch(
            pose=np.zeros(3),
            observation=np.zeros(self.low.size),
            coded=np.zeros(self.dimensions.size),
            tiles=np.zeros(self.config.n_tilings, dtype=np.int64),
            next_tiles=np.zeros(self.config.n_tilings, dtype=np.int64),
            values=np.zeros((1, self.n_actions)),
        )
        self._info: Mapping[str, Any] | None = None
        self._observation: Any = None
        self._next_observation: Any = None
        """The observations of the step being learned (set by :meth:`observe`)."""

    def _observer(self) -> Observer:
        """The observation kind read from the bounds (class doc) and how it is tiled."""
        assert self.context is not None
        grid = self.context.discretization
        width, height = float(grid.arena_width), float(grid.arena_height)
        low, high = self.low, self.high
        if (
            low.size == 3
            and np.array_equal(low, [0.0, 0.0, -math.pi])
            and np.array_equal(high, [width, height, math.pi])
        ):
            kind, max_range = OBSERVE_POSE, 1.0
        elif low.size >= 7 and high[0] == width and high[1] == height:
            kind, max_range = OBSERVE_FEATURES, float(high[7]) if low.size > 7 else 1.0
        else:
            raise ValueError(
                "expected the navigation env's 'pose' or 'features' observation for "
                f"{width} m × {height} m, got bounds of {low.size} values"
            )
        return Observer(
            kind=kind, occupancy=self.context.occupancy, arena=(width, height),
            goal=grid.cell_centre(*self.context.goal_cell), max_range=max_range,
            dimensions=self.dimensions, low=self._coded_low, high=self._coded_high,
            tiles=self.tiles,
        )  # fmt: skip

    def pose_of(self, observation: Any) -> tuple[float, float, float]:
        """The pose (x [m], y [m], heading [rad]) an observation shows: its first three values,
        or x, y and atan2(sin ψ, cos ψ) of the features."""
        obs = np.asarray(observation, dtype=np.float64)
        if self.observer.kind == OBSERVE_POSE:
            return float(obs[0]), float(obs[1]), float(obs[2])
        return float(obs[0]), float(obs[1]), math.atan2(float(obs[3]), float(obs[2]))

    def observation_tiles(self, pose: tuple[float, float, float]) -> np.ndarray:
        """The active tiles, int64 (n_tilings,), of the env's observation of ``pose`` as the
        planner computes it."""
        out = np.zeros(self.config.n_tilings, dtype=np.int64)
        observe_pose(self.observer, *pose, self._scratch, out)
        return out

    def observe(
        self,
        observation: Any,
        action: int,
        reward: float,
        next_observation: Any,
        terminated: bool,
        truncated: bool = False,
        info: dict[str, Any] | None = None,
    ) -> None:
        """Learn from one real step (module doc); ``info`` gives ``kinematic_log`` and
        ``collision`` (both optional)."""
        if self.kinematic is not None:
            self._info = info or {}
            self._observation, self._next_observation = observation, next_observation
        super().observe(observation, action, reward, next_observation, terminated, truncated, info)

    def _learn(
        self,
        tiles: np.ndarray,
        action: int,
        reward: float,
        next_tiles: np.ndarray,
        terminated: bool,
    ) -> int | None:
        super()._learn(tiles, action, reward, next_tiles, terminated)
        if self.kinematic is None:
            return None
        config, info = self._config, self._info or {}
        pose = self.pose_of(self._observation)
        self.visited_poses[(self.steps - 1) % config.planning_memory] = pose
        self._learn_kinematics(action, reward, terminated, info)
        if config.kinematic_steps and self.planner.counters[kp.USE_KINEMATIC]:
            self.planning_updates += self.plan_kinematic(config.kinematic_steps)
        return None

    def _learn_kinematics(
        self, action: int, reward: float, terminated: bool, info: Mapping[str, Any]
    ) -> None:
        """The tabular planner's bookkeeping of one real step (module doc, item 3)."""
        assert self.kinematic is not None
        counters = self.planner.counters
        log = info.get("kinematic_log")
        if log is not None:
            counters[kp.USE_KINEMATIC] = 1  # kinematic planning starts with the first log
            self.kinematic.feed(log)
        grid = self.context.discretization  # type: ignore[union-attr]
        state = grid.state(*self.pose_of(self._observation))
        next_pose = np.array(self.pose_of(self._next_observation))
        next_state = grid.state(*next_pose)
        planner_observe(
            self.planner, state, action, reward, next_state, terminated,
            bool(info.get("collision", False)), next_pose, self.kernel_robot, self.kernel_grid,
        )  # fmt: skip
        counters[kp.EPISODE_LENGTH] = 0  # the episode's pairs are not kept

    def plan_kinematic(self, n_updates: int) -> int:
        """``n_updates`` kinematic planning updates from the remembered poses; returns how many
        updated a value (:func:`~skidnav.agents.linear.kinematic_planning.kinematic_planning`)."""
        assert self.kinematic is not None
        config = self._config
        settings = KinematicPlanning(
            n_updates=n_updates, step=self.step_size, gamma=float(config.gamma),
            position_std=float(config.kinematic_position_std),
            heading_std=float(config.kinematic_heading_std),
        )  # fmt: skip
        planner = self.planner
        updates = kinematic_planning(
            self.w, self.visited_poses, min(max(self.steps, 1), config.planning_memory),
            settings, planner.velocities, planner.walls, planner.goals, planner.reward_stats,
            self.kernel_robot, self.kernel_grid, self.observer, self._scratch, self.rng,
        )  # fmt: skip
        return int(updates)

    def end_episode(self) -> None:
        """Refit the kinematic model on its schedule, decay ε."""
        if self.kinematic is not None:
            self.kinematic.maybe_refit()
            self.planner.stale[:] = False
            self.planner.counters[kp.EPISODE_TERMINATED] = 0
        super().end_episode()

    # --- saving -----------------------------------------------------------------------------

    def state_arrays(self) -> dict[str, np.ndarray]:
        arrays = super().state_arrays()
        if self.kinematic is None:
            return arrays
        planner = self.planner
        return {
            **arrays,
            "visited_poses": self.visited_poses,
            "map_occupancy": self.context.occupancy,  # type: ignore[union-attr]
            "planner_walls": planner.walls,
            "planner_goals": planner.goals,
            "planner_wall_evidence": planner.wall_evidence,
            "planner_free_evidence": planner.free_evidence,
            "planner_reward_stats": planner.reward_stats,
            "planner_counters": planner.counters,
            **self.kinematic.state_arrays(),
        }

    def _context_json(self) -> dict[str, Any]:
        if self.context is None:
            return {"context": None}
        robot, grid, _, goal, truth = self.context
        context = {**geometry_json(robot, grid), "goal_cell": list(goal)}
        if truth is not None and self._config.kinematic_model == "true":
            context["true_kinematics"] = truth.tolist()
        return {"context": context}

    @classmethod
    def context_from_json(cls, meta: Mapping[str, Any]) -> dict[str, Any]:
        value = meta["context"]
        if value is None:
            return {}
        config = cls.config_class.from_mapping(meta["config"])
        assert isinstance(config, LinearDynaKinematicConfig)
        keys = {"robot", "discretization", "goal_cell"}
        if config.kinematic_model == "true":
            keys.add("true_kinematics")
        if not isinstance(value, Mapping) or set(value) != keys:
            raise ValueError(f"expected a context with {', '.join(sorted(keys))}")
        robot, grid = geometry_from_json(
            {"robot": value["robot"], "discretization": value["discretization"]}
        )
        if grid is None:
            raise ValueError("expected a discretization in the context")
        goal = value["goal_cell"]
        if not (
            isinstance(goal, list)
            and len(goal) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) for v in goal)
            and 0 <= goal[0] < grid.n_x
            and 0 <= goal[1] < grid.n_y
        ):
            raise ValueError(f"expected a goal cell inside the grid, got {shown(goal)}")
        if grid.n_x * grid.n_y > MAX_CELLS:  # before the map is allocated
            raise ValueError(f"expected at most {MAX_CELLS:,} cells, got {grid.n_x * grid.n_y:,}")
        check_model_size(grid, config.kinematic_config())  # a model a file may describe
        truth = None
        if "true_kinematics" in keys:
            truth = true_kinematics_from_json(value["true_kinematics"], grid.n_regions)
        occupancy = np.zeros((grid.n_x, grid.n_y), dtype=np.uint8)  # read from the archive
        return {"context": KinematicContext(robot, grid, occupancy, (goal[0], goal[1]), truth)}

    def restore(
        self, counters: Mapping[str, Any], rng_state: Mapping[str, Any], arrays: Any
    ) -> None:
        super().restore(counters, rng_state, arrays)
        if self.kinematic is None:
            return
        occupancy = np.asarray(arrays["map_occupancy"])
        if occupancy.size and occupancy.max() > 1:
            raise CorruptFileError("saved map_occupancy holds values other than 0 and 1")
        stats = self.planner.reward_stats
        if (stats[:, 1] < 0).any():
            raise CorruptFileError("saved planner_reward_stats hold negative counts")
        try:
            check_planner_counters(self.planner.counters, [0, 0, 0], has_kinematic=True)
            check_planner_map(self.planner)
        except ValueError as error:
            raise CorruptFileError(str(error)) from None
        self.kinematic.load_arrays({name: np.asarray(arrays[name]) for name in arrays})


AGENT_NAME = "linear-dyna-kinematic"
AGENT_CLASS = LinearDynaKinematicAgent
