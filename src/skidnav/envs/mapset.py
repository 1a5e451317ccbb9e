"""A set of worlds as one Gymnasium env: each episode on a world drawn from the set.

Training on several maps and evaluating on maps never seen (:mod:`skidnav.studies.generalisation`)
needs an env whose episodes change world. :class:`MapSetEnv` holds one ``SkidSteerNav-v0`` per world
seed, built with the same options, and at every ``reset``:
1. draws the world uniformly from the set with its own generator (``self.np_random``, seeded by
   the first ``reset(seed=...)`` as Gymnasium's rules say);
2. resets that world with a seed drawn from the same generator, so the whole sequence of worlds,
   starts and slip noise follows from one seed;
3. returns that world's observation, with ``info["world"]`` its index in the set.

Spaces are the worlds' own, and must agree: a ``Box`` observation (``"pose"`` or ``"features"``)
has the same bounds on every map of one arena; the discrete state has the same count, though
it names a different place on every map (no goal in it), which is why only agents on
goal-relative features can carry what they learn to another map.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium

from skidnav.envs.navigation import SkidSteerNavEnv

MAX_WORLDS = 10_000


class MapSetEnv(gymnasium.Env[Any, int]):
    """Episodes on worlds drawn from ``world_seeds`` (module doc); ``env_options`` are the
    keyword arguments of every world's :class:`~skidnav.envs.navigation.SkidSteerNavEnv`
    (``map_kind``, ``slip``, ``observation``…, not ``world_seed``). No time limit of its own:
    wrap it in ``TimeLimit``."""

    metadata = {"render_modes": []}  # noqa: RUF012  (Gymnasium's convention)

    def __init__(self, world_seeds: Sequence[int], **env_options: Any) -> None:
        seeds = [int(seed) for seed in world_seeds]
        if not 1 <= len(seeds) <= MAX_WORLDS:
            raise ValueError(f"expected 1 to {MAX_WORLDS} world seeds, got {len(seeds)}")
        if "world_seed" in env_options:
            raise ValueError("world_seed is given by world_seeds")
        self.world_seeds = tuple(seeds)
        self.worlds = [SkidSteerNavEnv(world_seed=seed, **env_options) for seed in seeds]
        first = self.worlds[0]
        for seed, world in zip(seeds, self.worlds, strict=True):
            if world.observation_space != first.observation_space:
                raise ValueError(f"world {seed} has another observation space than world 0")
        self.observation_space = first.observation_space
        self.action_space = first.action_space
        self.current = 0
        """Index in the set of the world of the current episode."""

    @property
    def task(self) -> Any:
        """The robot and grid of the set (every world's are the same), for agents that ask for a
        navigation ``task``; its map is the current world's."""
        return self.worlds[self.current].task

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        super().reset(seed=seed)
        self.current = int(self.np_random.integers(len(self.worlds)))
        world_seed = int(self.np_random.integers(2**31))
        observation, info = self.worlds[self.current].reset(seed=world_seed, options=options)
        return observation, {**info, "world": self.current}

    def step(self, action: int) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.worlds[self.current].step(action)
        return observation, reward, terminated, truncated, {**info, "world": self.current}


def world_env(world_seed: int, max_steps: int, **env_options: Any) -> gymnasium.Env[Any, int]:
    """One world of a set on its own, cut at ``max_steps`` actions (for evaluations)."""
    env = SkidSteerNavEnv(world_seed=int(world_seed), **env_options)
    return gymnasium.wrappers.TimeLimit(env, max_steps)
