"""Training ``mppi-kinematic`` on the navigation env with wheel-speed actions, one real step at a
time, and evaluating its frozen planner: :func:`train_mppi` returns the project's
:class:`~skidnav.agents.training.TrainingLog`, as :func:`skidnav.agents.training.train_agent`
does for the agents of discrete actions.

The env must be the navigation env with ``action="continuous"``, and its observation the pose
(``observation="pose"``) or the features (whose first four entries hold the pose).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from skidnav.agents.mpc.agent import MPPIKinematicAgent, MPPIPolicy
from skidnav.agents.training import (
    NOT_REACHED,
    Rollout,
    TrainingLog,
    log_from_rows,
    record_evaluation,
)

DEFAULT_GREEDY_LIMIT = 10_000
"""Actions of an evaluation rollout without ``greedy_max_steps`` or ``max_steps``."""


def _check_env(env: gym.Env[Any, Any]) -> None:
    """ValueError unless ``env`` takes two wheel speeds."""
    space = env.action_space
    if not isinstance(space, gym.spaces.Box) or space.shape != (2,):
        raise ValueError("expected an env of two wheel speeds (action='continuous')")


def run_episode(
    agent: MPPIKinematicAgent, env: gym.Env[Any, Any], observation: Any, max_steps: int | None
) -> tuple[float, int, bool, int]:
    """One learning episode from ``observation`` (the env already reset): act, step, observe,
    until the goal or the limit (the env's or ``max_steps``), then ``end_episode``. Returns
    (return, actions, whether the goal was reached, collisions)."""
    total, length, collisions = 0.0, 0, 0
    while True:
        action = agent.act(observation)
        next_observation, reward, terminated, truncated, info = env.step(action)
        length += 1
        truncated = bool(truncated) or (max_steps is not None and length >= max_steps)
        collisions += int(bool(info.get("collision", False)))
        total += float(reward)
        agent.observe(
            observation, action, float(reward), next_observation, bool(terminated), truncated, info
        )
        observation = next_observation
        if terminated or truncated:
            agent.end_episode()
            return total, length, bool(terminated), collisions


def policy_run(
    policy: MPPIPolicy, env: gym.Env[Any, Any], max_steps: int, *, seed: int | None = None
) -> Rollout:
    """One rollout of a frozen planner from ``env.reset(seed=seed)`` (its plan forgotten
    first), at most ``max_steps`` actions: its length and summed ``info["cost"]`` if it reached
    the goal, else :data:`~skidnav.agents.training.NOT_REACHED`."""
    policy.reset()
    observation, _ = env.reset(seed=seed)
    cost = 0.0
    for step in range(1, max_steps + 1):
        action = np.array(policy.wheel_speeds(observation))
        observation, _, terminated, truncated, info = env.step(action)
        cost += float(info.get("cost", math.nan))
        if terminated:
            return Rollout(step, cost)
        if truncated:
            return NOT_REACHED
    return NOT_REACHED


def train_mppi(
    agent: MPPIKinematicAgent,
    env: gym.Env[Any, Any],
    episodes: int,
    max_steps: int | None = None,
    *,
    greedy_eval_env: gym.Env[Any, Any] | None = None,
    greedy_max_steps: int | None = None,
    greedy_seeds: Sequence[int] | None = None,
    seed: int | None = None,
    policy_seed: int = 0,
) -> TrainingLog:
    """Train ``agent`` for ``episodes`` episodes on ``env`` (semantics of
    :func:`~skidnav.agents.training.train_agent`: ``seed`` seeds the first reset, ``max_steps``
    truncates an episode). After each episode its frozen planner (:meth:`MPPIKinematicAgent.
    policy` seeded ``policy_seed``: every evaluation draws the same numbers, and none of the
    agent's) is rolled out on ``greedy_eval_env``, once per seed of ``greedy_seeds`` (else once,
    continuing that env's generator, first reset with ``seed + 1``), each stopped after
    ``greedy_max_steps`` actions (default ``max_steps``, else 10,000). ``planning_updates`` of
    the log counts the sequences rolled out through the model (K per action)."""
    if episodes < 0 or (max_steps is not None and max_steps < 1):
        raise ValueError(f"expected episodes >= 0 and max_steps >= 1, got {episodes}, {max_steps}")
    _check_env(env)
    limit = greedy_max_steps or max_steps or DEFAULT_GREEDY_LIMIT
    n_rollouts = 1 if greedy_seeds is None else len(greedy_seeds)
    columns: dict[str, list[Any]] = {name: [] for name in TrainingLog._fields}
    for episode in range(episodes):
        start, rolled_before = time.perf_counter(), agent.rollouts
        observation, _ = env.reset(seed=seed if episode == 0 else None)
        total, length, success, collisions = run_episode(agent, env, observation, max_steps)
        columns["wall_time"].append(time.perf_counter() - start)
        columns["returns"].append(total)
        columns["lengths"].append(length)
        columns["successes"].append(success)
        columns["collisions"].append(collisions)
        columns["planning_updates"].append(agent.rollouts - rolled_before)
        rollouts = [NOT_REACHED] * n_rollouts
        if greedy_eval_env is not None:
            if episode == 0 and seed is not None and greedy_seeds is None:
                greedy_eval_env.reset(seed=seed + 1)
            policy = agent.policy(policy_seed)
            seeds: Sequence[int | None] = [None] if greedy_seeds is None else greedy_seeds
            rollouts = [policy_run(policy, greedy_eval_env, limit, seed=s) for s in seeds]
        record_evaluation(columns, rollouts)
    return log_from_rows(columns, n_rollouts)
