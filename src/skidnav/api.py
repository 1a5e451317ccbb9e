"""skidnav from Python: make an env, make an agent by name, train it, evaluate it, save and load
it, read the convergence episode of its training, run an experiment config.

Everything here is re-exported by the package (``skidnav.make_env``, …), imported only when
first used, so ``import skidnav`` stays fast. The functions are the command line's own parts:
the env is the registered ``skidnav/SkidSteerNav-v0``, an agent is built and trained through
the catalog (:mod:`skidnav.agents.catalog`: a tabular agent in the compiled trainer, a linear
one step by step, a deep one in its own loop, as its family decides), convergence is judged as
in every report (docs/experiments.md) and a config runs on the one runner.

>>> import skidnav
>>> env = skidnav.make_env("free", seed=1)
>>> agent = skidnav.make_agent("q-learning", env, seed=0, alpha=0.5)
>>> agent.name, agent.config.alpha
('q-learning', 0.5)
>>> [rollout.length for rollout in skidnav.evaluate(agent, env, rollouts=2, max_steps=5)]
[-1, -1]

Seeds: ``make_env(seed=…)`` draws the world (map and slip field); ``make_agent(seed=s)`` and
``train(seed=s)`` use the children of ``s`` named by :data:`skidnav.seeding.TRAINING_ROLES`
(the agent, the training episodes, the evaluation rollouts), so one integer gives one run, the
same numbers every time.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium
import pandas as pd
from tqdm import tqdm

from skidnav import API
from skidnav._jit import first_compile
from skidnav.agents.callbacks import EpisodeCallback, listening
from skidnav.agents.callbacks import EpisodeInfo as EpisodeInfo
from skidnav.agents.callbacks import StopTraining as StopTraining
from skidnav.agents.catalog import CatalogEntry, entry
from skidnav.agents.catalog import agent_names as agent_names
from skidnav.agents.greedy import Rollout, greedy_evaluation
from skidnav.agents.interface import Agent
from skidnav.agents.saved import SavedPath, load_saved_agent
from skidnav.agents.training import Evaluation, TrainingLog
from skidnav.envs.registration import ENV_ID, creation_error
from skidnav.errors import UserError, shown
from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.limits import check_setting
from skidnav.experiments.metrics import ConvergenceRule, convergence_metrics, evaluation_summary
from skidnav.experiments.runner import RunOutcome
from skidnav.experiments.store import ResultStore, RunLayout
from skidnav.seeding import TRAINING_ROLES, child_sequences, seed_int
from skidnav.world.grid import MAP_KINDS

__all__ = list(API)  # the one list of the API's names, the package's (skidnav.API)

Env = gymnasium.Env[Any, Any]
DEFAULTS: Mapping[str, Any] = {
    field.name: field.default for field in dataclasses.fields(ExperimentConfig)
}
"""An experiment config's defaults: the convergence rule and oracle settings used here too."""
NO_LIMIT = 10_000
"""Actions per episode on an env without a time limit."""


def _check_setting(function: str, name: str, value: object, setting: str) -> None:
    """UserError ``"FUNCTION: expected NAME to be …"`` unless ``value`` is within the limit of
    the experiment config's ``setting`` (:data:`skidnav.experiments.limits.SETTINGS`: the
    config, the command line and the API accept the same values)."""
    try:
        check_setting(setting, value, shown_as=name)
    except ValueError as error:
        raise UserError(f"{function}: {error}") from None


def _check_type(function: str, name: str, value: object, kinds: Any, expected: str) -> None:
    """UserError ``"FUNCTION: expected NAME to be EXPECTED, got …"`` unless ``value`` is an
    instance of ``kinds``."""
    if not isinstance(value, kinds):
        raise UserError(f"{function}: expected {name} to be {expected}, got {shown(value)}")


def _check_run(function: str, agent: object, env: object) -> None:
    """UserError unless ``agent`` is an agent and ``env`` a Gymnasium env."""
    _check_type(function, "agent", agent, Agent, "an agent (skidnav.make_agent)")
    _check_type(function, "env", env, gymnasium.Env, "a Gymnasium env (skidnav.make_env)")


