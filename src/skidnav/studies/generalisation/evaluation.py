"""Generalisation: agents trained on a set of maps, their greedy policies run on maps never seen.

The thesis's agents learn one map: their state is a cell and a heading, so what they learn names
places, not situations. The ``"features"`` observation (goal distance and bearing, range
readings; :mod:`skidnav.sim.features`) describes situations, and an agent over it may carry a
policy to another map. This study measures whether it does:

1. **Split** (:func:`split_worlds`): from one root seed, ``n_training`` training worlds and
   ``n_held_out`` held-out worlds (seeded map and slip field each, drawn from separate children of
   the root, :data:`~skidnav.seeding.GENERALISATION_ROLES`), checked to share no map (walls, start
   and goal); and the reset seeds of the evaluation rollouts, the same for every agent and run
   (common random numbers).
2. **Training** (:func:`generalisation_run`): one run per (agent, seed) learns for ``episodes``
   episodes on :class:`~skidnav.envs.mapset.MapSetEnv` over the training worlds (a world drawn per
   episode), through the same catalog as the experiment runner
   (:mod:`skidnav.agents.catalog`).
3. **Evaluation**: the greedy policy, frozen, rolled out from every evaluation seed on every
   training world and on every held-out world; the share of rollouts that reach the goal and the
   mean length of those that do, on each side. The gap between the two is what does not carry.
   The same again with an ε-greedy policy (ε 0.05 by default, the draws seeded by the rollout's
   seed): on goal-relative features a deterministic policy can cycle between two situations
   forever, which a little noise breaks.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from gymnasium.wrappers import TimeLimit

from skidnav.agents.catalog import entry
from skidnav.agents.greedy import greedy_rollout, rollout_summary
from skidnav.agents.training import TrainingLog
from skidnav.envs.mapset import MapSetEnv, world_env
from skidnav.seeding import GENERALISATION_ROLES, RUN_ROLES, child, child_sequences, seed_int
from skidnav.sim.features import POSE_GOAL_NAMES
from skidnav.studies.generalisation.grid import GeneralisationGrid

DEFAULT_OPTIONS: Mapping[str, Any] = {"map_kind": "obstacles", "slip": "thesis"}
"""The worlds' env options unless a study sets them."""


@dataclass(frozen=True)
class Split:
    """World seeds of the training and held-out maps, and the evaluation rollouts' reset
    seeds."""

    training: tuple[int, ...]
    held_out: tuple[int, ...]
    evaluation: tuple[int, ...]


@dataclass(frozen=True)
class GeneralisationResult:
    """One run: its agent and seed, its real experience, and on each side (training maps,
    held-out maps) the share of greedy rollouts that reached the goal and their mean length
    [actions] (NaN when none did), and the shares of the ε-greedy policy (:class:`EpsilonGreedy`,
    ``eval_epsilon``); ``training_success`` is the share of its last (at most 100) training
    episodes that reached the goal."""

    agent: str
    seed: int
    episodes: int
    steps: int
    training_success: float
    success_training_maps: float
    success_held_out_maps: float
    length_training_maps: float
    length_held_out_maps: float
    eval_epsilon: float
    epsilon_success_training_maps: float
    epsilon_success_held_out_maps: float


def _map_key(env: Any) -> bytes:
    grid_map = env.unwrapped.grid_map
    return bytes(np.asarray(grid_map.occupancy, dtype=np.uint8)) + bytes(
        np.array([*grid_map.start, *grid_map.goal], dtype=np.int64)
    )


def split_worlds(
    root_seed: int,
    n_training: int,
    n_held_out: int,
    rollouts: int,
    env_options: Mapping[str, Any] | None = None,
) -> Split:
    """The study's worlds and evaluation seeds from ``root_seed`` (module doc, step 1).
    ValueError if a held-out world has the map of a training world (which the seeds make
    unlikely, and the check makes impossible)."""
    if n_training < 1 or n_held_out < 1 or rollouts < 1:
        raise ValueError("expected at least one training world, held-out world and rollout")
    children = child_sequences(root_seed, GENERALISATION_ROLES)
    training = tuple(seed_int(sequence) for sequence in children["training"].spawn(n_training))
    held_out = tuple(seed_int(sequence) for sequence in children["held-out"].spawn(n_held_out))
    evaluation = tuple(seed_int(sequence) for sequence in children["evaluation"].spawn(rollouts))
    options = {**DEFAULT_OPTIONS, **(env_options or {})}
    seen = {_map_key(world_env(seed, 1, **options)) for seed in training}
    for seed in held_out:
        if _map_key(world_env(seed, 1, **options)) in seen:
            raise ValueError(f"held-out world {seed} has the map of a training world")
    return Split(training, held_out, evaluation)


@functools.lru_cache(maxsize=4)
def _split(
    root_seed: int,
    training: int,
    held_out: int,
    rollouts: int,
    options: tuple[tuple[str, str], ...],
) -> Split:
    return split_worlds(root_seed, training, held_out, rollouts, dict(options))


def grid_split(grid: GeneralisationGrid) -> Split:
    """The split of ``grid``'s worlds and evaluation seeds (computed once per process)."""
    options = tuple(sorted(grid.env_options.items()))
    return _split(grid.root_seed, grid.training_maps, grid.held_out_maps, grid.rollouts, options)


def run_streams(root_seed: int, seed: int) -> dict[str, np.random.SeedSequence]:
    """The :data:`~skidnav.seeding.RUN_ROLES` streams of run ``seed`` (child ``seed`` of the
    root's ``run`` child)."""
    runs = child_sequences(root_seed, GENERALISATION_ROLES)["run"]
    return child_sequences(child(runs, seed), RUN_ROLES)


