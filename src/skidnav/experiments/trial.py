"""One run of the grid: build the world, train the agent, measure it (a pure function of its spec).

:func:`run_trial` takes a :class:`~skidnav.experiments.runs.RunSpec` and returns a
:class:`~skidnav.experiments.store.TrialResult`; it draws every random number from the run's two
seed streams (world: map and slip field; run: agent and episodes), so it gives the same numbers in
any process, on any Dask worker, in any order. Only ``wall_time`` differs between machines.

``wall_time`` measures training only: before the first run of an agent variant in a process,
:func:`warm_up` trains a throwaway copy of it for a few short episodes on a throwaway world, so
numba compiles (or loads from its cache) every kernel the run will call before the run's clock
starts. The warm-up draws from its own generators, never from the run's streams, so it changes no
number.

Agents of every family (:mod:`skidnav.agents.catalog`: tabular, linear on continuous
observations, deep) are built and trained through one door, the catalog entry of their name.
Tabular agents train in the compiled trainer
``skidnav.agents.tabular.fast_training.train_agent_fast``
for the skid-steer environment when it supports the agent, else in
``skidnav.agents.training.train_agent`` (which it falls back to on its own, e.g. for
``[env] dynamics = "mujoco"``, the physical robot, whose runs have no oracle); linear agents
train in ``train_agent``; a deep agent trains in its own loop with the same evaluations.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np

from skidnav.agents.catalog import CatalogAgent, entry
from skidnav.agents.greedy import greedy_path
from skidnav.agents.interface import Agent
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.agents.trained_world import trained_world
from skidnav.agents.training import Evaluation, TrainingLog
from skidnav.envs.registration import (
    allowed_env_modules,
    registered_env_id,
    with_env_modules,
)
from skidnav.envs.wrappers import FineStates
from skidnav.experiments.config import (
    CONVERGENCE_OBJECTIVES,
    AgentSpec,
    ExperimentConfig,
    MapSpec,
    freeze_params,
)
from skidnav.experiments.metrics import (
    ConvergenceRule,
    DrivingClock,
    evaluation_summary,
    run_metrics,
)
from skidnav.experiments.reference.finegrid import refines_positions, state_grid
from skidnav.experiments.reference.world import warm_up_references, world_reference
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import EPISODE_COLUMNS, TrialResult
from skidnav.experiments.value_maps import policy_map, value_maps
from skidnav.seeding import RUN_ROLES, WORLD_ROLES, child_sequences, seed_int
from skidnav.world.discretization import Discretization, heading_bin
from skidnav.world.grid import GridMap, border_walls, refine_map
from skidnav.world.maps import build_map

logger = logging.getLogger(__name__)

ExperimentRun = RunSpec[ExperimentConfig]
"""One run of an experiment config (``skidnav run``)."""

SKID_ENV_ID = "skidnav/SkidSteerNav-v0"
WARM_UP_LIMITS = (10, 300, 10, 10, 60, 10)
"""Action limits of the :func:`warm_up` episodes. Its arena is 6 × 6 cells with the goal right
ahead of the start, so short episodes end at the goal or run into walls between two model refits;
the long one makes learned models outgrow their first arrays and refit. Milliseconds in all."""
WARM_UP_REFITS = {
    "kinematic_min_samples": 1, "kinematic_refit_every": 1, "kinematic_refit_growth": 0.0,
}  # fmt: skip
"""The kinematic-model schedule of a second warm-up agent, where the config has one: every region
refitted at every episode end. The run's own schedule (500 new samples by default) is not
reached in the warm-up's few actions, so without it the refit kernels (Bayesian ridge, the rings'
moments) compiled on the run's clock: 8.3 s of dyna-full's first episode with a cold numba
cache. The first agent, on the run's schedule, compiles the episode ends without a refit."""
_warmed_up: set[tuple[Any, ...]] = set()
"""(env id, agent name, parameters[, finer cells]) of the agent variants this process has warmed
up."""


