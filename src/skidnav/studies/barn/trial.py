"""One run of a BARN study: one agent on one world and floor, scored by the benchmark's rules.

The env (:func:`barn_env`): the world's map, start pose, goal point and radius (as the shipped
archive has them), the Jackal, the floor's slip preset, the agent's action and observation
(:mod:`skidnav.studies.barn.agents`), one action lasting ``control_period`` seconds.

A **scored run** (:func:`scored_run`) is one BARN run of the agent's greedy policy from a reset,
on an env at the benchmark's 10 Hz (``control_period = 0.1``), judged every 0.1 s by
:class:`~skidnav.studies.barn.rules.BarnClock` and stopped at the first of success, collision
and timeout, whatever the env itself terminates on. A discrete agent whose actions last longer
(the config's ``discrete_action_duration``, k periods of 0.1 s) chooses every k periods and its
action is held for them: the same motion, the same draws of the floor's noise and the same
collision checks, sub-step by sub-step, as one action of the training env, but judged as
``run.py`` judges, every 0.1 s.

* **zero-shot**: a new agent's scored run, its first episode in a world it has never seen;
* **learning**: ``episodes`` times, one training episode (the agent's own episode on the env's
  rules, with actions of the agent's duration, at most 100 s: :func:`training_actions`) and
  then one scored run.

Seeds: the world stream (shared by every agent of a world, floor and seed) gives the slip field
and the reset seed of every scored run; the run stream gives the agent and its training
episodes. So two agents' scored runs of a world meet the same floor noise, and pair.
"""

from __future__ import annotations

import time
from typing import Any

import gymnasium
import numpy as np

from skidnav.agents.catalog import CatalogAgent, entry
from skidnav.agents.greedy import Greedy, as_state, start_rollout
from skidnav.envs.registration import registered_env_id
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import TrialResult
from skidnav.seeding import RUN_ROLES, WORLD_ROLES, child_sequences, seed_int
from skidnav.studies.barn.agents import (
    LIDAR_FOV,
    LIDAR_RANGE,
    action_duration,
    agent_params,
    env_interface,
)
from skidnav.studies.barn.grid import (
    CONTROL_PERIOD,
    EPISODE_COLUMNS,
    BarnGrid,
    quintile,
    world_number,
)
from skidnav.studies.barn.rules import BarnClock, BarnOutcome
from skidnav.world.barn import TIME_LIMIT, BarnWorld, load_barn_world

ENV_ID = "skidnav/SkidSteerNav-v0"
"""The env every run drives."""
ROBOT = "jackal"
"""The benchmark's robot."""

BarnRun = RunSpec[BarnGrid]
"""One run of a BARN grid."""


def training_actions(duration: float) -> int:
    """Most actions of a training episode with actions of ``duration`` [s]: the benchmark's
    100 s (1000 actions of 0.1 s)."""
    return round(TIME_LIMIT / duration)


def barn_env(
    spec: BarnRun, world: BarnWorld, slip_seed: int, control_period: float = CONTROL_PERIOD
) -> gymnasium.Env[Any, Any]:
    """The unwrapped env of a run (module doc) on ``world`` (its map, start pose and goal
    disc), its slip field drawn from ``slip_seed``, actions of ``control_period`` [s]; without
    a time limit (the rules end every run)."""
    grid = spec.config
    options: dict[str, Any] = dict(
        grid_map=world.map.grid,
        start_pose=world.start_pose,
        goal_disc=(*world.goal, world.goal_radius),
        discretization=world.discretization,
        robot=ROBOT,
        control_period=control_period,
        slip=spec.preset,
        world_seed=slip_seed,
        dynamics=grid.dynamics,
        lidar_rays=grid.lidar_rays,
        lidar_range=LIDAR_RANGE,
        lidar_fov=LIDAR_FOV,
        **env_interface(spec.agent.name),
    )
    return gymnasium.make(registered_env_id(ENV_ID), **options).unwrapped


def scored_run(
    agent: Greedy, env: gymnasium.Env[Any, Any], world: BarnWorld, seed: int, periods: int = 1
) -> tuple[BarnOutcome, np.ndarray]:
    """One BARN run of ``agent``'s greedy policy on ``env`` (0.1-s actions) from
    ``env.reset(seed=seed)`` (a policy with a state of its own forgets it first), the policy
    choosing every ``periods`` actions and its choice held for them (module doc); the outcome
    and the poses float32 (T + 1, 3) (x [m], y [m], heading [rad]: the reset's, then one per
    0.1-s action)."""
    observation, info = env.reset(seed=seed)
    start_rollout(agent)
    poses = [info["pose"]]
    start = (float(info["pose"][0]), float(info["pose"][1]))
    clock = BarnClock(start, world.goal, world.goal_radius, control_period=CONTROL_PERIOD)
    ended, action = False, None
    while not ended:
        if (len(poses) - 1) % periods == 0:
            action = agent.greedy_action(as_state(observation))
        observation, _, _, _, info = env.step(action)
        poses.append(info["pose"])
        ended = clock.step((info["pose"][0], info["pose"][1]), bool(info["collision"]))
    return clock.outcome(world.optimal_time), np.asarray(poses, dtype=np.float32)