class EpsilonGreedy:
    """``agent``'s greedy policy taking a uniform random action with probability ``epsilon``,
    drawn from ``rng``: a frozen policy that cannot loop forever where the greedy one would."""

    def __init__(
        self, agent: Any, epsilon: float, rng: np.random.Generator, n_actions: int = 4
    ) -> None:
        self.agent, self.epsilon, self.rng, self.n_actions = agent, epsilon, rng, n_actions

    def greedy_action(self, observation: Any) -> int:
        if self.rng.random() < self.epsilon:
            return int(self.rng.integers(self.n_actions))
        return int(self.agent.greedy_action(observation))


class GoalSeeker:
    """A reference policy on the ``"features"`` observation that ignores the range readings:
    forward while the goal's bearing is within :attr:`cone` rad of the heading, else turn toward
    it. What it reaches on a set of maps measures how open their straight start→goal lines
    are, i.e. how hard the maps are for a learned policy."""

    cone = 0.3
    bearing = (POSE_GOAL_NAMES.index("goal_cos_bearing"), POSE_GOAL_NAMES.index("goal_sin_bearing"))

    def greedy_action(self, observation: Any) -> int:
        cos_bearing, sin_bearing = observation[self.bearing[0]], observation[self.bearing[1]]
        if cos_bearing > math.cos(self.cone):
            return 0
        return 2 if sin_bearing > 0 else 3


@dataclass(frozen=True)
class Reference:
    """A reference policy's shares of rollouts reaching the goal on both sides of a split."""

    policy: str
    success_training_maps: float
    success_held_out_maps: float


def references(
    split: Split, max_steps: int, env_options: Mapping[str, Any] | None = None
) -> list[Reference]:
    """The uniform random policy and :class:`GoalSeeker` on the split's maps, with the same
    evaluation seeds as the agents (the random draws seeded by them too)."""
    options = {**DEFAULT_OPTIONS, **(env_options or {}), "observation": "features"}
    policies = (("random", GoalSeeker(), 1.0), ("goal-seeker", GoalSeeker(), 0.0))
    return [
        Reference(
            name,
            evaluate_on(policy, split.training, split.evaluation, max_steps, epsilon, **options)[0],
            evaluate_on(policy, split.held_out, split.evaluation, max_steps, epsilon, **options)[0],
        )
        for name, policy, epsilon in policies
    ]


def evaluate_on(
    agent: Any,
    worlds: Sequence[int],
    seeds: Sequence[int],
    max_steps: int,
    epsilon: float = 0.0,
    **options: Any,
) -> tuple[float, float]:
    """(share of rollouts reaching the goal, their mean length) of ``agent``'s greedy policy,
    one rollout per seed of ``seeds`` on each world of ``worlds``; with ``epsilon`` > 0 the
    policy is :class:`EpsilonGreedy`, its draws from :func:`exploration_stream` of the rollout's
    seed (the same draws for every agent)."""
    lengths: list[int] = []
    for world in worlds:
        env = world_env(world, max_steps, **options)
        for seed in seeds:
            policy = agent
            if epsilon > 0.0:
                policy = EpsilonGreedy(agent, epsilon, exploration_stream(int(seed)))
            lengths.append(greedy_rollout(policy, env, max_steps, seed=int(seed)))
    return rollout_summary(lengths)


def exploration_stream(seed: int) -> np.random.Generator:
    """The ε-greedy draws of a rollout reset with ``seed``: its first child, not the stream of
    ``default_rng(seed)``, from which the env's reset draws the rollout's slip noise."""
    return np.random.default_rng(child(seed, 0))


class GeneralisationRun(NamedTuple):
    """One run's results and its training log (one entry per training episode)."""

    result: GeneralisationResult
    log: TrainingLog


def generalisation_run(
    agent_name: str,
    seed: int,
    split: Split,
    episodes: int,
    *,
    root_seed: int,
    params: Mapping[str, Any] | None = None,
    env_options: Mapping[str, Any] | None = None,
    max_steps: int = 300,
    eval_epsilon: float = 0.05,
) -> GeneralisationRun:
    """Train ``agent_name`` (run ``seed``) on the split's training worlds and evaluate it on both
    sides (module doc, steps 2–3). ``env_options``: the worlds' env options (``map_kind``,
    ``slip``, ``observation``, ``lidar_rays``…)."""
    options = {**DEFAULT_OPTIONS, **(env_options or {})}
    known = entry(agent_name)
    options["observation"] = known.env_observation(options.get("observation"))
    streams = run_streams(root_seed, seed)
    env = MapSetEnv(split.training, **options)
    built = known.build(env, dict(params or {}), streams["agent"], max_steps)
    agent = built.agent
    limited = TimeLimit(env, max_steps)
    limited.reset(seed=seed_int(streams["episodes"]))
    log = built.train(limited, episodes, max_steps=max_steps)
    successes = np.asarray(log.successes, dtype=float)
    sides = [
        evaluate_on(agent, worlds, split.evaluation, max_steps, epsilon, **options)
        for epsilon in (0.0, eval_epsilon)
        for worlds in (split.training, split.held_out)
    ]
    (on_training, on_held_out, noisy_training, noisy_held_out) = sides
    result = GeneralisationResult(
        agent_name, seed, int(successes.size), int(np.sum(log.lengths)),
        float(successes[-100:].mean()) if successes.size else math.nan,
        on_training[0], on_held_out[0], on_training[1], on_held_out[1],
        eval_epsilon, noisy_training[0], noisy_held_out[0],
    )  # fmt: skip
    return GeneralisationRun(result, log)
