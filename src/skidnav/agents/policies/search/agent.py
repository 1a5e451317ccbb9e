"""CMA-ES as an agent of the catalog: the search on the world of the env it is made for.

:class:`CMAESAgent` runs the search of :mod:`skidnav.agents.policies.search.cmaes` generation by
generation: ``train_episodes(n)`` runs as many whole generations as ``n`` episodes need (each
generation λ × E real episodes, one log row each), and after every episode the greedy policy —
the distribution's mean, which changes only at a generation's end — is evaluated as every agent
is (:func:`~skidnav.agents.training.greedy_evaluation`). The search rebuilds its world in its own
vector envs, so the env must be one ``gymnasium.make`` made from a map kind, a world seed and a
slip preset (:func:`search_world`); its greedy action is the mean policy's wheel speeds.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import gymnasium
import numpy as np

from skidnav.agents.policies.search.cmaes import CMAESSearch
from skidnav.agents.policies.search.config import SearchConfig
from skidnav.agents.policies.search.policy_file import save_policy
from skidnav.agents.policies.search.tanh_policy import TanhPolicy
from skidnav.agents.training import (
    NOT_REACHED,
    TrainingLog,
    greedy_evaluation,
    log_from_rows,
    record_evaluation,
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
        self,
        episodes: int,
        *,
        greedy_eval_env: gymnasium.Env[Any, Any] | None = None,
        greedy_seeds: Sequence[int] | None = None,
        greedy_max_steps: int | None = None,
    ) -> TrainingLog:
        """Run ⌈``episodes`` / (λ E)⌉ generations; one log row per real episode, each with the
        greedy evaluation of the mean in force after it. Collisions are not counted by the
        search's vector envs: that column is 0."""
        per_generation = self.config.episodes_per_generation
        limit = greedy_max_steps or self.config.max_episode_steps
        columns: dict[str, list[Any]] = {name: [] for name in TrainingLog._fields}
        before = self._evaluate(greedy_eval_env, greedy_seeds, limit)
        for _ in range(math.ceil(episodes / per_generation) if episodes > 0 else 0):
            start = time.perf_counter()
            batch = self.search.advance()
            seconds = (time.perf_counter() - start) / per_generation
            after = self._evaluate(greedy_eval_env, greedy_seeds, limit)
            for row in range(per_generation):
                columns["returns"].append(float(batch.returns.flat[row]))
                columns["lengths"].append(int(batch.lengths.flat[row]))
                columns["successes"].append(bool(batch.successes.flat[row]))
                columns["collisions"].append(0)
                columns["planning_updates"].append(0)
                columns["wall_time"].append(seconds)
                record_evaluation(columns, after if row == per_generation - 1 else before)
            before = after
        return log_from_rows(columns, 1 if greedy_seeds is None else len(greedy_seeds))

    def _evaluate(
        self, env: gymnasium.Env[Any, Any] | None, seeds: Sequence[int] | None, limit: int
    ) -> list[Any]:
        if env is None:
            return [NOT_REACHED] * (1 if seeds is None else len(seeds))
        return greedy_evaluation(self, env, limit, seeds)

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
