"""The sim-to-sim gap: policies learned on the kinematic simulator, run on the physical robot.

For each seed: one world (map and slip field from the seed's ``world`` child), an agent trained
for ``episodes`` episodes on the kinematic env (the fused trainer), then its greedy policy rolled
out ``rollouts`` times with the same evaluation seeds on the same world twice — kinematic, and
``dynamics="mujoco"`` (:mod:`skidnav.physics`) — without learning. The drop in success and the
change in length are the gap: how much of what the ICR simulator taught survives a robot that
does not obey it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import gymnasium
import numpy as np

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.catalog import entry
from skidnav.agents.greedy import greedy_evaluation, rollout_summary
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.training import TrainingLog
from skidnav.seeding import seed_int

ENV_ID = "skidnav/SkidSteerNav-v0"


@dataclass(frozen=True)
class TransferResult:
    """One seed's gap: the share of greedy rollouts that reached the goal and their mean length
    [actions] (NaN when none did), on the kinematic simulator and on the physical robot."""

    agent: str
    seed: int
    success_kinematic: float
    success_physics: float
    length_kinematic: float
    length_physics: float


class TransferRun(NamedTuple):
    """One seed's gap and its training log on the kinematic simulator (one entry per
    episode)."""

    result: TransferResult
    log: TrainingLog


def transfer_run(
    agent_name: str,
    seed: int,
    episodes: int,
    *,
    params: Mapping[str, Any] | None = None,
    env_options: Mapping[str, Any] | None = None,
    rollouts: int = 5,
    max_steps: int = 300,
) -> TransferRun:
    """Train ``agent_name`` on the kinematic env of seed ``seed``'s world and evaluate it on both
    dynamics (module doc). ``env_options``: keyword arguments of the env (``map_kind``,
    ``slip``, ``floor``…; ``floor`` applies to the physical robot only)."""
    world, agent_stream, episode_stream, evaluation = np.random.SeedSequence(seed).spawn(4)
    options = {"map_kind": "obstacles", "slip": "slippery", **(env_options or {})}
    floor = options.pop("floor", None)
    common = {"world_seed": seed_int(world), "max_episode_steps": max_steps, **options}
    kinematic = gymnasium.make(ENV_ID, **common)
    physical = gymnasium.make(ENV_ID, dynamics="mujoco", floor=floor, **common)
    agent = (
        entry(agent_name)
        .build(kinematic.unwrapped, dict(params or {}), agent_stream, max_steps)
        .agent
    )
    log = train_agent_fast(
        agent, kinematic, episodes, max_steps=max_steps, seed=seed_int(episode_stream)
    )
    seeds = [int(s) for s in np.random.default_rng(evaluation).integers(0, 2**31, rollouts)]
    lengths = [
        [rollout.length for rollout in greedy_evaluation(agent, env, max_steps, seeds)]
        for env in (kinematic, physical)
    ]
    on_kinematic, on_physics = (rollout_summary(each) for each in lengths)
    result = TransferResult(
        agent_name, seed, on_kinematic[0], on_physics[0], on_kinematic[1], on_physics[1]
    )
    return TransferRun(result, log)
