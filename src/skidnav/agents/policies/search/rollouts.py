"""Episodes of a whole population of policies at once, through one vector env.

Candidate p's episode e runs in sub-env ``p · E + e`` of a vector env of P · E sub-envs made by
``gymnasium.make_vec`` (the native vector env, :mod:`skidnav.envs.vector`). Every sub-env runs
exactly one episode: the vector env is reset with the seeds ``seeds[e]`` repeated for every
candidate — so all candidates meet the same slip noise (common random numbers) — and stepped with
every candidate's wheel speeds until all episodes ended. Gymnasium's next-step autoreset then
restarts a finished sub-env at its next step; its outputs from then on are masked out and its action
is (0, 0).

The vector env takes one seed per sub-env in ``reset(seed=[...])`` (an int would seed sub-env k
with seed + k, so no two candidates would meet the same noise), and must autoreset at the next
step (checked).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode

from skidnav.agents.policies.search.tanh_policy import PolicyLayout
from skidnav.envs.registration import ENV_ID
from skidnav.sim.features import POSE_GOAL_NAMES

GOAL_DISTANCE = POSE_GOAL_NAMES.index("goal_distance")
"""Column of the goal distance [m] in the feature observation."""


class EpisodeBatch(NamedTuple):
    """The P × E episodes of one :meth:`PopulationRollouts.run`."""

    returns: np.ndarray
    """float64 (P, E): undiscounted sum of rewards of each episode."""
    successes: np.ndarray
    """bool (P, E): the episode ended at the goal (terminated, not truncated)."""
    lengths: np.ndarray
    """int64 (P, E): actions taken."""
    progress: np.ndarray
    """float64 (P, E): goal distance [m] at the start minus at the end of each episode."""

    @property
    def mean_returns(self) -> np.ndarray:
        """float64 (P,): each candidate's mean return over its E episodes."""
        return np.asarray(self.returns.mean(axis=1))

    @property
    def success_rates(self) -> np.ndarray:
        """float64 (P,): each candidate's share of episodes that reached the goal."""
        return np.asarray(self.successes.mean(axis=1))


def make_batch_env(num_envs: int, env_options: Mapping[str, Any]) -> gymnasium.vector.VectorEnv:
    """``gymnasium.make_vec`` of ``skidnav/SkidSteerNav-v0`` with ``num_envs`` sub-envs and
    ``env_options`` (continuous actions, feature observations): the native vector env
    (:mod:`skidnav.envs.vector`)."""
    env = gymnasium.make_vec(ENV_ID, num_envs=num_envs, **env_options)
    mode = env.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP)
    if mode != AutoresetMode.NEXT_STEP:  # the masking reads an episode's last observation
        env.close()
        raise ValueError(f"expected a vector env with next-step autoreset, got {mode}")
    return env


class PopulationRollouts:
    """A vector env of ``population × episodes`` sub-envs for scoring populations.

    Args:
        population: P candidates per call. episodes: E episodes per candidate.
        env_options: keyword arguments of the env (:meth:`SearchConfig.env_options`); must
            include ``max_episode_steps`` (the bound of the stepping loop) and ``lidar_range``.
    """

    def __init__(self, population: int, episodes: int, env_options: Mapping[str, Any]) -> None:
        self.population, self.episodes = population, episodes
        self.max_episode_steps = int(env_options["max_episode_steps"])
        self.lidar_range = float(env_options["lidar_range"])
        self.env = make_batch_env(population * episodes, env_options)

    def layout(self, hidden: int) -> PolicyLayout:
        """The policy layout of this env's spaces with ``hidden`` units."""
        observation_space = self.env.single_observation_space
        action_space = self.env.single_action_space
        assert isinstance(observation_space, gymnasium.spaces.Box)
        assert isinstance(action_space, gymnasium.spaces.Box)
        return PolicyLayout(
            observation_space.low, observation_space.high, hidden=hidden,
            wheel_speed=float(action_space.high[0]), lidar_rays=observation_space.shape[0] - 7,
            lidar_range=self.lidar_range,
        )  # fmt: skip

    def run(
        self, layout: PolicyLayout, parameters: np.ndarray, seeds: Sequence[int]
    ) -> EpisodeBatch:
        """One episode of each of the P candidates ``parameters`` float64 (P, n) on each of the
        E episode seeds ``seeds`` (the env's ``reset`` seeds)."""
        population, episodes = self.population, self.episodes
        if np.shape(parameters)[0] != population or len(seeds) != episodes:
            raise ValueError(
                f"expected {population} candidates and {episodes} seeds, got "
                f"{np.shape(parameters)[0]} and {len(seeds)}"
            )
        # One seed per sub-env (VectorEnv's own annotation names only an int, which would seed
        # sub-env k with seed + k: no two alike).
        episode_seeds = [int(seed) for seed in seeds] * population
        observations, _ = self.env.reset(seed=episode_seeds)  # type: ignore[arg-type]
        progress = np.array(observations[:, GOAL_DISTANCE], dtype=np.float64)
        returns = np.zeros(population * episodes)
        lengths = np.zeros(population * episodes, dtype=np.int64)
        successes = np.zeros(population * episodes, dtype=bool)
        running = np.ones(population * episodes, dtype=bool)
        for _ in range(self.max_episode_steps):
            per_candidate = np.asarray(observations).reshape(population, episodes, -1)
            actions = layout.forward(parameters, per_candidate).reshape(-1, 2)
            actions[~running] = 0.0
            observations, rewards, terminated, truncated, _ = self.env.step(
                actions.astype(np.float32)
            )
            returns += np.where(running, rewards, 0.0)
            lengths += running
            successes |= running & terminated
            ended = running & (terminated | truncated)
            progress[ended] -= observations[ended, GOAL_DISTANCE]  # the episode's last one
            running &= ~ended
            if not running.any():
                break
        assert not running.any(), "an episode outlived the env's time limit"
        shape = (population, episodes)
        return EpisodeBatch(
            returns.reshape(shape), successes.reshape(shape), lengths.reshape(shape),
            progress.reshape(shape),
        )  # fmt: skip

    def close(self) -> None:
        """Close the vector env."""
        self.env.close()