def config_map(entry: MapSpec, rng: np.random.Generator) -> GridMap:
    """The map of one ``[[maps]]`` entry of a config (:func:`skidnav.world.maps.build_map`):
    read from its file, or generated with ``rng`` and its options."""
    return build_map(rng, kind=entry.kind, file=entry.file or None, options=dict(entry.options))


def trial_env(
    spec: ExperimentRun, grid_map: GridMap, slip_seed: int, observation: str | None = None
) -> gymnasium.Env[Any, Any]:
    """The environment of a run, as ``gymnasium.make`` gives it (wrappers included).

    ``env_id`` is a registered Gymnasium id (e.g. ``skidnav/DynaMaze-v0``; ``module:Env-v0``
    only for a module the user allowed, :func:`~skidnav.envs.registration.registered_env_id`),
    made with the ``[env]`` options: nothing named in a config is imported or called. Only the
    skid-steer env receives the map, slip preset and drift of the run, and the observation its
    agent learns over (:meth:`skidnav.agents.catalog.AgentEntry.env_observation`: the discrete
    state for a tabular agent, else ``[env] observation``, "features" by default;
    ``observation`` overrides both).
    Gymnasium's ``TimeLimit`` truncates after the config's ``max_steps`` actions, else its
    ``[env] max_episode_steps``, else the registered limit (:func:`action_limit` reads it
    back). Runs train and evaluate on ``env.unwrapped``: the trainer enforces that limit itself.

    An agent's ``discretization`` (n_x, n_y, n_headings) with the map's cells becomes the env's own
    discretization (finer heading bins, the compiled trainer); one with finer cells than the map's
    leaves the env on poses, which :func:`agent_view` turns into the states of the finer grid
    (:class:`~skidnav.envs.wrappers.FineStates`). ``observation`` overrides both.
    """
    config = spec.config
    options: dict[str, Any] = dict(config.env_options)
    from_env = options.pop("max_episode_steps", None)
    limit = config.max_steps or from_env
    if limit is not None and (
        isinstance(limit, bool) or not (isinstance(limit, int) and limit >= 1)
    ):
        raise ValueError(f"expected [env] max_episode_steps to be an integer >= 1, got {limit!r}")
    if config.env_id == SKID_ENV_ID:
        levels = spec.agent.discretization
        if levels and observation is None:
            if refines_positions(levels, grid_map):
                observation = "pose"
            else:
                options["discretization"] = Discretization(*levels)
        requested = options.get("observation")
        options.update(
            observation=observation or entry(spec.agent.name).env_observation(requested),
            grid_map=grid_map,
            world_seed=slip_seed,
            slip=spec.preset,
            drift_amplitude=config.drift_amplitude,
            drift_period=config.drift_period,
        )
    return gymnasium.make(registered_env_id(config.env_id), max_episode_steps=limit, **options)


def agent_view(spec: ExperimentRun, env: gymnasium.Env[Any, Any]) -> gymnasium.Env[Any, Any]:
    """What a run's agent trains and is evaluated on: ``env.unwrapped``, seen through the finer
    states of the agent's ``discretization`` when it refines the map's cells (:func:`trial_env`)."""
    nav = env.unwrapped
    levels = spec.agent.discretization
    if refines_positions(levels, getattr(nav, "grid_map", None)):
        return FineStates(nav, state_grid(nav, levels))
    return nav


def action_limit(env: gymnasium.Env[Any, Any]) -> int:
    """Actions per episode of a run on ``env`` (from :func:`trial_env`): its time limit
    (``env.spec.max_episode_steps``), or 10,000 for an env registered without one."""
    limit = env.spec.max_episode_steps if env.spec is not None else None
    return int(limit or 10_000)


