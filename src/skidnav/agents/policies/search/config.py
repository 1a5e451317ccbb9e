"""The settings of one CMA-ES policy search: the world, the policy, the optimizer, the budget.

>>> config = SearchConfig(map_kind="free", generations=3)
>>> config.episodes_per_generation, config.env_options()["action"]
(32, 'continuous')
>>> SearchConfig(population=1)
Traceback (most recent call last):
...
ValueError: expected population to be an integer in [2, 10000], got 1
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from skidnav.agents.policies.search.tanh_policy import MAX_HIDDEN, MAX_LIDAR_RAYS, parameter_count
from skidnav.checks import check_integer, check_number
from skidnav.envs.navigation import with_control_period
from skidnav.envs.vector import NOISE_ACTIONS
from skidnav.files.configtables import check_keys
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SLIP_PRESETS

MAP_KINDS = ("free", "obstacles", "maze")
MAX_GENERATIONS = 1_000_000
MAX_POPULATION = 10_000
MAX_EPISODES = 10_000
MAX_EPISODE_STEPS = 100_000
MAX_SEED = 2**63 - 1
MAX_CONTROL_PERIOD = 3600.0
"""Longest action [s]: an hour (36,000 sub-steps of 0.1 s, each with its noise in memory)."""
MAX_PARAMETER = 1e32
"""``cmaes.CMA`` asserts every component of its mean and of every candidate it is told to be
below this in magnitude (its ``_MEAN_MAX``); the search and its checkpoint keep to it."""
MAX_SIGMA0 = MAX_PARAMETER / 100
"""Largest initial step size: a first-generation candidate is σ₀ z, z standard normal, and
|z| < 100 in every component (a larger one has probability below 10⁻²⁰⁰⁰)."""
MAX_SEARCH_BYTES = 4 * 2**30
"""Most memory [bytes] a search's largest arrays may need (:meth:`SearchConfig.memory_bytes`)."""


