"""One run of the textbook checks: one agent of one check (:class:`~skidnav.studies.sutton_barto.
grid.Check`) trained once on its maze, with the fused compiled maze trainers
(:mod:`skidnav.agents.tabular.fast_training`; the same numbers as the plain Gymnasium loop).

Its randomness: the agent's generator (ε-greedy, planning samples) is the ``"agent"`` child of the
run's stream ``RunSpec.run_seed`` and the env's first ``reset`` seed its ``"episodes"`` child
(:data:`~skidnav.seeding.RUN_ROLES`, as an experiment's runs); the mazes themselves are
deterministic.

What a run measures (Sutton & Barto (2018) ch. 8):

* Dyna Maze (Example 8.1): the actions of each of its 50 episodes;
* blocking and shortcut mazes (Examples 8.2/8.3): a fixed number of time steps, the walls changing
  part-way; its episodes (the last one cut short by the end of the steps) give the cumulative
  reward after every step (:func:`cumulative_reward`);
* prioritized sweeping (Example 8.4): episodes until the greedy path is first within
  :data:`PATH_TOLERANCE` of the shortest path, and the value updates made until then
  (:func:`updates_until_near_optimal`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav.agents.catalog import entry
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.agents.tabular.fast_training import train_agent_fast, train_for_steps_fast
from skidnav.agents.training import Evaluation
from skidnav.envs.mazes import GridMazeEnv, blocking_maze, dyna_maze, shortcut_maze
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import TrialResult
from skidnav.seeding import RUN_ROLES, child_sequences, seed_int
from skidnav.studies.sutton_barto.grid import (
    CHANGING_MAZES,
    DYNA_MAZE_EPISODES,
    MAX_SWEEP_EPISODES,
    Check,
    TextbookChecks,
)

PATH_TOLERANCE = 1.2
"""A greedy path at most this many times the shortest counts as near-optimal in Example 8.4: with
ε-greedy exploration from zero values an agent may never try the pairs of the one optimal path."""
N_ACTIONS = 4
"""Up, down, left, right."""
_NO_LIMIT = 10**9
"""Actions per episode a family may cut at when building an agent: the mazes limit their own."""


class RunEpisodes(NamedTuple):
    """What one run gives: per episode (each shape (E,)) ``steps`` int64 [actions] and ``reward``
    float64, and the run's summary."""

    steps: np.ndarray
    reward: np.ndarray
    summary: dict[str, float]


def checks_trial(spec: RunSpec[TextbookChecks]) -> TrialResult:
    """The runner's trial function of the checks: check ``spec.agent.label``, run ``spec.seed``
    (module doc)."""
    check = spec.config.check(spec.agent.label)
    streams = child_sequences(spec.run_seed.sequence(), RUN_ROLES)
    agent_seed = streams["agent"]
    reset_seed = seed_int(streams["episodes"])
    if check.example == "dyna-maze":
        run = dyna_maze_run(check, agent_seed, reset_seed)
    elif check.example == "prioritized-sweeping":
        run = sweeping_run(check, agent_seed, reset_seed)
    else:
        run = changing_maze_run(check, agent_seed, reset_seed)
    episodes = {"steps": run.steps.astype(np.int64), "reward": run.reward.astype(np.float64)}
    return TrialResult(spec.run_id, spec.coordinates, episodes, run.summary, {})


def _agent(check: Check, env: GridMazeEnv, seed: np.random.SeedSequence) -> TabularAgent:
    """A new agent of the check, made as its family makes one (the catalog), drawing from
    ``seed``."""
    built = entry(check.agent).build(env, dict(check.params), seed, _NO_LIMIT)
    agent: TabularAgent = built.agent
    return agent


def dyna_maze_run(check: Check, agent_seed: np.random.SeedSequence, reset_seed: int) -> RunEpisodes:
    """Example 8.1: :data:`DYNA_MAZE_EPISODES` episodes of Dyna-Q (the check's n) on the Dyna
    Maze; the summary holds n and the mean actions of the last 10 episodes."""
    env = dyna_maze()
    log = train_agent_fast(_agent(check, env, agent_seed), env, DYNA_MAZE_EPISODES, seed=reset_seed)
    summary = {
        "planning_steps": float(check.planning_steps),
        "last_10_steps": float(log.lengths[-10:].mean()),
    }
    return RunEpisodes(log.lengths, log.returns, summary)