def action_duration(env: gymnasium.Env[Any, Any]) -> float:
    """Seconds one action of ``env`` lasts: its robot's ``dt × substeps``
    (:attr:`~skidnav.robot.params.RobotParams.action_duration`, after the env's
    ``control_period``; the kinematic and the MuJoCo robot alike), NaN for an env without a
    robot (e.g. a grid world)."""
    robot = getattr(env.unwrapped, "robot", None)
    duration = getattr(robot, "action_duration", None)
    return float(duration) if isinstance(duration, int | float) else math.nan


def _world_arrays(
    agent: Agent, grid_map: GridMap, env: gymnasium.Env[Any, Any]
) -> dict[str, np.ndarray]:
    """Walls, start, goal and slip η of a skid-steer run, and of a tabular agent its value,
    heading and policy maps (on the agent's finer grid, and the map refined to it, for an agent
    seeing :class:`~skidnav.envs.wrappers.FineStates`)."""
    grid = getattr(env, "discretization", None)
    nav: Any = env
    if isinstance(env, FineStates):
        grid_map = refine_map(grid_map, (env.discretization.n_x, env.discretization.n_y))
        nav = env.unwrapped
    start_heading = float(nav.start_pose()[2])
    arrays = {
        "start_heading": np.asarray(start_heading),
        "occupancy": grid_map.occupancy,
        "start": np.asarray(grid_map.start),
        "goal": np.asarray(grid_map.goal),
        "slip_eta": nav.slip_field.eta,
    }
    if isinstance(agent, TabularAgent):
        value, heading = value_maps(agent.q, grid_map)
        n_headings = int(grid.n_headings)  # type: ignore[union-attr]
        arrays.update(
            value_map=value,
            heading_map=heading,
            policy_map=policy_map(agent.q, grid_map, heading_bin(start_heading, n_headings)),
        )
    return arrays


def _episode_arrays(log: TrainingLog) -> dict[str, np.ndarray]:
    """The TrainingLog as record columns: each evaluation's R rollouts become their mean length
    and their mean cost over those that reached the goal (NaN if none) and the share that did."""
    greedy, reached = evaluation_summary(log.greedy_lengths)
    cost, _ = evaluation_summary(log.greedy_lengths, log.greedy_costs)
    arrays = {
        "return": np.asarray(log.returns, dtype=np.float64),
        "length": np.asarray(log.lengths, dtype=np.int64),
        "success": np.asarray(log.successes, dtype=bool),
        "collisions": np.asarray(log.collisions, dtype=np.int64),
        "planning_updates": np.asarray(log.planning_updates, dtype=np.int64),
        "wall_time": np.asarray(log.wall_time, dtype=np.float64),
        "greedy_length": greedy,
        "greedy_success": reached,
        "greedy_cost": cost,
    }
    assert set(arrays) == set(EPISODE_COLUMNS)
    return arrays


def _world(
    spec: ExperimentRun, map_rng: np.random.Generator, slip_seed: int
) -> tuple[GridMap | None, gymnasium.Env[Any, Any], gymnasium.Env[Any, Any], int]:
    """(map or None, training env, evaluation env, action limit) of a run, the map drawn with
    ``map_rng``; the envs unwrapped (:func:`trial_env`)."""
    skid = spec.config.env_id == SKID_ENV_ID
    grid_map = config_map(spec.map, map_rng) if skid else None
    env = trial_env(spec, grid_map, slip_seed)  # type: ignore[arg-type]
    eval_env = trial_env(spec, grid_map, slip_seed)  # type: ignore[arg-type]
    return grid_map, agent_view(spec, env), agent_view(spec, eval_env), action_limit(env)


def _oracle_env(
    spec: ExperimentRun, grid_map: GridMap, slip_seed: int, eval_env: gymnasium.Env[Any, Any]
) -> gymnasium.Env[Any, Any]:
    """The evaluation env on the discrete state, which the oracle solves: ``eval_env`` itself
    for a tabular agent, else a twin of it (same world and limit; the oracle and its cache are
    the same for every agent of a world)."""
    if isinstance(eval_env.observation_space, gymnasium.spaces.Discrete):
        return eval_env
    return trial_env(spec, grid_map, slip_seed, observation="discrete").unwrapped


