"""What continuity buys, measured: discrete agents against wheel-speed learners on one world
(``skidnav study continuity``, or a ``kind = "continuity"`` config run by ``skidnav run``:
:mod:`skidnav.studies.continuity.study`; docs/continuity.md).

Every learner of :data:`LEARNERS` trains on the same world (map, slip field) from the same seeds,
and its final deterministic policy is rolled out from the start on the same evaluation seeds
(common random numbers: every policy meets the same slip noise); each rollout is a
:class:`~skidnav.studies.continuity.traces.Trace` and gives the metrics of
:mod:`skidnav.studies.continuity.traces`. The learners:

* ``q-learning`` and ``dyna-full`` (the thesis's agents, discrete actions; the fused trainer),
* ``cmaes`` (policy search, :mod:`skidnav.agents.policies.search`), ``ppo`` and ``sac``
  (Stable-Baselines3, :mod:`skidnav.agents.deep`) on ``action="continuous"``,
* ``mppi-kinematic`` (:mod:`skidnav.agents.mpc`), model predictive control through the learned
  kinematic model on ``action="continuous"``, planning :data:`MPPI_LOOKAHEAD` seconds ahead
  whatever the control period (:func:`mppi_params`),
* ``goal-tracker``, the reference controller that ignores walls (nothing learned).

**Real episodes to learn** [episodes]: the training episodes consumed until the learner's
greedy policy first reached the goal in every evaluation rollout of a check (discrete, deep and
model-predictive learners: a check after every episode on the evaluation seeds; CMA-ES: its mean
policy, checked every ``eval_every`` generations on its own evaluation seeds); NaN if never
within the budget. Every kind of action uses the same control period, so times and energies
compare. The final policies are deterministic, except ``mppi-kinematic``'s frozen planner, which
samples from a generator of its own seeded alike for every rollout (the same numbers for the
same observations).

A :class:`ComparisonConfig` is the runner's grid (:class:`~skidnav.experiments.runs.Grid`): the
learners are its agents, the world its one map and preset, and seed index k of every learner is
one world of the runner, whose stream (:func:`run_seed`) every learner's run k trains from.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

import gymnasium
import numpy as np

from skidnav.agents.catalog import entry
from skidnav.agents.mpc.config import MAX_HORIZON, steps_ahead
from skidnav.agents.policies.goal_tracker import GoalTracker
from skidnav.agents.training import Evaluation
from skidnav.checks import check_integer
from skidnav.envs.registration import ENV_ID
from skidnav.errors import first_line, shown
from skidnav.experiments.config import AgentSpec, MapSpec
from skidnav.extras import require
from skidnav.seeding import RUN_ROLES, child, child_sequences, seed_int
from skidnav.studies.continuity.traces import (
    Policy,
    Trace,
    record_rollout,
    tabular_policy,
    wheel_speed_policy,
)

DISCRETE_PARAMS = {
    "q-learning": {"alpha": 0.5, "gamma": 0.95, "epsilon": 0.1},
    "dyna-full": {"alpha": 0.5, "gamma": 0.95, "epsilon": 0.1, "planning_steps": 100},
}
"""The discrete learners and their settings (the thesis's, with 100 planning updates)."""
WHEEL_LEARNERS = ("cmaes", "ppo", "sac")
MODEL_LEARNER = "mppi-kinematic"
"""The model-predictive wheel-speed learner (docs/agents/mppi-kinematic.md)."""
MPPI_LOOKAHEAD = 4.0
"""How far ``mppi-kinematic`` plans ahead in this study [s]: its horizon is this over the control
period (40 actions of 0.1 s, the setting it was measured at; 4 of 1 s). The study's own
setting, kept as its tables were measured; the agent's default looks 10 s ahead, at most 40
steps (:data:`~skidnav.agents.mpc.config.LOOKAHEAD_TIME`)."""
REFERENCE = "goal-tracker"
"""The reference controller: it learns nothing, so its runs are alike (one is enough)."""
LEARNERS = (*DISCRETE_PARAMS, *WHEEL_LEARNERS, MODEL_LEARNER, REFERENCE)
LEARNER_EXTRAS = {"cmaes": "search", "ppo": "deep", "sac": "deep"}
"""The learners that need an extra (:mod:`skidnav.extras`) → that extra."""
MAX_COUNTS = {
    "seeds": 1000, "episodes": 10**6, "generations": 10**6, "population": 10**4,
    "rollouts": 10**4, "max_steps": 10**5,
}  # fmt: skip
"""Upper bounds of the comparison's counts."""
COMPARISON_ROLES = ("run", "evaluation")
"""Children of the root seed: one per seed index (every learner's run of that index), the
evaluation seeds (shared by every learner and run)."""


@dataclass(frozen=True)
class ComparisonConfig:
    """One comparison, and the runner's grid of its runs (learner × seed index).

    Attributes:
        name: names its results (``skidnav run``'s default ``--out`` is ``runs/NAME``).
        map_kind, world_seed, slip: the world (the env's arguments). max_steps: actions per
            episode, training and rollouts. control_period: one action [s], both kinds.
        learners: names from :data:`LEARNERS`. seeds: runs per learner, ≥ 1. root_seed: of
            everything. episodes: training episodes of the discrete, deep and
            model-predictive learners.
        generations, population: CMA-ES's budget (λ · 2 · generations real episodes).
        rollouts: evaluation rollouts of each final policy (and of each check).
    """

    name: str = "continuity"
    map_kind: str = "obstacles"
    world_seed: int = 3
    slip: str = "slippery"
    max_steps: int = 200
    control_period: float = 1.0
    learners: tuple[str, ...] = LEARNERS
    seeds: int = 3
    root_seed: int = 0
    episodes: int = 300
    generations: int = 100
    population: int = 32
    rollouts: int = 5

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"expected a non-empty name, got {shown(self.name)}")
        if not isinstance(self.learners, tuple):
            raise ValueError(f"expected a list of learners, got {shown(self.learners)}")
        unknown = [name for name in self.learners if name not in LEARNERS]
        if unknown or not self.learners:
            raise ValueError(f"expected learners from {', '.join(LEARNERS)}, got {unknown}")
        if len(set(self.learners)) != len(self.learners):
            raise ValueError(f"expected distinct learners, got {shown(self.learners)}")
        for name in ("seeds", "episodes", "generations", "population", "rollouts", "max_steps"):
            check_integer(name, getattr(self, name), 1, MAX_COUNTS[name])
        check_integer("world_seed", self.world_seed, 0)
        check_integer("root_seed", self.root_seed, 0)
        # everything a learner will build, built once now: a bad setting ends the command before
        # any learner has trained, not after the first ones
        for continuous in {learner not in DISCRETE_PARAMS for learner in self.learners}:
            try:
                gymnasium.make(ENV_ID, **self.env_kwargs(continuous)).close()
            except (TypeError, ValueError) as error:
                raise ValueError(f"the env refuses these settings: {first_line(error)}") from None
        if "cmaes" in self.learners:
            search_config(self, seed=0)

    def env_kwargs(self, continuous: bool) -> dict[str, Any]:
        """The env's arguments for a learner of either kind of action."""
        kind = {"action": "continuous", "observation": "features"} if continuous else {}
        return {
            "map_kind": self.map_kind, "world_seed": self.world_seed, "slip": self.slip,
            "max_episode_steps": self.max_steps, "control_period": self.control_period, **kind,
        }  # fmt: skip

    @property
    def agents(self) -> tuple[AgentSpec, ...]:
        """The learners as the grid's agents (label = name)."""
        return tuple(AgentSpec(learner, learner) for learner in self.learners)

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The one map of the grid (the env builds it from ``world_seed``)."""
        return (MapSpec(self.map_kind, kind=self.map_kind),)

    @property
    def presets(self) -> tuple[str, ...]:
        """The one slip preset of the grid."""
        return (self.slip,)

    @property
    def n_runs(self) -> int:
        """Runs of the grid: every learner × seed index (the goal tracker's are alike)."""
        return len(self.learners) * self.seeds

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of :func:`comparison_to_dict` (names a results
        directory)."""
        text = json.dumps(comparison_to_dict(self), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def require_learner_extras(config: ComparisonConfig) -> None:
    """Refuse ``config`` before anything runs when a learner's extra is missing (the default
    learners include ``ppo`` and ``sac``: ``--learners`` without them runs on the core).

    Raises:
        MissingExtraError: one line naming the learner and the ``pip install`` that brings it.
    """
    for learner in config.learners:
        if learner in LEARNER_EXTRAS:
            require(LEARNER_EXTRAS[learner], f"learner {learner!r}")


def comparison_to_dict(config: ComparisonConfig) -> dict[str, Any]:
    """The config as a JSON-ready dict (inverse of :func:`comparison_from_dict`)."""
    data = dataclasses.asdict(config)
    data["learners"] = list(config.learners)
    return data


def comparison_from_dict(data: dict[str, Any]) -> ComparisonConfig:
    """The config saved by :func:`comparison_to_dict` (ValueError, TypeError or KeyError if
    invalid)."""
    values = {**data, "learners": tuple(data["learners"])}
    return ComparisonConfig(**values)


class LearnerRun(NamedTuple):
    """One learner's run: its final policy's rollouts and what learning it cost."""

    learner: str
    seed: int
    traces: tuple[Trace, ...]
    episodes_used: int
    episodes_to_learn: float
    wall_time: float


def search_config(config: ComparisonConfig, seed: int) -> Any:
    """The CMA-ES search of ``config`` with run seed ``seed`` (a ``SearchConfig``: ValueError
    for settings it refuses)."""
    from skidnav.agents.policies.search.config import SearchConfig

    return SearchConfig(
        map_kind=config.map_kind, world_seed=config.world_seed, slip=config.slip,
        max_episode_steps=config.max_steps, control_period=config.control_period,
        population=config.population, generations=config.generations,
        eval_episodes=config.rollouts, eval_every=5, seed=seed,
    )  # fmt: skip


def evaluation_seeds(config: ComparisonConfig) -> list[int]:
    """The rollout seeds every learner's policy meets (:data:`COMPARISON_ROLES`)."""
    rng = np.random.default_rng(child(config.root_seed, 1))
    return [int(seed) for seed in rng.integers(0, 2**31, config.rollouts)]