def _check_limit(function: str, max_steps: object) -> None:
    """UserError unless ``max_steps`` is None (the env's limit) or an action limit."""
    if max_steps is not None:
        _check_setting(function, "max_steps", max_steps, "max_steps")


def make_env(
    map: str | Path = "obstacles",
    *,
    slip: str = "thesis",
    seed: int = 0,
    observation: str = "discrete",
    **options: Any,
) -> Env:
    """The skid-steer env ``skidnav/SkidSteerNav-v0`` on one world, made by ``gymnasium.make``
    (its 500-action time limit included; ``max_episode_steps=N`` changes it).

    Args:
        map: a map kind (``"free"``, ``"obstacles"``: the thesis arena, ``"maze"``) or the path
            of a map file.
        slip: the slip preset (``"thesis"``, ``"slippery"``, ``"rough"``, …).
        seed: the world seed: it draws the map and the slip field.
        observation: ``"discrete"`` (tabular agents), ``"features"`` or ``"pose"`` (the others).
        options: any other argument of the env (:class:`skidnav.envs.navigation.SkidSteerNavEnv`)
            or of ``gymnasium.make``.

    Raises:
        UserError: an unknown map kind, a missing map file, or an option the env refuses.
    """
    _check_type("make_env", "map", map, str | Path, "a map kind or a map file's path")
    _check_type("make_env", "slip", slip, str, "a slip preset's name")
    _check_type("make_env", "observation", observation, str, "an observation's name")
    _check_setting("make_env", "seed", seed, "root_seed")
    if isinstance(map, str) and map not in MAP_KINDS and not Path(map).exists():
        raise UserError(
            f"make_env: expected a map kind ({', '.join(MAP_KINDS)}) or a map file, got {map!r}"
        )
    where = {"map_kind": map} if isinstance(map, str) and map in MAP_KINDS else {"map_file": map}
    try:
        return gymnasium.make(
            ENV_ID, world_seed=seed, slip=slip, observation=observation, **where, **options
        )
    except (TypeError, ValueError, gymnasium.error.Error) as error:
        raise UserError(f"make_env: {creation_error(error)}") from None


def make_agent(name: str, env: Env, *, seed: int = 0, **params: Any) -> Agent:
    """A new agent ``name`` (:func:`agent_names`) for ``env`` with hyperparameters ``params``
    (the fields of its config, e.g. ``alpha=0.5, planning_steps=100``), drawing from ``seed``.

    Raises:
        UserError: an unknown agent, a bad hyperparameter, an env whose observation the agent
            does not learn over, or the agent's extra missing (one line naming it).
    """
    _check_type("make_agent", "name", name, str, "an agent's name (skidnav.agent_names())")
    _check_type("make_agent", "env", env, gymnasium.Env, "a Gymnasium env (skidnav.make_env)")
    _check_setting("make_agent", "seed", seed, "root_seed")
    described = entry(name)
    _check_observation(described, env)
    sequence = child_sequences(seed, TRAINING_ROLES)["agent"]
    agent: Agent = described.build(env.unwrapped, params, sequence, _limit(env)).agent
    return agent


def _check_observation(described: CatalogEntry, env: Env) -> None:
    """UserError unless ``env``'s observation is what the agent learns over."""
    discrete = isinstance(env.observation_space, gymnasium.spaces.Discrete)
    if discrete != (described.observation == "discrete"):
        wanted = described.env_observation(None)
        raise UserError(
            f"agent {described.name!r} learns over a {described.observation} observation: "
            f"make the env with observation={wanted!r}"
        )


def _limit(env: Env) -> int:
    """Actions per episode of ``env``: its time limit, else :data:`NO_LIMIT`."""
    limit = env.spec.max_episode_steps if env.spec is not None else None
    return int(limit or NO_LIMIT)