def _agent(
    spec: ExperimentRun, env: gymnasium.Env[Any, Any], seed: np.random.SeedSequence, max_steps: int
) -> CatalogAgent:
    """A new agent of the run's variant for ``env``, of whichever family, with its family's
    training (:meth:`skidnav.agents.catalog.AgentEntry.build`)."""
    return entry(spec.agent.name).build(env, spec.agent.params_dict(), seed, max_steps)


def warm_up(spec: ExperimentRun) -> None:
    """Train a throwaway copy of the run's agent variant for a few short episodes on a throwaway
    world, once per process and variant, so the kernels the run calls are compiled before its
    clock starts (module docs). Draws only from its own generators."""
    key: tuple[Any, ...] = (spec.config.env_id, spec.agent.name, repr(spec.agent.params))
    levels = spec.agent.discretization
    if levels:  # the same kernels, or the plain loop over finer states (docs/discretization-gap.md)
        fine = refines_positions(levels, config_map(spec.map, np.random.default_rng(0)))
        key += (fine,)
    if key in _warmed_up:
        return
    grid_map = None
    if spec.config.env_id == SKID_ENV_ID:
        grid_map = GridMap(border_walls((6, 6)), start=(1, 1), goal=(2, 1))
        agent = spec.agent
        if levels:
            side = 11 if fine else 6
            agent = dataclasses.replace(agent, discretization=(side, side, levels[2]))
        spec = dataclasses.replace(
            spec, agent=agent,
            config=dataclasses.replace(spec.config, max_steps=max(WARM_UP_LIMITS)),
        )  # fmt: skip
    made = (trial_env(spec, grid_map, 0) for _ in range(2))  # type: ignore[arg-type]
    env, eval_env = (agent_view(spec, each) for each in made)
    env.reset(seed=1)
    eval_env.reset(seed=2)
    built = _agent(spec, env, np.random.SeedSequence(3), max(WARM_UP_LIMITS))
    evaluation = Evaluation(eval_env if spec.config.greedy_eval else None, [2, 3])
    for limit in WARM_UP_LIMITS:
        built.train(env, 1, max_steps=limit, evaluation=evaluation)
    refitting = dataclasses.replace(spec, agent=_refitting(spec.agent))
    if refitting != spec:  # and the refit kernels (WARM_UP_REFITS)
        again = _agent(refitting, env, np.random.SeedSequence(4), max(WARM_UP_LIMITS))
        again.train(env, 2, max_steps=max(WARM_UP_LIMITS), evaluation=evaluation)
    greedy_path(built.agent, eval_env, max(WARM_UP_LIMITS), seed=2)
    if grid_map is not None:
        _world_arrays(built.agent, grid_map, env)
    if grid_map is not None:
        oracle_env = functools.partial(_oracle_env, spec, grid_map, 0, eval_env)
        warm_up_references(eval_env, oracle_env, 2, max(WARM_UP_LIMITS))
    _warmed_up.add(key)


def _refitting(agent: AgentSpec) -> AgentSpec:
    """``agent`` with :data:`WARM_UP_REFITS` in its parameters where its config has them."""
    config_class: Any = entry(agent.name).config_class  # a frozen dataclass (AgentConfig)
    fields = {field.name for field in dataclasses.fields(config_class)}
    refits = {name: value for name, value in WARM_UP_REFITS.items() if name in fields}
    return dataclasses.replace(agent, params=freeze_params(agent.params_dict() | refits))


def run_trial(spec: ExperimentRun) -> TrialResult:
    """Train and measure one run of the grid (see module docs)."""
    warm_up(spec)
    return measure_trial(spec)