def run_seed(config: ComparisonConfig, index: int) -> int:
    """The integer seed of every learner's run ``index`` (31 bits: PyTorch and the legacy NumPy
    seeding that Stable-Baselines3 calls take no more): drawn from child ``index`` of the root's
    child 0, the stream the runner names world ``index`` of the grid (:mod:`skidnav.experiments.
    runs`; its one map and preset), shared by every learner (common random numbers)."""
    return seed_int(child(child(config.root_seed, 0), index)) % 2**31


def first_learned(greedy_lengths: np.ndarray) -> float:
    """1-based episode after which every greedy rollout reached the goal (NaN if none):
    ``greedy_lengths`` int64 (episodes, rollouts), −1 where a rollout did not."""
    learned = np.flatnonzero((greedy_lengths >= 0).all(axis=1))
    return float(learned[0] + 1) if learned.size else math.nan


def train_learner(config: ComparisonConfig, learner: str, seed: int) -> LearnerRun:
    """Train ``learner`` with run seed ``seed`` and roll its final policy out, as its family
    (the catalog's :func:`~skidnav.agents.catalog.entry`) is trained here
    (:data:`FAMILY_TRAINERS`)."""
    start = time.perf_counter()
    env = gymnasium.make(ENV_ID, **config.env_kwargs(learner not in DISCRETE_PARAMS))
    trainer = FAMILY_TRAINERS[entry(learner).family.name]
    policy, used, learned = trainer(config, learner, seed, env)
    wall = time.perf_counter() - start
    traces = tuple(record_rollout(env, policy, seed=s) for s in evaluation_seeds(config))
    env.close()
    return LearnerRun(learner, seed, traces, used, learned, wall)


