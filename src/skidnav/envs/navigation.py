"""The Gymnasium environment ``skidnav/SkidSteerNav-v0``: skid-steer navigation to a goal."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from skidnav.envs import rendering
from skidnav.kernels.navigation import (
    NavigationTask,
    RewardScheme,
    build_task,
    transition,
)
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField, make_slip_field
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, generate_map
from skidnav.world.mapfile import load_map

OBSERVATION_KINDS = ("discrete", "pose")
VARIANCE_SOURCES = ("true", "observed")


class SkidSteerNavEnv(gymnasium.Env[Any, int]):
    """Drive a skid-steer robot to a goal through an arena with walls and a slippery floor.

    ## Description
    A small four-wheel skid-steer robot (SPEC §1, the thesis robot: r = 2.25 cm, c = 6 cm,
    x_ICR = 5 cm) moves in a 0.62 m × 0.505 m arena. Each action commands both wheels for
    10 × 0.1 s; the floor slows the wheels by a random, region-dependent amount (the slip field),
    and the skid makes turns slide the body sideways. The robot must reach the goal cell in as few
    actions as possible while bumping into walls as little as possible.

    ## Action Space
    ``Discrete(4)``: 0 forward (both wheels +1.7 rad/s), 1 backward (both −1.7), 2 turn left
    (ω_L −1.7, ω_R +1.7), 3 turn right (ω_L +1.7, ω_R −1.7).

    ## Observation Space
    ``Discrete(n_x · n_y · n_headings)`` (12,500 by default): the flat index
    ``(i · n_y + j) · n_headings + heading_bin`` of the discretized pose (see
    :mod:`skidnav.world.discretization`). With ``observation="pose"``: ``Box`` of
    (x [m], y [m], heading [rad] in [−π, π]).

    ## Rewards
    +10 on ending an action in the goal cell; −10 for an action that ran into a wall; otherwise
    −1 − 10·var, var being the wheel-speed variance of the region the action ends in (the slip
    field's true η²/12 with ``variance="true"``, the default; the running variance measured in
    forward actions with ``variance="observed"``, as the thesis).

    ## Starting State
    The centre of the map's start cell, heading 0 (facing +x).

    ## Episode End
    Terminated when an action ends in the goal cell. Truncated after ``max_episode_steps`` actions
    (default 500). Agents bootstrap on truncation, never on termination.

    ## Info
    ``pose`` (x, y, heading), ``cell`` (i, j, heading_bin), ``collision`` (bool), ``wheel_speeds``
    (ω_L, ω_R of the last sub-step [rad/s]), ``region`` (flat slip region at the end of the action),
    ``kinematic_log`` float64 (n_free_substeps, 6), columns [region, omega_left_cmd,
    omega_right_cmd, v_x, v_y, yaw_rate]: what the Bayesian ridge kinematic model learns from.

    ## Arguments
    ``map_kind`` ("free", "obstacles", "maze") or ``map_file`` (plain-text map) or ``grid_map``;
    ``world_seed`` (draws the map and the slip field; the map does not change between episodes);
    ``slip`` preset ("thesis", "slippery", "rough") or ``slip_field``; ``drift_amplitude`` and
    ``drift_period`` [s] (non-stationary slip; the clock runs across episodes and restarts when
    ``reset`` is given a seed); ``robot`` (:class:`RobotParams`, e.g. ``integrator="exact"``);
    ``discretization``; ``max_episode_steps``; ``observation``; ``variance``; ``render_mode``
    ("rgb_array" or "ansi").

    >>> import gymnasium, skidnav
    >>> env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1)
    >>> state, info = env.reset(seed=0)
    >>> int(env.observation_space.n), int(env.action_space.n)
    (12500, 4)
    >>> _, reward, terminated, truncated, info = env.step(0)
    >>> round(float(reward), 3), info["collision"], info["kinematic_log"].shape
    (-1.0, False, (10, 6))

    ## Version History
    v0: initial version.
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
        robot: RobotParams | None = None,
        discretization: Discretization | None = None,
        max_episode_steps: int = 500,
        observation: str = "discrete",
        variance: str = "true",
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"expected render_mode in {self.metadata['render_modes']}, got {render_mode!r}"
            )
        if observation not in OBSERVATION_KINDS:
            raise ValueError(f"expected observation in {OBSERVATION_KINDS}, got {observation!r}")
        if variance not in VARIANCE_SOURCES:
            raise ValueError(f"expected variance in {VARIANCE_SOURCES}, got {variance!r}")
        if not (isinstance(max_episode_steps, int) and max_episode_steps >= 1):
            raise ValueError(f"expected max_episode_steps >= 1, got {max_episode_steps!r}")
        self.render_mode = render_mode
        self.robot = robot or RobotParams()
        map_rng, slip_rng = (
            np.random.default_rng(s) for s in np.random.SeedSequence(world_seed).spawn(2)
        )
        self.grid_map = _resolve_map(grid_map, map_file, map_kind, map_rng, discretization)
        self.discretization = discretization or Discretization(
            n_x=self.grid_map.shape[0],
            n_y=self.grid_map.shape[1],
            arena_width=self.robot.arena_width,
            arena_height=self.robot.arena_height,
        )
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
            self.grid_map, self.slip_field, self.robot, self.discretization, rewards
        )
        self.max_episode_steps = max_episode_steps
        self.observation_kind = observation
        self.action_space = spaces.Discrete(4)  # type: ignore[assignment]
        self.observation_space: spaces.Space[Any] = (
            spaces.Discrete(self.discretization.n_states)
            if observation == "discrete"
            else spaces.Box(
                low=np.array([0.0, 0.0, -math.pi]),
                high=np.array([self.robot.arena_width, self.robot.arena_height, math.pi]),
                dtype=np.float64,
            )
        )
        self.pose = np.zeros(3)
        self.time = 0.0
        self.elapsed_steps = 0
        self.trail: list[tuple[float, float]] = []
        self._log = np.zeros((self.robot.substeps, 6))

    def start_pose(self) -> np.ndarray:
        """(x, y, heading) at the centre of the start cell, heading 0."""
        x, y = self.discretization.cell_centre(*self.grid_map.start)
        return np.array([x, y, 0.0])

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
        self.elapsed_steps = 0
        self.trail = [(float(self.pose[0]), float(self.pose[1]))]
        state = self.discretization.state(*self.pose)
        region = self.discretization.region(self.pose[0], self.pose[1])
        return self._observation(state), self._info(state, region, False, (0.0, 0.0), 0)

    def step(self, action: int) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Apply one action (10 sub-steps of 0.1 s by default)."""
        if not self.action_space.contains(action):
            raise ValueError(f"expected an action in 0..3, got {action!r}")
        noise = self.np_random.random(2 * self.robot.substeps)
        outcome = transition(self.task, self.pose, int(action), self.time, noise, self._log)
        self.time += self.robot.action_duration
        self.elapsed_steps += 1
        self.trail.append((float(self.pose[0]), float(self.pose[1])))
        truncated = not outcome.terminated and self.elapsed_steps >= self.max_episode_steps
        info = self._info(
            outcome.state,
            outcome.region,
            outcome.collided,
            (outcome.omega_left, outcome.omega_right),
            outcome.n_logged,
        )
        return (
            self._observation(outcome.state),
            float(outcome.reward),
            bool(outcome.terminated),
            truncated,
            info,
        )

    def state(self) -> int:
        """Flat discrete state of the current pose."""
        return self.discretization.state(*self.pose)

    def _observation(self, state: int) -> Any:
        if self.observation_kind == "discrete":
            return int(state)
        heading = math.atan2(math.sin(self.pose[2]), math.cos(self.pose[2]))
        return np.array([self.pose[0], self.pose[1], heading])

    def _info(
        self,
        state: int,
        region: int,
        collided: bool,
        wheel_speeds: tuple[float, float],
        n_logged: int,
    ) -> dict[str, Any]:
        x, y, heading = (float(v) for v in self.pose)
        return {
            "pose": (x, y, heading),
            "cell": self.discretization.unflatten(state),
            "collision": bool(collided),
            "wheel_speeds": (float(wheel_speeds[0]), float(wheel_speeds[1])),
            "region": int(region),
            "kinematic_log": self._log[:n_logged].copy(),
        }

    def render(self) -> Any:  # type: ignore[override]
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


def _resolve_map(
    grid_map: GridMap | None,
    map_file: str | Path | None,
    map_kind: str,
    rng: np.random.Generator,
    discretization: Discretization | None,
) -> GridMap:
    """The map given, read from a file, or generated."""
    if grid_map is not None:
        return grid_map
    if map_file is not None:
        return load_map(map_file)
    shape = (discretization.n_x, discretization.n_y) if discretization else (25, 25)
    return generate_map(map_kind, rng, shape)