def _evaluation_seeds(seed: int, rollouts: int) -> list[int]:
    """The reset seeds of ``rollouts`` evaluation rollouts of ``seed`` (:data:`TRAINING_ROLES`)."""
    stream = child_sequences(seed, TRAINING_ROLES)["evaluation"]
    return [seed_int(each) for each in stream.spawn(rollouts)]


def train(
    agent: Agent,
    env: Env,
    episodes: int,
    *,
    seed: int | None = 0,
    max_steps: int | None = None,
    rollouts: int = 5,
    eval_env: Env | None = None,
    callback: EpisodeCallback | None = None,
    progress: bool = False,
) -> TrainingLog:
    """Train ``agent`` for ``episodes`` episodes on ``env`` (a deep agent: on the env it was made
    for), as its family trains (compiled for a tabular agent), and evaluate its greedy policy
    after every episode: ``rollouts`` rollouts on ``eval_env`` (default: a twin of ``env``, the
    same world), each from a reset seed of ``seed``, the same after every episode.

    Before a training whose compiled code is not cached yet (the first run after installing or
    changing skidnav: :func:`skidnav._jit.first_compile`), one line ``compiling (first run
    only)…`` goes to stderr.

    Args:
        seed: the training episodes' first reset and the evaluation seeds; None: the env's own
            generator, and one evaluation rollout that continues the twin's.
        max_steps: actions per episode, training and evaluation (default: the env's limit).
        callback: called after each episode (every family, the compiled tabular trainer
            included) with an :class:`~skidnav.agents.callbacks.EpisodeInfo` (its number from
            1, length [actions], return, success, seconds of computing, seconds since the start,
            simulated seconds of driving); returning ``False`` or raising
            :class:`~skidnav.agents.callbacks.StopTraining` stops training after that episode,
            as Stable-Baselines3's ``BaseCallback._on_step`` returning ``False`` does (CMA-ES
            after the generation under way). A callback that never stops changes no number.
        progress: a tqdm progress bar over the episodes on stderr (Stable-Baselines3's
            ``progress_bar=True``).

    Returns:
        The per-episode :class:`~skidnav.agents.training.TrainingLog` (returns, lengths,
        greedy evaluations, …) of the episodes run: :func:`convergence_episode` reads it.

    Raises:
        UserError: an argument of the wrong type, or beyond the experiment config's limit
            (:data:`skidnav.experiments.limits.SETTINGS`: ``episodes`` ≤ 10⁷, ``max_steps``
            ≤ 10⁶, ``rollouts`` ≤ 100), one line naming it.
    """
    _check_run("train", agent, env)
    if callback is not None and not callable(callback):
        raise UserError(
            f"train: expected callback to be a function of an episode's info or None, "
            f"got {shown(callback)}"
        )
    _check_type("train", "progress", progress, bool, "true or false")
    _check_setting("train", "episodes", episodes, "episodes")
    _check_setting("train", "rollouts", rollouts, "eval_rollouts")
    if seed is not None:
        _check_setting("train", "seed", seed, "root_seed")
    _check_limit("train", max_steps)
    if eval_env is not None:
        _check_type("train", "eval_env", eval_env, gymnasium.Env, "a Gymnasium env or None")
    limit = max_steps or _limit(env)
    evaluation = eval_env if eval_env is not None else _twin(env)
    seeds = None if seed is None else _evaluation_seeds(seed, rollouts)
    if seed is not None:
        env.reset(seed=seed_int(child_sequences(seed, TRAINING_ROLES)["episodes"]))
    built = entry(agent.name).bind(agent)
    measured = Evaluation(None if evaluation is None else evaluation.unwrapped, seeds)
    if first_compile((type(agent).__module__.rpartition(".")[0], "skidnav.sim")):
        print("compiling (first run only)…", file=sys.stderr, flush=True)
    if callback is None and not progress:
        return built.train(env.unwrapped, episodes, max_steps=limit, evaluation=measured)
    with (
        tqdm(total=episodes, unit="episode", disable=not progress, file=sys.stderr) as bar,
        listening(_told(bar, callback), _seconds_per_action(env)),
    ):
        return built.train(env.unwrapped, episodes, max_steps=limit, evaluation=measured)


