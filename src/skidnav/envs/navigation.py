"""The Gymnasium environment ``skidnav/SkidSteerNav-v0``: skid-steer navigation to a goal."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from skidnav.envs.step_info import step_info
from skidnav.physics.mdp import floor_materials, physics_transition
from skidnav.physics.mujoco_robot import PhysicsRobot
from skidnav.robot.kinematics import (
    clipped_wheel_speeds,
    commanded_wheel_speeds,
    wrap_angle,
)
from skidnav.robot.params import RobotParams
from skidnav.robot.presets import robot_preset
from skidnav.robot.slip import SlipField, make_slip_field
from skidnav.seeding import ARENA_ROLES, streams
from skidnav.sim.features import PoseFeatures
from skidnav.sim.lidar import FULL_TURN
from skidnav.sim.navigation import NavigationTask, RewardScheme
from skidnav.sim.task import build_task, step_arrays, task_arrays
from skidnav.world import rendering
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap
from skidnav.world.mapfile import load_map_file
from skidnav.world.maps import build_map

OBSERVATION_KINDS = ("discrete", "pose", "features")
ACTION_KINDS = ("discrete", "continuous")
VARIANCE_SOURCES = ("true", "observed")
DYNAMICS = ("kinematic", "mujoco")


class SkidSteerNavEnv(gymnasium.Env[Any, int]):
    """Drive a skid-steer robot to a goal through an arena with walls and a slippery floor.

    ## Description
    A small four-wheel skid-steer robot (the thesis robot, Alhawary (2020), App. A.1.1: r = 2.25 cm,
    c = 6 cm, x_ICR = 5 cm) moves in a 0.62 m × 0.505 m arena. Each action commands both wheels for
    10 × 0.1 s; the floor slows the wheels by a random, region-dependent amount (the slip field),
    and the skid makes turns slide the body sideways. The robot must reach the goal cell in as few
    actions as possible while bumping into walls as little as possible.

    ## Action Space
    ``Discrete(4)``: 0 forward (both wheels +1.7 rad/s), 1 backward (both −1.7), 2 turn left
    (ω_L −1.7, ω_R +1.7), 3 turn right (ω_L +1.7, ω_R −1.7). With ``action="continuous"``:
    ``Box(−1.7, 1.7, (2,), float32)`` of the wheel speeds (ω_L, ω_R) [rad/s] held through the
    action (the thesis's range, ± ``robot.wheel_speed``); an action outside the box is clipped to
    it (the motors saturate), a non-finite one refused. (1.7, 1.7) is the forward action, the
    same trajectory bit for bit, and so on for the other three.

    ## Observation Space
    ``Discrete(n_x · n_y · n_headings)`` (12,500 by default): the flat index
    ``(i · n_y + j) · n_headings + heading_bin`` of the discretized pose (see
    :mod:`skidnav.world.discretization`). With ``observation="pose"``: ``Box`` of
    (x [m], y [m], heading [rad] in [−π, π]). With ``observation="features"``: ``Box`` float64
    (7 + k,) of x [m], y [m], cos ψ, sin ψ, the distance [m] to the goal cell's centre, cos and
    sin of the goal's bearing from the heading, and k = ``lidar_rays`` range readings [m] to the
    nearest wall or border, ray 0 ahead and the others counter-clockwise, clipped at
    ``lidar_range`` (layout and bounds: :mod:`skidnav.sim.features`).

    ## Rewards
    +10 on ending an action in the goal cell; −10 for an action that ran into a wall; otherwise
    −1 − 10·var, var being the wheel-speed variance of the region the action ends in (the slip
    field's true η²/12 with ``variance="true"``, the default; the running variance measured in
    forward actions with ``variance="observed"``, as the thesis). The same with either dynamics.
    ``info["cost"]`` is the action's cost, minus its reward without the goal bonus: 1 + 10·var,
    10 for a collision, and the action that reaches the goal costs what a free step ending there
    would (:func:`skidnav.sim.navigation.action_cost`); summed over an episode that reaches
    the goal it ranks paths as the return does.

    ## Starting State
    The centre of the map's start cell, heading 0 (facing +x); or ``start_pose`` (x [m], y [m],
    heading [rad]), which a map file of format version 2 may give (``start`` line).

    ## Episode End
    Terminated when an action ends in the goal cell; with a goal disc (``goal_disc`` (x [m], y [m],
    radius [m]) or a version-2 map file's ``goal`` line, as the BARN worlds have), when it ends
    within the disc instead. A robot with a footprint (``RobotParams.footprint_length`` ×
    ``footprint_width``, the Jackal's) collides when its rectangle touches a wall cell's inscribed
    disc (:mod:`skidnav.sim.footprint`), a point robot when it enters a wall cell. The env itself
    never truncates: Gymnasium's ``TimeLimit`` does, which ``gymnasium.make`` adds after 500 actions
    (registered ``max_episode_steps``; ``gymnasium.make(..., max_episode_steps=N)`` overrides it and
    ``env.spec.max_episode_steps`` says which applies). Built directly, wrap it in
    ``gymnasium.wrappers.TimeLimit`` for a limit. Agents bootstrap on truncation, never on
    termination.

    ## Info
    Built by :func:`skidnav.envs.step_info.step_info`, as the real-time loop's: ``pose`` (x [m],
    y [m], heading [rad]), ``cell`` (i, j, heading_bin), ``collision`` (bool), ``wheel_speeds``
    (ω_L, ω_R of the last sub-step after slip [rad/s]), ``region`` (flat slip region at the end of
    the action), ``kinematic_log`` float64 (n_free_substeps, 6), columns [region, omega_left_cmd,
    omega_right_cmd, v_x, v_y, yaw_rate] (what the Bayesian ridge kinematic model learns from),
    ``cost`` (see Rewards; 0 at a reset), and ``step_info``: the same as a typed
    :class:`~skidnav.envs.step_info.StepInfo`.

    ## Arguments
    ``map_kind`` ("free", "obstacles", "maze") or ``map_file`` (plain-text map) or ``grid_map``;
    ``world_seed`` (draws the map and the slip field; the map does not change between episodes);
    ``slip`` preset (:data:`skidnav.robot.slip.SLIP_PRESETS`: "thesis", "slippery", "rough",
    "nominal", "rough-physics", "slippery-physics", "ice-physics") or ``slip_field``;
    ``drift_amplitude`` and ``drift_period`` [s] (non-stationary slip; the clock runs across
    episodes and restarts when ``reset`` is given a seed); ``robot`` (:class:`RobotParams`, e.g.
    ``integrator="exact"``, or a robot's name, "thesis" or "jackal",
    :data:`skidnav.robot.presets.ROBOT_PRESETS`); ``discretization``; ``observation`` ("discrete",
    "pose", "features"); ``lidar_rays`` (k ≥ 0, default 8), ``lidar_range`` [m] (> 0, default 0.3)
    and ``lidar_fov`` [rad] (in (0, 2π], default 2π) of the features; ``variance``; ``render_mode``
    ("rgb_array" or "ansi"); ``action`` ("discrete", the default, or "continuous");
    ``control_period`` [s]: the duration of one action, a whole number of the robot's sub-steps of
    ``robot.dt`` (default ``robot.action_duration``, 1 s: the robot's ``substeps`` are replaced by
    ``control_period / dt``); ``dynamics``: "kinematic" (the ICR model of Kozłowski & Pazderski
    (2004), the default) or "mujoco" (the MuJoCo robot of :mod:`skidnav.physics`, the ``physics``
    extra: the same spaces, rewards, walls and episode rules, the slip field's wheel-speed loss
    applied to the servo set points, the motion that of the physics — :mod:`skidnav.physics.mdp` —
    and the kinematic log filled from the measured body twist; ``wheel_speeds`` are the measured
    ones; the MuJoCo state restarts at every ``reset``); ``floor``: with "mujoco", one material of
    :data:`skidnav.physics.materials.MATERIALS` for the whole floor, or None (default) for the slip
    preset's materials (:func:`skidnav.physics.materials.region_materials`).

    >>> import gymnasium, skidnav
    >>> env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1)
    >>> state, info = env.reset(seed=0)
    >>> int(env.observation_space.n), int(env.action_space.n), env.spec.max_episode_steps
    (12500, 4, 500)
    >>> _, reward, terminated, truncated, info = env.step(0)
    >>> round(float(reward), 3), info["collision"], info["kinematic_log"].shape
    (-1.0, False, (10, 6))
    >>> info["step_info"].pose == info["pose"]
    True

    ## Version History
    v0: initial version; ``start_pose``, ``goal_disc``, ``lidar_fov`` and robot footprints added
    (the defaults give the same numbers as before); truncation moved from the env to Gymnasium's
    ``TimeLimit`` (same limit, 500 actions, when made with ``gymnasium.make``); ``dynamics`` and
    ``floor`` added (the default ``dynamics="kinematic"`` gives the same numbers as before);
    ``observation="features"`` with ``lidar_rays`` and ``lidar_range`` added; ``action`` and
    ``control_period`` added (the defaults give the same numbers as before); ``info["cost"]`` added;
    the ``true_kinematics`` property added (a reference for agents, nothing in the MDP changes).
    """

    metadata = {"render_modes": ["rgb_array", "ansi"], "render_fps": 10}  # noqa: RUF012

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        map_kind: str = "obstacles",
        map_file: str | Path | None = None,
        grid_map: GridMap | None = None,
        world_seed: int = 0,
        slip: str = "thesis",
        slip_field: SlipField | None = None,
        drift_amplitude: float = 0.0,
        drift_period: float = 600.0,
        robot: RobotParams | str | None = None,
        discretization: Discretization | None = None,
        observation: str = "discrete",
        variance: str = "true",
        dynamics: str = "kinematic",
        floor: str | None = None,
        lidar_rays: int = 8,
        lidar_range: float = 0.3,
        lidar_fov: float = FULL_TURN,
        action: str = "discrete",
        control_period: float | None = None,
        start_pose: tuple[float, float, float] | None = None,
        goal_disc: tuple[float, float, float] | None = None,
    ) -> None:
        self._check_choices(render_mode, observation, variance, dynamics, action)
        self.render_mode = render_mode
        if isinstance(robot, str):
            robot = robot_preset(robot)
        self.robot = with_control_period(robot or RobotParams(), control_period)
        world = streams(world_seed, ARENA_ROLES)
        map_rng, slip_rng = world["map"], world["slip"]
        self.grid_map = _resolve_map(grid_map, map_file, map_kind, map_rng, discretization)
        if map_file is not None:
            start_pose, goal_disc = _metric_marks(map_file, start_pose, goal_disc)
        self.discretization = discretization or Discretization(
            n_x=self.grid_map.shape[0],
            n_y=self.grid_map.shape[1],
            arena_width=self.robot.arena_width,
            arena_height=self.robot.arena_height,
        )
        _check_same_arena(self.robot, self.discretization)
        self.slip_field = slip_field or make_slip_field(
            slip,
            slip_rng,
            regions=(self.discretization.regions_x, self.discretization.regions_y),
            drift_amplitude=drift_amplitude,
            drift_period=drift_period,
            robot=self.robot,
        )
        rewards = RewardScheme(observed_variance=variance == "observed")
        self.task: NavigationTask = build_task(
            self.grid_map, self.slip_field, self.robot, self.discretization, rewards, goal_disc
        )
        self._start_pose = self._checked_start(start_pose)
        self._task_arrays = task_arrays(self.task)
        self.observation_kind = observation
        self.features = PoseFeatures(
            self.grid_map, self.discretization, lidar_rays, lidar_range, lidar_fov,
            self.goal_point if goal_disc is not None else None,
        )  # fmt: skip
        self.action_kind = action
        self.action_space = action_space(action, self.robot)
        self._commands = [commanded_wheel_speeds(a, self.robot.wheel_speed) for a in range(4)]
        self.observation_space = self._observation_space()
        self.pose = np.zeros(3)
        self.time = 0.0
        self.trail: list[tuple[float, float]] = []
        self._log = np.zeros((self.robot.substeps, 6))
        self._noise = np.zeros(2 * self.robot.substeps)
        self._action_duration = self.robot.action_duration
        self.dynamics, self.floor = dynamics, floor
        self.physics_robot = self._physics_robot(slip) if dynamics == "mujoco" else None
        if floor is not None and self.physics_robot is None:
            raise ValueError(f"expected floor=None with dynamics={dynamics!r}, got {floor!r}")

    @classmethod
    def _check_choices(
        cls, render_mode: str | None, observation: str, variance: str, dynamics: str, action: str
    ) -> None:
        """ValueError unless the render mode, observation, variance source, dynamics and action
        kind are known."""
        if render_mode is not None and render_mode not in cls.metadata["render_modes"]:
            raise ValueError(
                f"expected render_mode in {cls.metadata['render_modes']}, got {render_mode!r}"
            )
        if observation not in OBSERVATION_KINDS:
            raise ValueError(f"expected observation in {OBSERVATION_KINDS}, got {observation!r}")
        if variance not in VARIANCE_SOURCES:
            raise ValueError(f"expected variance in {VARIANCE_SOURCES}, got {variance!r}")
        if dynamics not in DYNAMICS:
            raise ValueError(f"expected dynamics in {DYNAMICS}, got {dynamics!r}")
        if action not in ACTION_KINDS:
            raise ValueError(f"expected action in {ACTION_KINDS}, got {action!r}")

    def _physics_robot(self, preset: str) -> PhysicsRobot:
        """The MuJoCo robot on this env's floor (materials of ``floor``, else of the slip preset
        ``preset``); PhysicsUnavailable without MuJoCo. Its model leaves out the drawn wall
        boxes: they take no part in the physics (the MDP's wall rule decides collisions, and
        the trajectories are the same bit for bit) but cost about an eighth of the step time
        on the obstacles arena."""
        materials = floor_materials(preset, self.slip_field, self.floor, self.robot)
        return PhysicsRobot(self.robot, materials)

    def _observation_space(self) -> spaces.Space[Any]:
        if self.observation_kind == "discrete":
            return spaces.Discrete(self.discretization.n_states)
        if self.observation_kind == "features":
            return self.features.space()
        return spaces.Box(
            low=np.array([0.0, 0.0, -math.pi]),
            high=np.array([self.robot.arena_width, self.robot.arena_height, math.pi]),
            dtype=np.float64,
        )

    @property
    def true_kinematics(self) -> np.ndarray | None:
        """The floor's true expected body velocities of every slip region and discrete action,
        float64 (n_regions, 4, 3) (v_x [m/s], v_y [m/s], yaw_rate [rad/s];
        :meth:`~skidnav.robot.slip.SlipField.expected_velocities`, averaged over a drift period
        when the slip drifts): what a kinematic model could at best learn, for agents told to
        plan with the truth (``kinematic_model = "true"``). None with ``dynamics="mujoco"``:
        the physics robot has no such closed form."""
        if self.physics_robot is not None:
            return None
        return self.slip_field.expected_velocities(self.robot)

    def start_pose(self) -> np.ndarray:
        """(x [m], y [m], heading [rad]) where an episode starts: the given start pose, else the
        centre of the start cell, heading 0."""
        if self._start_pose is not None:
            return np.array(self._start_pose)
        x, y = self.discretization.cell_centre(*self.grid_map.start)
        return np.array([x, y, 0.0])

    @property
    def goal_point(self) -> tuple[float, float]:
        """The goal (x, y) [m]: the goal disc's centre, else the goal cell's centre."""
        if self.task.goal_radius > 0.0:
            return self.task.goal_x, self.task.goal_y
        return self.discretization.cell_centre(*self.grid_map.goal)

    @property
    def goal_radius(self) -> float:
        """The goal disc's radius [m]; 0 when the goal is the goal cell."""
        return float(self.task.goal_radius)

    def _checked_start(
        self, start_pose: tuple[float, float, float] | None
    ) -> tuple[float, float, float] | None:
        """``start_pose`` as floats; ValueError unless finite, in the arena and free."""
        if start_pose is None:
            return None
        x, y, heading = (float(v) for v in start_pose)
        width, height = self.robot.arena_width, self.robot.arena_height
        if not (all(math.isfinite(v) for v in (x, y, heading)) and 0 <= x <= width
                and 0 <= y <= height):  # fmt: skip
            raise ValueError(f"expected a finite start pose in the arena, got {start_pose}")
        if self.grid_map.occupancy[self.discretization.cell(x, y)]:
            raise ValueError(f"expected a start pose off the walls, got {start_pose}")
        return x, y, heading

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Put the robot at the start. With a seed, also restart the slip clock and the observed
        wheel-speed statistics, so the same seed gives the same trajectory."""
        super().reset(seed=seed)
        if seed is not None:
            self.time = 0.0
            self.task.variance_stats[:] = 0.0
        self.pose = self.start_pose()
        x, y, heading = self.pose.tolist()
        self.trail = [(x, y)]
        if self.physics_robot is not None:
            self.physics_robot.reset(x, y, heading)
        state = self.discretization.state(x, y, heading)
        region = self.discretization.region(x, y)
        return self._observation(state), self._info(state, False, (0.0, 0.0), region, 0, 0.0)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Apply one action (10 sub-steps of 0.1 s by default); never truncates (see class doc)."""
        commands = self.wheel_commands(action)
        self.np_random.random(out=self._noise)  # the same draws as ``random(2 · substeps)``
        if self.physics_robot is None:
            outcome = step_arrays(
                *self._task_arrays, self.pose, *commands, self.time, self._noise, self._log
            )
        else:
            outcome = physics_transition(
                self.task, self.physics_robot, self.pose, commands, self.time, self._noise,
                self._log,
            )  # fmt: skip
        reward, terminated, collided, n_logged, omega_left, omega_right, state, region, cost = (
            outcome
        )
        self.time += self._action_duration
        info = self._info(state, collided, (omega_left, omega_right), region, n_logged, cost)
        self.trail.append(info["pose"][:2])
        return self._observation(state), float(reward), bool(terminated), False, info

    def wheel_commands(self, action: Any) -> tuple[float, float]:
        """The wheel speeds (ω_L, ω_R) [rad/s] an action of this env commands; ValueError for an
        action the action space does not hold (continuous: a non-finite or misshapen one; a
        finite one outside the box is clipped)."""
        if self.action_kind == "continuous":
            return clipped_wheel_speeds(action, self.robot.wheel_speed)
        if type(action) is not int or not 0 <= action < 4:  # the common case checked fast
            if not self.action_space.contains(action):
                raise ValueError(f"expected an action in 0..3, got {action!r}")
            action = int(action)
        return self._commands[action]  # type: ignore[no-any-return]

    def state(self) -> int:
        """Flat discrete state of the current pose."""
        return self.discretization.state(*self.pose)

    def _observation(self, state: int) -> Any:
        if self.observation_kind == "discrete":
            return int(state)
        if self.observation_kind == "features":
            return self.features(self.pose)
        heading = wrap_angle(float(self.pose[2]))
        return np.array([self.pose[0], self.pose[1], heading])

    def _info(
        self,
        state: int,
        collided: bool,
        wheel_speeds: tuple[float, float],
        region: int,
        n_logged: int,
        cost: float,
    ) -> dict[str, Any]:
        """The step info of the current pose (:func:`~skidnav.envs.step_info.step_info`)."""
        cell = self.discretization.unflatten(state)
        log = self._log[:n_logged].copy()
        return step_info(self.pose.tolist(), cell, collided, wheel_speeds, region, log, cost)

    def render(self) -> Any:
        """An RGB image (H, W, 3) uint8 of the arena, or an ANSI text grid."""
        if self.render_mode == "ansi":
            return rendering.ansi_frame(self.grid_map, self.discretization, self.pose)
        if self.render_mode == "rgb_array":
            return rendering.rgb_frame(
                self.grid_map,
                self.discretization,
                self.slip_field,
                self.pose,
                self.trail,
                self.robot.body_length,
            )
        return None


