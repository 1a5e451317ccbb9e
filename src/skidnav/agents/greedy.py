"""Greedy rollouts: the greedy policy of any agent run on any Gymnasium env without learning,
its :class:`Rollout` (length and cost), the poses it passes through, and one evaluation's
rollouts over fixed reset seeds (common random numbers). The training loop
(:mod:`skidnav.agents.training`) runs them after every episode.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np


class Greedy(Protocol):
    """What a greedy evaluation needs from an agent: its greedy action in a state (an int, or
    wheel speeds for Box actions)."""

    def greedy_action(self, state: Any) -> Any: ...


@runtime_checkable
class RolloutState(Protocol):
    """A greedy policy with a state of its own within a rollout: a model predictive controller's
    plan, warm-started from action to action (``mppi-kinematic``). Every rollout starts by
    forgetting it, so a rollout's actions do not depend on the rollouts before it."""

    def start_greedy_rollout(self) -> None:
        """Forget what the previous rollout left (called after each ``env.reset``)."""
        ...


def start_rollout(policy: object) -> None:
    """Tell ``policy`` that a greedy rollout starts, if it keeps a state (:class:`RolloutState`);
    nothing for any other policy."""
    if isinstance(policy, RolloutState):
        policy.start_greedy_rollout()


class Rollout(NamedTuple):
    """One greedy rollout: its ``length`` [actions] and ``cost`` (the sum of ``info["cost"]`` over
    its actions) if it reached the goal, else −1 and NaN."""

    length: int
    cost: float


NOT_REACHED = Rollout(-1, math.nan)
"""A rollout that did not reach the goal (or was not run)."""
_NO_POSE = (math.nan, math.nan, math.nan)
"""The pose :func:`greedy_run` records for an env whose ``info`` has none."""


def as_state(observation: Any) -> Any:
    """The state an agent takes for ``observation``: an int for a Discrete one (NumPy integers
    included), a float64 array for a Box one."""
    if isinstance(observation, np.ndarray) and observation.ndim > 0:
        return np.asarray(observation, dtype=np.float64)
    return int(observation)


def greedy_run(
    agent: Greedy,
    env: gym.Env[Any, Any],
    max_steps: int,
    *,
    seed: int | None = None,
    poses: list[Any] | None = None,
) -> Rollout:
    """Run the greedy policy for at most ``max_steps`` actions (without learning) from
    ``env.reset(seed=seed)`` (a policy with a state of its own forgets it first:
    :func:`start_rollout`); its :class:`Rollout` (the costs summed in step order, NaN for an
    env whose info has no ``"cost"``). A list ``poses`` receives ``info["pose"]`` (x [m], y [m],
    heading [rad]) of the reset and of every action, NaN where the env reports none
    (:func:`greedy_path`)."""
    state, info = env.reset(seed=seed)
    start_rollout(agent)
    if poses is not None:
        poses.append(info.get("pose", _NO_POSE))
    cost = 0.0
    for step in range(1, max_steps + 1):
        state, _, terminated, truncated, info = env.step(agent.greedy_action(as_state(state)))
        if poses is not None:
            poses.append(info.get("pose", _NO_POSE))
        cost += float(info.get("cost", math.nan))
        if terminated:
            return Rollout(step, cost)
        if truncated:
            return NOT_REACHED
    return NOT_REACHED


def greedy_rollout(
    agent: Greedy, env: gym.Env[Any, Any], max_steps: int, *, seed: int | None = None
) -> int:
    """The length of :func:`greedy_run`: the number of actions if the env terminated, else −1."""
    return greedy_run(agent, env, max_steps, seed=seed).length


def greedy_path(
    agent: Greedy, env: gym.Env[Any, Any], max_steps: int, *, seed: int | None = None
) -> tuple[np.ndarray, bool]:
    """The poses :func:`greedy_run` passes through, float64 (T + 1, 3) (x [m], y [m], heading
    [rad]; the reset's, then one per action; NaN rows for an env without ``info["pose"]``), and
    whether it reached the goal."""
    poses: list[Any] = []
    rollout = greedy_run(agent, env, max_steps, seed=seed, poses=poses)
    return np.asarray(poses, dtype=np.float64), rollout.length >= 0


def greedy_evaluation(
    agent: Greedy, env: gym.Env[Any, Any], max_steps: int, seeds: Sequence[int] | None
) -> list[Rollout]:
    """The greedy rollouts of one evaluation (:func:`greedy_run` each): one per seed in
    ``seeds``, each from ``env.reset(seed=seed)`` — the same seeds at every evaluation, so every
    evaluation meets the same slip noise (common random numbers) — or, without seeds, one rollout
    that continues the env's own generator."""
    if seeds is None:
        return [greedy_run(agent, env, max_steps)]
    return [greedy_run(agent, env, max_steps, seed=int(seed)) for seed in seeds]


def rollout_summary(lengths: Sequence[int]) -> tuple[float, float]:
    """(share that reached the goal, mean length [actions] of those that did, NaN if none) of
    greedy rollout lengths as :func:`greedy_rollout` returns them (−1: not reached)."""
    reached = [length for length in lengths if length >= 0]
    return len(reached) / len(lengths), (float(np.mean(reached)) if reached else math.nan)