@dataclass(frozen=True)
class SearchConfig:
    """One search (docs/agents/cmaes.md); validated on construction, never mutated: every field
    within its bounds, and the search's largest arrays within :data:`MAX_SEARCH_BYTES`
    (:meth:`memory_bytes`: the policy's size ``hidden`` and ``lidar_rays`` with ``population``,
    and the sub-envs ``population`` × ``episodes_per_candidate`` + ``eval_episodes`` with
    ``control_period``).

    Attributes:
        map_kind: the arena, "free", "obstacles" or "maze" (drawn from ``world_seed``).
        world_seed: the env's ``world_seed`` (map and slip field), ≥ 0.
        slip: the slip preset (:data:`skidnav.robot.slip.SLIP_PRESETS`).
        max_episode_steps: actions before the time limit truncates an episode.
        control_period: duration of one action [s], a whole number of the robot's 0.1 s
            sub-steps, at most :data:`MAX_CONTROL_PERIOD`.
        lidar_rays: k range readings in the observation.
        lidar_range: their largest reading [m].
        hidden: H tanh units of the policy's hidden layer (0: linear policy).
        population: λ, candidates per generation.
        sigma0: the initial step size σ₀ of CMA-ES, in parameter units (the inputs are scaled
            to [−1, 1], so σ₀ ≈ 0.5 moves every unit's pre-activation by about that much); at
            most :data:`MAX_SIGMA0`, so that the optimizer accepts the first candidates.
        generations: generations to run (each one CMA-ES ask/tell).
        episodes_per_candidate: real episodes each candidate is scored on; every candidate of a
            generation meets the same episode seeds.
        progress_weight: w ≥ 0, reward per metre of goal distance gained over an episode
            (start minus end) added to its return in a candidate's score; 0 (default): the score
            is the plain mean return. (Potential-based shaping, Ng, Harada & Russell 1999, with
            the potential −w × goal distance and no discount: the shaping rewards of an episode
            sum to w × (d_start − d_end).)
        eval_episodes: episodes of the distribution's mean on the fixed evaluation seeds.
        eval_every: evaluate the mean every this many generations (and after the last one).
        seed: the root seed of every random draw of the search (module
            :mod:`skidnav.agents.policies.search.cmaes`).
    """

    map_kind: str = "obstacles"
    world_seed: int = 0
    slip: str = "thesis"
    max_episode_steps: int = 200
    control_period: float = 1.0
    lidar_rays: int = 8
    lidar_range: float = 0.3
    hidden: int = 8
    population: int = 16
    sigma0: float = 0.5
    generations: int = 50
    episodes_per_candidate: int = 2
    progress_weight: float = 0.0
    eval_episodes: int = 10
    eval_every: int = 1
    seed: int = 0

    def __post_init__(self) -> None:
        if self.map_kind not in MAP_KINDS:
            raise ValueError(f"expected map_kind in {MAP_KINDS}, got {self.map_kind!r}")
        if self.slip not in SLIP_PRESETS:
            raise ValueError(f"expected slip in {tuple(SLIP_PRESETS)}, got {self.slip!r}")
        integers = {
            "world_seed": (0, MAX_SEED), "max_episode_steps": (1, MAX_EPISODE_STEPS),
            "lidar_rays": (0, MAX_LIDAR_RAYS), "hidden": (0, MAX_HIDDEN),
            "population": (2, MAX_POPULATION), "generations": (0, MAX_GENERATIONS),
            "episodes_per_candidate": (1, MAX_EPISODES), "eval_episodes": (1, MAX_EPISODES),
            "eval_every": (1, MAX_GENERATIONS), "seed": (0, MAX_SEED),
        }  # fmt: skip
        for name, (low, high) in integers.items():
            check_integer(name, getattr(self, name), low, high)
        check_number("control_period", self.control_period, 0.0, MAX_CONTROL_PERIOD)
        check_number("lidar_range", self.lidar_range, 0.0)
        check_number("sigma0", self.sigma0, 0.0, MAX_SIGMA0)
        check_number("progress_weight", self.progress_weight, 0.0, closed=True)
        optimizer, rollouts = self.memory_bytes()  # also refuses a part of a sub-step
        if optimizer + rollouts > MAX_SEARCH_BYTES:
            raise ValueError(
                f"expected a search needing at most {MAX_SEARCH_BYTES / 2**30:g} GiB, got about "
                f"{(optimizer + rollouts) / 2**30:.3g} GiB: {optimizer / 2**30:.3g} GiB for the "
                f"CMA-ES update of {self.n_parameters:,} parameters from hidden {self.hidden} "
                f"and lidar_rays {self.lidar_rays} with population {self.population}, "
                f"{rollouts / 2**30:.3g} GiB for the episodes of population {self.population} "
                f"× episodes_per_candidate {self.episodes_per_candidate} + eval_episodes "
                f"{self.eval_episodes} at control_period {self.control_period:g} s"
            )

    @property
    def n_parameters(self) -> int:
        """n, the parameters of the policy searched
        (:func:`~skidnav.agents.policies.search.tanh_policy.parameter_count` of 7 + ``lidar_rays``
        features and ``hidden`` units)."""
        return parameter_count(7 + self.lidar_rays, self.hidden)

    def memory_bytes(self) -> tuple[int, int]:
        """(optimizer, episodes): an estimate [bytes] of the memory of the search's largest
        arrays, float64 throughout.

        * The optimizer: cmaes 0.13's rank-μ update builds a (λ, n, n) array and its weighted
          copy besides a few n × n matrices: 8 n² (2λ + 6) (measured: 8 n² (2λ + 4)).
        * The episodes, per sub-env of the two vector envs (λ E + ``eval_episodes``): the
          env's 2 · NOISE_ACTIONS uniforms per sub-step of an action and the policy's forward
          pass: 8 (64 s + 10 d + 10 H + 300) for s sub-steps per action, d = 7 + k features
          and H hidden units (measured: 1 % to 30 % less).
        """
        n = self.n_parameters
        substeps = with_control_period(RobotParams(), float(self.control_period)).substeps
        sub_envs = self.episodes_per_generation + self.eval_episodes
        per_sub_env = 2 * NOISE_ACTIONS * substeps + 10 * (7 + self.lidar_rays + self.hidden) + 300
        return 8 * n * n * (2 * self.population + 6), 8 * sub_envs * per_sub_env

    @property
    def episodes_per_generation(self) -> int:
        """Real episodes one generation consumes: λ × episodes per candidate."""
        return self.population * self.episodes_per_candidate

    def env_options(self) -> dict[str, Any]:
        """The keyword arguments of ``gymnasium.make_vec`` for this search's world."""
        return {
            "action": "continuous",
            "observation": "features",
            "map_kind": self.map_kind,
            "world_seed": self.world_seed,
            "slip": self.slip,
            "max_episode_steps": self.max_episode_steps,
            "control_period": float(self.control_period),
            "lidar_rays": self.lidar_rays,
            "lidar_range": float(self.lidar_range),
        }

    def to_dict(self) -> dict[str, Any]:
        """The fields as a JSON-able dict (read back by :meth:`from_mapping`)."""
        return {field.name: getattr(self, field.name) for field in fields(self)}

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> SearchConfig:
        """A config from a mapping of its fields; ValueError naming an unknown key."""
        check_keys(values, [field.name for field in fields(cls)])
        return cls(**values)

    def resumes(self, saved: SearchConfig) -> bool:
        """Whether a search of ``saved`` may continue as this one: every field equal but
        ``generations``, which may grow."""
        mine, theirs = self.to_dict(), saved.to_dict()
        mine.pop("generations"), theirs.pop("generations")
        return mine == theirs