def with_control_period(robot: RobotParams, control_period: float | None) -> RobotParams:
    """``robot`` with ``control_period`` [s] per action (its ``substeps`` replaced by
    ``control_period / robot.dt``), or unchanged for None; ValueError unless the period is a
    whole number ≥ 1 of sub-steps."""
    if control_period is None:
        return robot
    substeps = round(control_period / robot.dt) if math.isfinite(control_period) else 0
    if substeps < 1 or abs(substeps * robot.dt - control_period) > 1e-9:
        raise ValueError(
            f"expected control_period to be a whole number >= 1 of the robot's {robot.dt} s "
            f"sub-steps, got {control_period!r}"
        )
    return dataclasses.replace(robot, substeps=substeps)


def action_space(kind: str, robot: RobotParams) -> spaces.Space[Any]:
    """The action space of ``kind``: ``Discrete(4)``, or for "continuous" the box of wheel
    speeds (ω_L, ω_R) within ± ``robot.wheel_speed`` [rad/s], float32."""
    if kind == "discrete":
        return spaces.Discrete(4)
    limit = np.float32(robot.wheel_speed)
    return spaces.Box(low=-limit, high=limit, shape=(2,), dtype=np.float32)


def _check_same_arena(robot: RobotParams, discretization: Discretization) -> None:
    """ValueError unless the discretization's arena [m] is the robot's: the MDP clips poses to
    the robot's arena and reads cells from the discretization's, so two sizes would put walls
    and the goal where the robot is not."""
    robot_size = (robot.arena_width, robot.arena_height)
    grid_size = (discretization.arena_width, discretization.arena_height)
    if not np.allclose(robot_size, grid_size, rtol=1e-12, atol=0.0):
        raise ValueError(
            f"expected the discretization's arena {grid_size[0]:g} × {grid_size[1]:g} m to be "
            f"the robot's {robot_size[0]:g} × {robot_size[1]:g} m"
        )


def _metric_marks(
    map_file: str | Path,
    start_pose: tuple[float, float, float] | None,
    goal_disc: tuple[float, float, float] | None,
) -> tuple[tuple[float, float, float] | None, tuple[float, float, float] | None]:
    """The start pose and goal disc an env on ``map_file`` uses: those given, else the file's
    own (format version 2's ``start`` and ``goal`` lines, :mod:`skidnav.world.mapfile`)."""
    document = load_map_file(map_file)
    return (
        start_pose if start_pose is not None else document.start_pose,
        goal_disc if goal_disc is not None else document.goal,
    )


def _resolve_map(
    grid_map: GridMap | None,
    map_file: str | Path | None,
    map_kind: str,
    rng: np.random.Generator,
    discretization: Discretization | None,
) -> GridMap:
    """The map given, else read from ``map_file``, else generated (:func:`build_map`); a map of
    ``discretization``'s size (25 × 25 cells without one)."""
    if grid_map is not None:
        return grid_map
    shape = (discretization.n_x, discretization.n_y) if discretization else None
    if map_file is not None:
        return build_map(rng, file=map_file, shape=shape)
    return build_map(rng, kind=map_kind, shape=shape or (25, 25))
