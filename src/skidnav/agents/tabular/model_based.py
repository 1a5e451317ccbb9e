"""The shared machinery of the model-based tabular agents (``dyna-kinematic``,
``trajectory-prioritized``, ``dyna-full``, ``dyna-sweep``): :class:`ModelBasedAgent`, a Dyna-Q
agent with the multinomial model, an optional kinematic model and optional sweeps of the best
trajectories found, all learned in one compiled step (:func:`model_based_step`); the saved
geometry and planner, and their checks.

Each subclass switches parts on (``uses_kinematic``, ``uses_trajectories``) and names its config:
docs/agents/dyna-kinematic.md, docs/agents/trajectory-prioritized.md, docs/agents/dyna-full.md,
docs/agents/dyna-sweep.md.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from typing import Any, ClassVar, NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.agents import kinematic_planning as kp
from skidnav.agents.config import KinematicModelFields, QLearningConfig
from skidnav.agents.geometry import geometry_from_task, geometry_json
from skidnav.agents.learning import PLANNING_UPDATES, Experience, learning_step
from skidnav.agents.planner_learning import feed_log, planner_observe, refresh_stale
from skidnav.agents.planner_state import (
    MAP_ARRAYS,
    check_planner_counters,
    check_planner_map,
    hold_kinematic_model,
)
from skidnav.agents.tabular.dyna_q import DynaAgent
from skidnav.agents.trajectory_keys import loop_erase, neighbourhood_keys
from skidnav.models.kinematic import KinematicModel
from skidnav.models.multinomial_kernels import MultinomialArrays, model_observe
from skidnav.robot.params import KinematicConstants, RobotParams
from skidnav.sim.navigation import NavigationTask
from skidnav.sim.q_values import td_update, visit_step_size
from skidnav.world.discretization import Discretization, GridShape

logger = logging.getLogger(__name__)


_NO_GRID = GridShape(2, 2, 1, 2, 2, 1.0, 1.0)
_NO_ROBOT = RobotParams().kernel_constants()


class ModelBasedArrays(NamedTuple):
    """What the model-based agents learn into: Q table, multinomial model, the planner's arrays
    and the kinematic model's sample buffers (float64 (n_regions, window, 5) and int64
    (n_regions,); (1, 1, 5) and (1,) placeholders without a kinematic model), and the real
    updates of each pair (:attr:`~skidnav.agents.tabular.agent.TabularAgent.visits`)."""

    q: np.ndarray
    model: MultinomialArrays
    planner: kp.PlannerArrays
    kinematic_data: np.ndarray
    kinematic_counts: np.ndarray
    visits: np.ndarray


class ModelBasedSettings(NamedTuple):
    """The planning shares, the agent's robot and grid as the kernels take them, whether it
    has a geometry and a kinematic model, and the visit exponent ω of the real updates' step
    size."""

    shares: kp.PlanningShares
    robot: KinematicConstants
    grid: GridShape
    has_geometry: bool
    has_kinematic: bool
    alpha_exponent: float


_NO_KINEMATIC = (np.zeros((1, 1, 5)), np.zeros(1, dtype=np.int64))


@learning_step(ModelBasedArrays)
@jit
def model_based_step(
    arrays: ModelBasedArrays,
    settings: ModelBasedSettings,
    counters: np.ndarray,
    step: Experience,
    rng: np.random.Generator,
) -> None:
    """The learning step of the model-based agents: TD update, model count, the planner's
    bookkeeping (rewards, walls, goals, the episode's pairs), the kinematic samples of the step,
    then the combined planning updates."""
    a, s = arrays, settings
    alpha = visit_step_size(a.visits, step.state, step.action, s.shares.alpha, s.alpha_exponent)
    td_update(
        a.q, step.state, step.action, step.reward, step.next_state, step.terminated, alpha,
        s.shares.gamma,
    )  # fmt: skip
    model_observe(a.model, step.state, step.action, step.reward, step.next_state, step.terminated)
    pose = step.pose if s.has_geometry else np.full(3, -1.0)
    logged = s.has_kinematic and step.n_logged >= 0
    if logged:  # kinematic planning starts with the first step that brings samples
        a.planner.counters[kp.USE_KINEMATIC] = 1
    planner_observe(
        a.planner, step.state, step.action, step.reward, step.next_state, step.terminated,
        step.collided, pose, s.robot, s.grid,
    )  # fmt: skip
    if logged:
        n_regions = a.kinematic_counts.shape[0]
        feed_log(a.kinematic_data, a.kinematic_counts, step.log, step.n_logged, n_regions)
    if s.shares.n_steps > 0:
        counters[PLANNING_UPDATES] += kp.combined_planning(
            a.q, a.model, a.planner, s.shares, s.grid, rng
        )


class ModelBasedAgent(DynaAgent[ModelBasedArrays, ModelBasedSettings]):
    """Shared machinery of ``dyna-kinematic``, ``trajectory-prioritized``, ``dyna-full`` and
    ``dyna-sweep``: multinomial model, optional kinematic model, optional best-trajectory sweeps.

    Context keyword arguments (from :func:`~skidnav.agents.tabular.registry.make_agent`): ``task``
    (a :class:`NavigationTask`, e.g. ``env.unwrapped.task``) or ``robot`` and ``discretization``.
    Without a discretization the agent has no geometry, whatever ``n_states`` is: no kinematic
    model, no spatial neighbours. With one, kinematic planning starts at the first real step whose
    ``info`` carries a ``kinematic_log`` (an env that never supplies one gets plain replay, not
    predictions of the untrained prior). ``true_kinematics``: the simulator's expected body
    velocities, float64 (n_regions, 4, 3) (the kinematic env's ``true_kinematics``), which an agent
    whose ``kinematic_model`` is "true" plans with (:func:`hold_kinematic_model`).
    """

    uses_kinematic: ClassVar[bool] = False
    uses_trajectories: ClassVar[bool] = False

    def __init__(
        self,
        n_states: int,
        n_actions: int,
        config: QLearningConfig | None = None,
        rng: np.random.Generator | None = None,
        *,
        task: NavigationTask | None = None,
        robot: RobotParams | None = None,
        discretization: Discretization | None = None,
        true_kinematics: np.ndarray | None = None,
    ) -> None:
        super().__init__(n_states, n_actions, config, rng)
        if task is not None:
            robot, discretization = geometry_from_task(task)
        self._set_geometry(robot or RobotParams(), discretization, true_kinematics)

    def _set_geometry(
        self, robot: RobotParams, grid: Discretization | None, true_kinematics: np.ndarray | None
    ) -> None:
        """Build the kinematic model (held as ``kinematic_model`` asks) and the planner for this
        geometry (None: no geometry)."""
        if grid is not None and (grid.n_states != self.n_states or self.n_actions != 4):
            raise ValueError(
                f"expected {grid.n_states} states and 4 actions for this discretization, "
                f"got {self.n_states} and {self.n_actions}"
            )
        self.robot = robot
        self.discretization = grid
        self.kernel_robot: KinematicConstants = robot.kernel_constants() if grid else _NO_ROBOT
        self.kernel_grid: GridShape = grid.grid_shape() if grid else _NO_GRID
        self.kinematic: KinematicModel | None = None
        if self.uses_kinematic and grid is not None:
            config: KinematicModelFields = self.config  # type: ignore[assignment]
            self.kinematic = KinematicModel(robot, grid, config.kinematic_config())
            hold_kinematic_model(self.kinematic, config.kinematic_model, true_kinematics)
        self.trajectories: list[np.ndarray] = []
        """The best loop-erased start→goal trajectories (pair keys), shortest first."""
        self.planner = self._new_planner()
        self._refresh_table()

    def _new_planner(self) -> kp.PlannerArrays:
        n_table = self.n_states if self.kinematic else 1
        shape = (self.kernel_grid.n_x, self.kernel_grid.n_y)
        n_regions = self.kernel_grid.regions_x * self.kernel_grid.regions_y
        velocities = self.kinematic.velocities if self.kinematic else np.zeros((1, 4, 3))
        counters = np.zeros(kp.N_COUNTERS, dtype=np.int64)  # USE_KINEMATIC set by the first log
        return kp.PlannerArrays(
            pred_next=np.zeros((n_table, self.n_actions), dtype=np.int32),
            pred_outcome=np.zeros((n_table, self.n_actions), dtype=np.int8),
            pred_row=np.zeros((n_table, self.n_actions), dtype=np.int16),
            velocities=velocities,
            walls=np.zeros(shape, dtype=np.bool_),
            goals=np.zeros(shape, dtype=np.bool_),
            stale=np.zeros(shape, dtype=np.bool_),
            wall_evidence=np.zeros(shape, dtype=np.int64),
            free_evidence=np.zeros(shape, dtype=np.int64),
            reward_stats=np.zeros((n_regions + 2, 2)),
            trajectory_keys=np.zeros(1, dtype=np.int64),
            neighbour_keys=np.zeros(1, dtype=np.int64),
            episode_keys=np.zeros(256, dtype=np.int64),
            counters=counters,
        )

    @property
    def shares(self) -> kp.PlanningShares:
        """The planning hyperparameters as the kernels take them."""
        config = self.config
        return kp.PlanningShares(
            n_steps=config.planning_steps, alpha=config.alpha, gamma=config.gamma,
            mode=config.planning_mode_code,
            trajectory_share=float(getattr(config, "trajectory_share", 0.0)),
            kinematic_share=float(getattr(config, "kinematic_share", 0.0)),
        )  # fmt: skip

    def reserve_episode(self, n_steps: int) -> None:
        """Make room for ``n_steps`` more pairs in the current episode's buffer."""
        needed = int(self.planner.counters[kp.EPISODE_LENGTH]) + n_steps
        keys = self.planner.episode_keys
        if needed > keys.shape[0]:
            grown = np.zeros(max(needed, 2 * keys.shape[0]), dtype=np.int64)
            grown[: keys.shape[0]] = keys
            self.planner = self.planner._replace(episode_keys=grown)

    def reserve(self, n_steps: int) -> None:
        super().reserve(n_steps)
        self.reserve_episode(n_steps)

    def learning_arrays(self) -> ModelBasedArrays:
        data, counts = (
            (self.kinematic.data, self.kinematic.counts) if self.kinematic else _NO_KINEMATIC
        )
        return ModelBasedArrays(self.q, self.model.arrays, self.planner, data, counts, self.visits)

    def learning_settings(self) -> ModelBasedSettings:
        return ModelBasedSettings(
            self.shares, self.kernel_robot, self.kernel_grid, self.discretization is not None,
            self.kinematic is not None, float(self.config.alpha_visit_exponent),
        )  # fmt: skip

    def end_episode(self) -> None:
        """Update the best trajectories, refit the kinematic model on its schedule, decay ε."""
        counters = self.planner.counters
        if self.uses_trajectories and counters[kp.EPISODE_TERMINATED]:
            keys = self.planner.episode_keys[: counters[kp.EPISODE_LENGTH]]
            self._offer_trajectory(loop_erase(keys, self.n_actions, self.n_states))
        counters[kp.EPISODE_LENGTH] = 0
        counters[kp.EPISODE_TERMINATED] = 0
        if self.kinematic is not None and self.kinematic.maybe_refit():
            self._refresh_table()
        elif self.kinematic is not None and self.planner.stale.any():
            refresh_stale(self.planner, self.kernel_robot, self.kernel_grid)
        self.planner.stale[:] = False
        super().end_episode()

    def _offer_trajectory(self, trajectory: np.ndarray) -> None:
        """Keep ``trajectory`` if it is among the K shortest distinct ones; rebuild the sweeps."""
        limit = int(self.config.n_trajectories)  # type: ignore[attr-defined]
        if any(np.array_equal(trajectory, kept) for kept in self.trajectories):
            return
        if len(self.trajectories) >= limit and trajectory.size >= self.trajectories[-1].size:
            return
        self.trajectories.append(trajectory)
        self.trajectories.sort(key=len)  # stable: older first among equal lengths
        del self.trajectories[limit:]
        self._rebuild_sweeps()

    def _rebuild_sweeps(self) -> None:
        """Sweep lists: trajectory pairs backward from the goal, shortest trajectory first; then
        their neighbourhoods (see docs/agents/trajectory-prioritized.md)."""
        if not self.trajectories:
            return
        backward = _first_occurrences(np.concatenate([t[::-1] for t in self.trajectories]))
        spatial = self.discretization is not None
        around = np.concatenate([
            neighbourhood_keys(t, self.planner.walls, self.kernel_grid, self.n_actions, spatial)
            for t in self.trajectories
        ])  # fmt: skip
        around = _first_occurrences(around)
        around = around[~np.isin(around, backward)]
        if self.kinematic is None:
            around = around[np.isin(around, self.model.visited_pairs())]
        counters = self.planner.counters
        counters[[kp.N_TRAJECTORY, kp.TRAJECTORY_CURSOR]] = (backward.size, 0)
        counters[[kp.N_NEIGHBOURS, kp.NEIGHBOUR_CURSOR]] = (around.size, 0)
        self.planner = self.planner._replace(
            trajectory_keys=backward,
            neighbour_keys=around if around.size else np.zeros(1, np.int64),
        )

    def _refresh_table(self) -> None:
        """Recompute the whole kinematic table and the local-refresh radius."""
        if self.kinematic is None or self.discretization is None:
            return
        velocities = self.kinematic.velocities
        reach = float(np.hypot(velocities[..., 0], velocities[..., 1]).max()) * (
            self.robot.action_duration
        )
        cell = min(self.discretization.cell_width, self.discretization.cell_height)
        self.planner.counters[kp.REFRESH_RADIUS] = math.ceil(reach / cell) + 1
        self.kinematic.fill_table(
            self.planner.pred_next, self.planner.pred_outcome, self.planner.walls,
            self.planner.goals,
        )  # fmt: skip
        kp.fill_reward_rows(self.planner, self.kernel_grid)

    # --- saving -----------------------------------------------------------------------------

    def _state_arrays(self) -> dict[str, np.ndarray]:
        planner = self.planner
        counters = planner.counters
        trajectories = self.trajectories or [np.zeros(0, dtype=np.int64)]
        arrays = {
            **super()._state_arrays(),
            "planner_walls": planner.walls,
            "planner_goals": planner.goals,
            "planner_stale": planner.stale,
            "planner_wall_evidence": planner.wall_evidence,
            "planner_free_evidence": planner.free_evidence,
            "planner_reward_stats": planner.reward_stats,
            "planner_counters": counters,
            "planner_trajectory_keys": planner.trajectory_keys[: counters[kp.N_TRAJECTORY]],
            "planner_neighbour_keys": planner.neighbour_keys[: counters[kp.N_NEIGHBOURS]],
            "planner_episode_keys": planner.episode_keys[: counters[kp.EPISODE_LENGTH]],
            "trajectory_keys": np.concatenate(trajectories),
            "trajectory_lengths": np.array([t.size for t in self.trajectories], dtype=np.int64),
        }
        if self.kinematic is not None:
            arrays.update(self.kinematic.state_arrays())
        return arrays

    def _state_json(self) -> dict[str, Any]:
        meta = {**super()._state_json(), "geometry": geometry_json(self.robot, self.discretization)}
        if self.kinematic is not None and self.kinematic.reference is not None:
            meta["true_kinematics"] = self.kinematic.reference.tolist()
        return meta

    def _restore_state_arrays(self, arrays: Mapping[str, np.ndarray]) -> None:
        """The saved planner, trajectories and kinematic model, into an agent built with the
        saved geometry (:func:`skidnav.agents.tabular.registry.load_agent` builds it so, once the
        archive's arrays are known to have that geometry's shapes)."""
        super()._restore_state_arrays(arrays)
        planner = self.planner
        for name in (*MAP_ARRAYS, "reward_stats", "counters"):
            saved = np.asarray(arrays[f"planner_{name}"])
            if saved.shape != getattr(planner, name).shape:
                raise ValueError(f"saved planner {name} has shape {saved.shape}")
            getattr(planner, name)[...] = saved
        check_planner_map(planner)
        sweeps = [_saved_keys(arrays, f"planner_{name}_keys", self.q.size)
                  for name in ("trajectory", "neighbour", "episode")]  # fmt: skip
        check_planner_counters(
            planner.counters, [keys.size for keys in sweeps], self.kinematic is not None
        )
        if not np.isfinite(planner.reward_stats).all() or (planner.reward_stats[:, 1] < 0).any():
            raise ValueError("saved planner reward_stats are not finite counts")
        self.planner = planner._replace(
            trajectory_keys=_at_least_one(sweeps[0]), neighbour_keys=_at_least_one(sweeps[1])
        )
        self.reserve_episode(0)  # room for the saved EPISODE_LENGTH pairs
        self.planner.episode_keys[: sweeps[2].size] = sweeps[2]
        keys = _saved_keys(arrays, "trajectory_keys", self.q.size)
        lengths = np.asarray(arrays["trajectory_lengths"], dtype=np.int64)
        if (lengths < 1).any() or lengths.sum() != keys.size:
            raise ValueError("saved trajectory lengths do not match the trajectory keys")
        self.trajectories = np.split(keys, np.cumsum(lengths)[:-1]) if lengths.size else []
        if self.kinematic is not None:
            self.kinematic.load_arrays(dict(arrays))
            self._refresh_table()


def _saved_keys(arrays: Mapping[str, np.ndarray], name: str, n_keys: int) -> np.ndarray:
    """Saved pair keys ``arrays[name]`` as int64; ValueError unless each is in [0, n_keys)."""
    keys = np.asarray(arrays[name])
    if keys.ndim != 1 or (keys.size and keys.dtype.kind not in "iu"):
        raise ValueError(f"saved {name} are not a list of integers")
    keys = keys.astype(np.int64)
    if keys.size and (keys.min() < 0 or keys.max() >= n_keys):
        raise ValueError(f"saved {name} refer to pairs outside the Q table")
    return keys


def _first_occurrences(keys: np.ndarray) -> np.ndarray:
    """``keys`` without repeats, each kept at its first position."""
    _, first = np.unique(keys, return_index=True)
    return keys[np.sort(first)]


def _at_least_one(keys: np.ndarray) -> np.ndarray:
    keys = np.asarray(keys, dtype=np.int64)
    return keys.copy() if keys.size else np.zeros(1, dtype=np.int64)
