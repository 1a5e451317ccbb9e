"""CMA-ES as an agent of the catalog: the search on the world of the env it is made for.

:class:`CMAESAgent` runs the search of :mod:`skidnav.agents.policies.search.cmaes` generation by
generation: ``train_episodes(n)`` runs as many whole generations as ``n`` episodes need (each
generation λ × E real episodes, one log row each), and after every episode the greedy policy —
the distribution's mean, which changes only at a generation's end — is evaluated as every agent
is (:func:`~skidnav.agents.greedy.greedy_evaluation`). The search rebuilds its world in its own
vector envs, so the env must be one ``gymnasium.make`` made from a map kind, a world seed and a
slip preset (:func:`search_world`); its greedy action is the mean policy's wheel speeds.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium
import numpy as np

from skidnav.agents.policies.search.cmaes import CMAESSearch
from skidnav.agents.policies.search.config import SearchConfig
from skidnav.agents.policies.search.policy_file import save_policy
from skidnav.agents.policies.search.tanh_policy import TanhPolicy
from skidnav.agents.training import (
    NO_EVALUATION,
    Episode,
    Evaluation,
    LogRows,
    TrainingLog,
    plain_evaluations,
)
from skidnav.errors import UserError

WORLD_FIELDS = (
    "map_kind", "world_seed", "slip", "max_episode_steps", "control_period", "lidar_rays",
    "lidar_range",
)  # fmt: skip
"""The :class:`~skidnav.agents.policies.search.config.SearchConfig` fields the env gives."""
FOREIGN_WORLD = ("map_file", "grid_map", "slip_field", "robot", "discretization", "floor")
"""Env arguments the search cannot rebuild its world from."""


def search_world(env: gymnasium.Env[Any, Any], max_steps: int) -> dict[str, Any]:
    """The world fields of a search on ``env`` (made by ``gymnasium.make`` with wheel-speed
    actions and the feature observation), its episodes cut at ``max_steps`` actions; UserError
    in one line for an env the search cannot rebuild."""
    spec = env.unwrapped.spec
    kwargs = dict(spec.kwargs) if spec is not None else None
    if kwargs is None or any(kwargs.get(name) is not None for name in FOREIGN_WORLD):
        raise UserError(
            "agent 'cmaes' searches on a world it rebuilds: make the env with a map kind, a world "
            "seed and a slip preset (skidnav.make_env), not from a map file or objects"
        )
    if kwargs.get("action") != "continuous" or kwargs.get("observation") != "features":
        raise UserError(
            "agent 'cmaes' drives wheel speeds on the feature observation (set [env] action = "
            "'continuous' and observation = 'features')"
        )
    nav: Any = env.unwrapped
    env_robot = nav.robot
    return {
        "map_kind": kwargs.get("map_kind", "obstacles"),
        "world_seed": int(kwargs.get("world_seed", 0)),
        "slip": kwargs.get("slip", "thesis"),
        "max_episode_steps": int(max_steps),
        "control_period": float(env_robot.dt * env_robot.substeps),
        "lidar_rays": int(kwargs.get("lidar_rays", 8)),
        "lidar_range": float(kwargs.get("lidar_range", 0.3)),
    }


class CMAESAgent:
    """The CMA-ES search of ``config`` as an agent (module doc); its ``generations`` field counts
    nothing here: training decides how many generations run."""

    name: ClassVar[str] = "cmaes"
    config_class: ClassVar[type[SearchConfig]] = SearchConfig
    planning_updates: int = 0
    """It plans nothing (its episodes are all real)."""

    def __init__(self, config: SearchConfig) -> None:
        self.config = config
        self.search = CMAESSearch(config)

    def mean_policy(self) -> TanhPolicy:
        """The distribution's mean as a policy (the search's result so far)."""
        return self.search.mean_policy()

    def greedy_action(self, state: Any) -> np.ndarray:
        """The mean policy's wheel speeds at the observation ``state``, float64 (2,) [rad/s]."""
        return np.array(self.mean_policy().wheel_speeds(np.asarray(state, dtype=np.float64)))

    def train_episodes(
        self, episodes: int, *, evaluation: Evaluation = NO_EVALUATION, seed: int | None = None
    ) -> TrainingLog:
        """Run ⌈``episodes`` / (λ E)⌉ generations; one log row per real episode
        (:class:`~skidnav.agents.training.LogRows`), each with the greedy evaluation of the mean
        in force after it (:func:`~skidnav.agents.training.plain_evaluations`). The search seeds
        its own episodes (``seed`` only seeds the evaluation env, as in every loop); its vector
        envs do not count collisions: that column is 0."""
        per_generation = self.config.episodes_per_generation
        rows = LogRows(evaluation.n_rollouts)
        limit = evaluation.limit(self.config.max_episode_steps)
        evaluate = plain_evaluations(self, evaluation)
        evaluation.start(seed)
        before = evaluation.run(evaluate, limit)
        for _ in range(math.ceil(max(episodes, 0) / per_generation)):
            start = time.perf_counter()
            batch = self.search.advance()
            seconds = (time.perf_counter() - start) / per_generation
            after = evaluation.run(evaluate, limit)
            for row in range(per_generation):
                episode = Episode(
                    float(batch.returns.flat[row]), int(batch.lengths.flat[row]),
                    bool(batch.successes.flat[row]), 0, 0,
                )  # fmt: skip
                rows.add(episode, seconds, after if row == per_generation - 1 else before)
            before = after
            if rows.stopped:  # a training callback asked: the generation's episodes all ran
                break
        return rows.log()

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """The mean policy's file (:func:`~skidnav.agents.policies.search.policy_file.
        save_policy`), with the search's config and generation as provenance; both paths."""
        provenance = {
            "agent": self.name,
            "search": self.config.to_dict(),
            "generation": self.search.generation,
        }
        return save_policy(self.mean_policy(), path, provenance)


def make_cmaes_agent(
    env: gymnasium.Env[Any, Any], params: Mapping[str, Any], seed: int, max_steps: int
) -> CMAESAgent:
    """A new search on ``env``'s world with the settings ``params`` (any
    :class:`~skidnav.agents.policies.search.config.SearchConfig` field but the world's and
    ``seed``), its root seed ``seed``; UserError in one line for bad settings or an env the
    search cannot rebuild."""
    taken = sorted(set(params) & {*WORLD_FIELDS, "seed"})
    if taken:
        raise UserError(f"agent 'cmaes': {taken[0]!r} comes from the env and the run's seed")
    try:
        config = SearchConfig.from_mapping(
            {**dict(params), **search_world(env, max_steps), "seed": seed, "generations": 0}
        )
    except (ValueError, TypeError) as error:
        raise UserError(f"agent 'cmaes': {error}") from None
    return CMAESAgent(dataclasses.replace(config))
