"""The fused compiled loop: whole stretches of an episode in one numba call (used by
:mod:`skidnav.agents.tabular.fast_training`).

The loop knows how an episode goes, and nothing of the agent or of the env: it calls the env's
step through :func:`skidnav.agents.tabular.env_steps.env_step` and the agent's learning step through
:func:`skidnav.agents.learning.learn`, both chosen while compiling by the type of the env's
state and of the agent's arrays (numba compiles and caches the loop once per such pair). Each
step does what the plain Python loop (:func:`skidnav.agents.training.run_episode` driving
``env.step`` and the agent's ``observe``) does, in the same order and with the same draws, so
both give identical numbers:

1. ``epsilon_greedy(q, s, ε, agent_rng)`` (:mod:`skidnav.sim.q_values`);
2. the env's step with the env's generator;
3. the agent's learning step with the agent's generator;
4. the end: termination, the env's limit or the trainer's ``max_steps``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from skidnav._jit import jit, uncached
from skidnav.agents.learning import STEPS, Experience, learn
from skidnav.agents.tabular.env_steps import env_step
from skidnav.sim.q_values import epsilon_greedy, greedy_first

# columns of the int64 ``tally`` array of one episode
LENGTH, COLLISIONS, TERMINATED, ELAPSED, ENDED = range(5)
N_TALLY = 5
"""``LENGTH``: steps taken by this episode's calls; ``COLLISIONS``; ``TERMINATED`` and ``ENDED``
(0/1: the goal was reached; the episode is over); ``ELAPSED``: the env's steps since its reset."""


class Limits(NamedTuple):
    """When a stretch stops: the env's step limit, the trainer's ``max_steps`` (both per
    episode), and ``stop``, the ``tally[LENGTH]`` at which to pause without ending the episode."""

    env_limit: int
    max_steps: int
    stop: int


@jit
def learn_stretch(
    env: Any,
    state: int,
    arrays: Any,
    settings: Any,
    epsilon: float,
    counters: np.ndarray,
    tally: np.ndarray,
    limits: Limits,
    returns: tuple[float, np.ndarray],
    rngs: tuple[np.random.Generator, np.random.Generator],
) -> tuple[float, int]:
    """Learn from ``state`` until the episode ends or ``tally[LENGTH]`` reaches ``limits.stop``.

    :func:`~skidnav.agents.tabular.env_steps.env_step` moves ``env`` (whose ``pose`` and ``log`` the
    experience carries); :func:`~skidnav.agents.learning.learn` teaches the agent whose
    ``arrays``, ``settings`` and ``counters`` these are. ``returns`` is (the return so
    far, float64 rewards array: reward of step k at ``[tally[LENGTH]]`` unless it is empty);
    ``rngs`` (env's, agent's). Returns (the return so far, the state reached).
    """
    total, rewards = returns
    env_rng, agent_rng = rngs
    while tally[LENGTH] < limits.stop:
        action = epsilon_greedy(arrays.q, state, epsilon, agent_rng)
        next_state, reward, terminated, collided, n_logged, _ = env_step(
            env, state, action, env_rng
        )
        if rewards.shape[0] > 0:
            rewards[tally[LENGTH]] = reward
        tally[ELAPSED] += 1
        tally[LENGTH] += 1
        tally[COLLISIONS] += 1 if collided else 0
        counters[STEPS] += 1
        total += reward
        experience = Experience(
            state, action, reward, next_state, terminated, collided, env.pose, env.log, n_logged
        )
        learn(arrays, settings, counters, experience, agent_rng)
        state = next_state
        if terminated or tally[ELAPSED] >= limits.env_limit or tally[LENGTH] >= limits.max_steps:
            tally[TERMINATED] = 1 if terminated else 0
            tally[ENDED] = 1
            break
    return total, state


learn_stretch_uncached = uncached(learn_stretch)
""":func:`learn_stretch` for agents whose arrays are not skidnav's own types (not cached)."""


@jit
def greedy_stretch(
    env: Any,
    state: int,
    q: np.ndarray,
    max_steps: int,
    env_limit: int,
    env_rng: np.random.Generator,
) -> tuple[int, float, int, int]:
    """Greedy rollout (``greedy_first``, no learning) from a reset env: returns (actions taken if
    the goal was reached else −1, the sum of the steps' costs in step order if it was else NaN,
    last state, actions taken)."""
    cost = 0.0
    for step in range(1, max_steps + 1):
        state, _, terminated, _, _, step_cost = env_step(
            env, state, greedy_first(q, state), env_rng
        )
        cost += step_cost
        if terminated:
            return step, cost, state, step
        if step >= env_limit:
            return -1, np.nan, state, step
    return -1, np.nan, state, max_steps