def default_trial() -> Callable[[ExperimentRun], TrialResult]:
    """:func:`run_trial`, which a worker process runs after importing the environment modules
    the user allowed in this process (:func:`~skidnav.envs.registration.allow_env_modules`)."""
    modules = allowed_env_modules()
    return functools.partial(with_env_modules, modules, run_trial) if modules else run_trial


def measure_trial(spec: ExperimentRun) -> TrialResult:
    """:func:`run_trial` without the warm-up: the first call in a process also times numba's
    compilation of the kernels.

    Seeds: the world stream gives the map, the slip field, the evaluation seeds and the oracle's
    sampling seed (so every agent of a world meets the same evaluations: common random numbers);
    the run stream gives the agent and the training episodes."""
    config = spec.config
    world_streams = child_sequences(spec.world_seed.sequence(), WORLD_ROLES)
    run_streams = child_sequences(spec.run_seed.sequence(), RUN_ROLES)
    map_rng = np.random.default_rng(world_streams["map"])
    slip_seed = seed_int(world_streams["slip"])
    grid_map, env, eval_env, max_steps = _world(spec, map_rng, slip_seed)
    evaluation = world_streams["evaluation"].spawn(config.eval_rollouts)
    eval_seeds = [seed_int(s) for s in evaluation]
    env.reset(seed=seed_int(run_streams["episodes"]))
    built = _agent(spec, env, run_streams["agent"], max_steps)
    envs = None
    if grid_map is not None:
        oracle_env = functools.partial(_oracle_env, spec, grid_map, slip_seed, eval_env)
        pose_env = functools.partial(trial_env, spec, grid_map, slip_seed, observation="pose")
        envs = (oracle_env, pose_env)
    world = world_reference(config, eval_env, envs, world_streams["oracle"], eval_seeds, max_steps)
    measured = Evaluation(eval_env if config.greedy_eval else None, eval_seeds)
    log = built.train(env, config.episodes, max_steps=max_steps, evaluation=measured)
    episodes = _episode_arrays(log)
    poses, reached = greedy_path(built.agent, eval_env, max_steps, seed=eval_seeds[0])
    arrays = {"greedy_poses": poses}
    if grid_map is not None:
        arrays.update(_world_arrays(built.agent, grid_map, env))
    rule = None
    optimum = world.optimum(config.convergence_objective)
    if math.isfinite(optimum) and config.greedy_eval:
        rule = ConvergenceRule(
            optimum, config.convergence_tolerance, config.convergence_window,
            config.convergence_level, CONVERGENCE_OBJECTIVES[config.convergence_objective],
        )  # fmt: skip
    clock = DrivingClock(action_duration(env), config.convergence_window)
    summary = run_metrics(episodes, poses, reached, rule, clock)
    summary["action_limit"] = float(max_steps)
    summary.update(world.summary_columns(rule))
    files = agent_files(built.agent, env) if config.save_agents else {}
    return TrialResult(spec.run_id, spec.coordinates, episodes, summary, arrays, files)


def agent_files(agent: Agent, env: gymnasium.Env[Any, Any]) -> dict[str, bytes]:
    """The files of a trained ``agent`` kept beside its run file (``[experiment] save_agents``),
    by name: ``agent.npz`` and ``agent.json`` as its family's own ``save`` writes them (here
    into a temporary folder, so that a worker process or a Dask worker hands back bytes, never
    the agent), and, on the skid-steer env ``env`` (the agent's view of it), ``world.json`` and
    ``map.txt``: the world it was trained for (:mod:`skidnav.agents.trained_world`)."""
    with tempfile.TemporaryDirectory(prefix="skidnav-agent-") as folder:
        paths = agent.save(Path(folder) / "agent")
        files = {path.name: path.read_bytes() for path in paths}
    world = trained_world(agent.name, env)
    if world is not None:
        files.update(world.files())
    return files