def mppi_params(config: ComparisonConfig) -> dict[str, Any]:
    """``mppi-kinematic``'s settings in ``config``: its defaults, with the horizon that looks
    :data:`MPPI_LOOKAHEAD` seconds ahead at the control period (at least one action)."""
    return {"horizon": steps_ahead(config.control_period, MPPI_LOOKAHEAD, MAX_HORIZON)}


def _evaluation(config: ComparisonConfig, wheel_speeds: bool) -> Evaluation:
    """The greedy evaluation after every episode: the comparison's rollout seeds on a twin of
    the learner's env, each cut at ``max_steps``."""
    checks = gymnasium.make(ENV_ID, **config.env_kwargs(wheel_speeds))
    return Evaluation(checks, evaluation_seeds(config), config.max_steps)


def _train_by_family(
    config: ComparisonConfig, learner: str, seed: int, env: Any
) -> tuple[Policy, int, float]:
    """A learner made and trained as its family makes and trains it (tabular, mpc): drawing from
    the run's ``agent`` stream, its first episode reset from ``seed`` itself (an agent on
    default_rng(seed) would draw the very numbers of the env's slip noise)."""
    described = entry(learner)
    params = DISCRETE_PARAMS.get(learner) or mppi_params(config)
    agent_seed = child_sequences(seed, RUN_ROLES)["agent"]
    agent = described.build(env.unwrapped, params, agent_seed, config.max_steps).agent
    evaluation = _evaluation(config, learner not in DISCRETE_PARAMS)
    log = described.family.train(agent, env, config.episodes, evaluation=evaluation, seed=seed)
    return tabular_policy(agent), config.episodes, first_learned(log.greedy_lengths)