class Rows:
    """The episode rows of a run (:data:`~skidnav.studies.barn.grid.EPISODE_COLUMNS`) and the
    poses of its scored runs, one scored run at a time, for an agent whose training actions
    last ``action_duration`` [s]."""

    def __init__(self, world: BarnWorld, action_duration: float = CONTROL_PERIOD) -> None:
        self.world = world
        self.action_duration = action_duration
        self.columns: dict[str, list[float]] = {key: [] for key in EPISODE_COLUMNS}
        self.poses: list[np.ndarray] = []
        self.driving_seconds = 0.0

    def add(
        self, outcome: BarnOutcome, poses: np.ndarray, training_actions: int, wall_time: float
    ) -> None:
        """Record one scored run after a training episode of ``training_actions`` actions that
        took ``wall_time`` [s] (0 and 0 for zero-shot)."""
        self.driving_seconds += training_actions * self.action_duration
        row = {
            "world": self.world.number,
            "quintile": quintile(self.world.number),
            "success": outcome.success,
            "collision": outcome.collision,
            "timeout": outcome.timeout,
            "time": outcome.time,
            "metric": outcome.metric,
            "optimal_time": self.world.optimal_time,
            "clock_start": outcome.clock_start,
            "scored_actions": outcome.actions,
            "training_actions": training_actions,
            "driving_seconds": self.driving_seconds,
            "wall_time": wall_time,
        }
        for key, value in row.items():
            self.columns[key].append(value)
        self.poses.append(poses)

    def episodes(self) -> dict[str, np.ndarray]:
        """The rows as arrays, one value per scored run (0/1 columns as bool)."""
        flags = ("success", "collision", "timeout")
        return {
            key: np.asarray(values, dtype=bool if key in flags else np.float64)
            for key, values in self.columns.items()
        }

    def arrays(self) -> dict[str, np.ndarray]:
        """``poses`` (all scored runs' poses, one run after the other) and ``pose_counts``."""
        return {
            "poses": np.concatenate(self.poses).astype(np.float32),
            "pose_counts": np.array([len(poses) for poses in self.poses], dtype=np.int64),
        }


def summary(episodes: dict[str, np.ndarray], world: BarnWorld) -> dict[str, float]:
    """The run's summary: the world, its quintile and OT [s]; the last scored run's metric and
    success; the best metric; the first episode whose scored run succeeded and the seconds of
    training driving up to it (NaN when none did)."""
    succeeded = np.flatnonzero(episodes["success"])
    first = int(succeeded[0]) if succeeded.size else -1
    return {
        "world": float(world.number),
        "quintile": float(quintile(world.number)),
        "optimal_time": world.optimal_time,
        "metric": float(episodes["metric"][-1]),
        "success": float(episodes["success"][-1]),
        "best_metric": float(episodes["metric"].max()),
        "first_success_episode": float(first + 1) if first >= 0 else np.nan,
        "seconds_to_first_success": float(episodes["driving_seconds"][first])
        if first >= 0
        else np.nan,
        "driving_seconds": float(episodes["driving_seconds"][-1]),
    }


def train_one(
    built: CatalogAgent, env: gymnasium.Env[Any, Any], seed: int | None, max_steps: int
) -> tuple[int, float]:
    """One training episode of ``built`` on ``env`` (from ``env.reset(seed=seed)``, None: the
    env's own generator), cut at ``max_steps`` actions; (its actions, its wall time [s])."""
    started = time.perf_counter()
    log = built.train(env, 1, max_steps=max_steps, seed=seed)
    return int(log.lengths[0]), time.perf_counter() - started


def barn_trial(spec: BarnRun) -> TrialResult:
    """The runner's trial function of a BARN study: the run of the module doc."""
    grid = spec.config
    world = load_barn_world(world_number(spec.map.label))
    world_streams = child_sequences(spec.world_seed.sequence(), WORLD_ROLES)
    run_streams = child_sequences(spec.run_seed.sequence(), RUN_ROLES)
    slip_seed = seed_int(world_streams["slip"])
    reset_seed = seed_int(world_streams["evaluation"])
    duration = action_duration(spec.agent.name, grid)
    periods = round(duration / CONTROL_PERIOD)
    env = barn_env(spec, world, slip_seed, duration)
    scoring_env = barn_env(spec, world, slip_seed)
    described = entry(spec.agent.name)
    params = agent_params(spec.agent, grid, described)
    limit = training_actions(duration)
    built = described.build(env, params, run_streams["agent"], limit)
    rows = Rows(world, duration)

    def score() -> tuple[BarnOutcome, np.ndarray]:
        return scored_run(built.agent, scoring_env, world, reset_seed, periods)

    if grid.protocol == "zero-shot":
        rows.add(*score(), 0, 0.0)
    else:
        episode_seed: int | None = seed_int(run_streams["episodes"])
        for _ in range(grid.episodes):
            actions, wall_time = train_one(built, env, episode_seed, limit)
            episode_seed = None  # later episodes continue the env's generator
            rows.add(*score(), actions, wall_time)
    episodes = rows.episodes()
    return TrialResult(
        spec.run_id, spec.coordinates, episodes, summary(episodes, world), rows.arrays()
    )