def _told(bar: tqdm[Any], callback: EpisodeCallback | None) -> EpisodeCallback:
    """The listener of :func:`train`: advance ``bar``, then ask ``callback`` (if any)."""

    def heard(info: EpisodeInfo) -> object:
        bar.update(1)
        return None if callback is None else callback(info)

    return heard


def _seconds_per_action(env: Env) -> float:
    """Simulated seconds per action of the skid-steer env ``env`` [s]; NaN for another env."""
    robot = getattr(env.unwrapped, "robot", None)
    return float(getattr(robot, "action_duration", math.nan))


def _twin(env: Env) -> Env | None:
    """A new env of ``env``'s spec (the same world), or None for an env made without one."""
    return gymnasium.make(env.spec) if env.spec is not None else None


def evaluate(
    agent: Agent, env: Env, *, rollouts: int = 5, seed: int = 0, max_steps: int | None = None
) -> list[Rollout]:
    """``rollouts`` greedy rollouts of ``agent`` on ``env`` without learning, each from a reset
    seed of ``seed`` (the seeds :func:`train` evaluates with) and cut at ``max_steps`` actions
    (default: the env's limit); each a :class:`~skidnav.agents.greedy.Rollout` (length
    [actions] and cost, −1 and NaN where it did not reach the goal). UserError for an argument
    of the wrong type or beyond its limit, as :func:`train`."""
    _check_run("evaluate", agent, env)
    _check_setting("evaluate", "rollouts", rollouts, "eval_rollouts")
    _check_setting("evaluate", "seed", seed, "root_seed")
    _check_limit("evaluate", max_steps)
    limit = max_steps or _limit(env)
    return greedy_evaluation(agent, env, limit, _evaluation_seeds(seed, rollouts))


def save_agent(agent: Agent, path: str | Path) -> tuple[Path, Path]:
    """Save ``agent`` as ``path.npz`` + ``path.json`` (never pickle); both paths returned."""
    _check_type("save_agent", "agent", agent, Agent, "an agent (skidnav.make_agent)")
    _check_type("save_agent", "path", path, str | Path, "a path")
    return agent.save(path)


def load_agent(path: SavedPath, env: Env | None = None) -> Agent:
    """The agent saved at ``path`` by :func:`save_agent` (the path given to it, either file, or
    the pair it returned), of any family
    (:func:`skidnav.agents.saved.load_saved_agent`; a deep agent needs the ``env`` it acts in).
    """
    pair = isinstance(path, list | tuple) and len(path) == 2
    if not (
        isinstance(path, str | Path) or (pair and all(isinstance(p, str | Path) for p in path))
    ):
        raise UserError(
            f"load_agent: expected path to be a path or a pair of paths, got {shown(path)}"
        )
    if env is not None:
        _check_type("load_agent", "env", env, gymnasium.Env, "a Gymnasium env or None")
    return load_saved_agent(path, env)


def convergence_episode(
    log: TrainingLog,
    env: Env,
    *,
    tolerance: float = DEFAULTS["convergence_tolerance"],
    window: int = DEFAULTS["convergence_window"],
    level: float = DEFAULTS["convergence_level"],
) -> int | None:
    """The episode (from 1) after which the greedy policy of a training ``log`` on ``env`` had
    converged, or None when it had not by the end of the log.

    As in every report (docs/experiments.md, :mod:`skidnav.experiments.metrics`): an evaluation
    passes when every rollout reached the goal in at most (1 + ``tolerance``) · L* actions on
    average, L* the oracle's expected length from the start on ``env``'s world (computed once
    and cached); the convergence episode is the first passing one from which at least a share
    ``level`` of the evaluations pass to the end, over at least ``window`` of them.

    Raises:
        UserError: ``env`` is not the skid-steer env on kinematic dynamics (no oracle).
    """
    _check_type("convergence_episode", "log", log, TrainingLog, "a training log (skidnav.train)")
    _check_setting("convergence_episode", "tolerance", tolerance, "convergence_tolerance")
    _check_setting("convergence_episode", "window", window, "convergence_window")
    _check_setting("convergence_episode", "level", level, "convergence_level")
    rule = ConvergenceRule(_reference_length(env, "convergence_episode"), tolerance, window, level)
    mean, share = evaluation_summary(log.greedy_lengths)
    episodes = {"greedy_length": mean, "greedy_success": share, "length": log.lengths}
    metrics = convergence_metrics(episodes, rule)
    return int(metrics["convergence_episode"]) if metrics["converged"] else None