def _train_deep(
    config: ComparisonConfig, learner: str, seed: int, env: Any
) -> tuple[Policy, int, float]:
    """PPO or SAC on the env, seeded with the run seed itself (what Stable-Baselines3 takes)."""
    agent = entry(learner).agent_class(env, seed=seed)
    log = agent.train_episodes(config.episodes, evaluation=_evaluation(config, True))
    return (
        wheel_speed_policy(agent.policy(), env),
        config.episodes,
        first_learned(log.greedy_lengths),
    )


def _train_policy(
    config: ComparisonConfig, learner: str, seed: int, env: Any
) -> tuple[Policy, int, float]:
    """CMA-ES's search of the comparison's population and generations (its curve's first
    generation whose mean reached the goal from every evaluation start), or the goal tracker,
    which learns nothing."""
    if learner == REFERENCE:
        return wheel_speed_policy(GoalTracker(robot=env.unwrapped.robot), env), 0, math.nan
    from skidnav.agents.policies.search.cmaes import run_search

    result = run_search(search_config(config, seed))
    learned = [r.episodes for r in result.records if r.mean_success == 1.0]
    first = float(learned[0]) if learned else math.nan
    return wheel_speed_policy(result.policy, env), result.records[-1].episodes, first


FAMILY_TRAINERS = {
    "tabular": _train_by_family,
    "mpc": _train_by_family,
    "deep": _train_deep,
    "policies": _train_policy,
}
"""A learner's family (:attr:`~skidnav.agents.family.Family.name`) → how the comparison trains
it: the family's own make and train where the comparison's seeds fit them; PPO and SAC take
the run seed as an integer, and CMA-ES runs the comparison's search."""


def run_comparison(config: ComparisonConfig, progress: Any = None) -> list[LearnerRun]:
    """Every learner × seed of ``config`` (the reference once: it does not learn)."""
    runs = []
    for learner in config.learners:
        for index in range(1 if learner == REFERENCE else config.seeds):
            run = train_learner(config, learner, run_seed(config, index))
            runs.append(run)
            if progress is not None:
                progress(run)
    return runs


def config_fields() -> Sequence[str]:
    """The names of :class:`ComparisonConfig`'s fields (for the command line)."""
    return [field.name for field in fields(ComparisonConfig)]