def changing_maze_run(
    check: Check, agent_seed: np.random.SeedSequence, reset_seed: int
) -> RunEpisodes:
    """Examples 8.2/8.3: the check's time steps on its maze (:data:`CHANGING_MAZES`); the
    summary holds the reward gathered before and after the change."""
    n_steps, change = CHANGING_MAZES[check.example]
    make_maze = blocking_maze if check.example == "blocking-maze" else shortcut_maze
    env = make_maze(change_after=change)
    gathered = train_for_steps_fast(_agent(check, env, agent_seed), env, n_steps, seed=reset_seed)
    steps, reward = episodes_of(gathered)
    summary = {
        "change_step": float(change),
        "reward_before_change": float(gathered[change - 1]),
        "reward_after_change": float(gathered[-1] - gathered[change - 1]),
    }
    return RunEpisodes(steps, reward, summary)


def episodes_of(cumulative: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(steps int64 (E,), reward float64 (E,)) of the episodes behind ``cumulative``, the
    cumulative reward after each time step, float64 (n,), of a maze that rewards 1 at the goal
    (where an episode ends) and 0 otherwise: each goal ends an episode; steps after the last goal
    make a last episode of reward 0. :func:`cumulative_reward` is its inverse."""
    ends = np.flatnonzero(np.diff(cumulative, prepend=0.0) > 0.0) + 1  # steps taken at each goal
    bounds = np.concatenate([[0], ends])
    steps = np.diff(bounds)
    reward = np.ones(len(steps))
    if bounds[-1] < len(cumulative):
        steps = np.append(steps, len(cumulative) - bounds[-1])
        reward = np.append(reward, 0.0)
    return steps.astype(np.int64), reward


def cumulative_reward(steps: np.ndarray, reward: np.ndarray) -> np.ndarray:
    """The cumulative reward after each time step, float64 (Σ steps,), of episodes of ``steps``
    actions each gathering ``reward`` at its last step (:func:`episodes_of`'s inverse)."""
    gained = np.zeros(int(np.sum(steps)))
    ends = np.cumsum(steps) - 1
    gained[ends[steps > 0]] = reward[steps > 0]
    return np.cumsum(gained)


def sweeping_run(check: Check, agent_seed: np.random.SeedSequence, reset_seed: int) -> RunEpisodes:
    """Example 8.4: the check's agent on the Dyna Maze of its scale, an episode at a time until
    its greedy path is near-optimal (:func:`updates_until_near_optimal`); the summary holds the
    scale, the states, the shortest path [actions] and the value updates (NaN: not within
    :data:`MAX_SWEEP_EPISODES` episodes)."""
    env = dyna_maze(check.scale)
    agent = _agent(check, env, agent_seed)
    steps, reward, updates = updates_until_near_optimal(agent, check.scale, reset_seed)
    summary = {
        "scale": float(check.scale),
        "n_states": float(env.n_rows * env.n_cols),
        "shortest_path": float(env.shortest_path_length()),
        "updates": updates,
    }
    return RunEpisodes(steps, reward, summary)


def updates_until_near_optimal(
    agent: TabularAgent, scale: int, reset_seed: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """(steps, reward, value updates) of ``agent`` trained an episode at a time on the Dyna Maze
    of ``scale`` until the greedy path is first within :data:`PATH_TOLERANCE` of the shortest
    (NaN updates if not within :data:`MAX_SWEEP_EPISODES` episodes). Value updates: real and
    planning ones for Dyna-Q; for prioritized sweeping the queue's (its real steps only queue)."""
    env = dyna_maze(scale)
    shortest = env.shortest_path_length()
    steps, reward = [], []
    for episode in range(MAX_SWEEP_EPISODES):
        log = train_agent_fast(
            agent, env, 1, evaluation=Evaluation(dyna_maze(scale), max_steps=4 * shortest),
            seed=reset_seed if episode == 0 else None,
        )  # fmt: skip
        steps.append(int(log.lengths[0]))
        reward.append(float(log.returns[0]))
        greedy = int(log.greedy_lengths[0, 0])
        if 0 < greedy <= PATH_TOLERANCE * shortest:
            real = 0 if agent.name == "prioritized-sweeping" else agent.steps
            return np.array(steps), np.array(reward), float(real + agent.planning_updates)
    return np.array(steps), np.array(reward), math.nan