def reference_length(env: Env) -> float:
    """L* of ``env``'s world [actions]: the oracle's expected number of actions from the start
    (:mod:`skidnav.experiments.reference.oracle`, :data:`DEFAULTS`' sample count, seed 0), what
    :func:`convergence_episode` judges a training log against.

    Raises:
        UserError: ``env`` is not the skid-steer env on kinematic dynamics (no oracle).
    """
    return _reference_length(env, "reference_length")


def _reference_length(env: Env, function: str) -> float:
    """:func:`reference_length`, its error naming the API ``function`` called."""
    from skidnav.experiments.reference.oracle import load_or_compute_oracle

    nav = getattr(env, "unwrapped", None)
    if (
        not isinstance(env, gymnasium.Env)
        or env.spec is None
        or env.spec.id != ENV_ID
        or getattr(nav, "dynamics", "") != "kinematic"
    ):
        raise UserError(f"{function}: expected a skidnav/SkidSteerNav-v0 env on kinematic "
                        "dynamics (its oracle gives the optimal length)")  # fmt: skip
    discrete = gymnasium.make(env.spec, observation="discrete").unwrapped
    limit = _limit(env)
    oracle = load_or_compute_oracle(discrete, DEFAULTS["oracle_samples"], 0, [0], limit)
    return float(oracle.start_value)


@dataclasses.dataclass(frozen=True)
class RunResults:
    """What :func:`run_config` did, and its results.

    Attributes:
        out_dir: the results directory. outcome: runs in the grid, run now, already done, time.
        layout: what the results directory holds (experiment or study).
    """

    out_dir: Path
    outcome: RunOutcome
    layout: RunLayout

    def tables(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        """(episodes, summaries): the tidy Parquet tables, one row per episode of every run and
        one per run (docs/experiments.md, "Results")."""
        return ResultStore(self.out_dir, self.layout).load_tables()


def run_config(
    config: str | Path,
    out: str | Path | None = None,
    *,
    backend: str | None = None,
    jobs: int | None = None,
    progress: bool = False,
) -> RunResults:
    """Run (or resume) the experiment or study config at ``config`` into ``out`` (default
    ``runs/<name>``), as ``skidnav run`` does: the same runs, files and resume, on ``backend``
    (``"serial"``, ``"process"`` (the default), ``"dask"``) with ``jobs`` workers.

    Raises:
        UserError: the config is invalid (one line naming the file and key), ``out`` holds other
            results or is in use, or the backend's extra is missing.
        RunsFailedError: runs raised; the finished ones are kept for a resume.
    """
    from skidnav.files.outputs import check_output_dir
    from skidnav.studies.loading import load_grid, run_loaded

    _check_type("run_config", "config", config, str | Path, "a config file's path")
    _check_type("run_config", "out", out, str | Path | None, "a folder's path or None")
    _check_type("run_config", "backend", backend, str | None, "a backend's name or None")
    if jobs is not None:
        _check_type("run_config", "jobs", jobs, int, "a number of workers or None")
    _check_type("run_config", "progress", progress, bool, "true or false")
    loaded = load_grid(Path(config))
    folder = Path(out) if out is not None else Path("runs") / loaded.grid.name
    outcome = run_loaded(
        loaded, check_output_dir(folder), backend=backend, jobs=jobs, progress=progress
    )
    return RunResults(outcome.out_dir, outcome, loaded.layout)
