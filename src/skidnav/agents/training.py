"""The plain training loop: any agent on any Gymnasium env with Discrete actions and Discrete
(tabular agents) or Box (agents on continuous states) observations.

:func:`train_agent` runs whole episodes and returns a :class:`TrainingLog` of per-episode arrays;
:func:`train_for_steps` runs a fixed number of real steps across episodes (the cumulative-reward
view of Sutton & Barto (2018) Examples 8.2 and 8.3). A compiled trainer may replace
:func:`train_agent` for speed as long as it has the same signature and output.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any, NamedTuple, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np

from skidnav.errors import UserError


class Learner(Protocol):
    """What the loop needs from an agent (every :class:`~skidnav.agents.tabular.agent.TabularAgent`,
    the agents on continuous states, ``mppi-kinematic``). A state is what :func:`as_state` makes of
    an observation: an int for a Discrete observation, a float64 array for a Box one; an action
    is an int for Discrete actions, the wheel speeds float64 (2,) [rad/s] for the Box actions of
    ``action="continuous"``."""

    @property
    def planning_updates(self) -> int:
        """Model-based updates (or model rollouts) made so far."""
        ...

    def act(self, state: Any) -> Any: ...

    def greedy_action(self, state: Any) -> Any: ...

    def observe(
        self,
        state: Any,
        action: int,
        reward: float,
        next_state: Any,
        terminated: bool,
        truncated: bool,
        info: dict[str, Any],
    ) -> None: ...

    def end_episode(self) -> None: ...


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


class TrainingLog(NamedTuple):
    """Per-episode results, each an array of shape (n_episodes,)."""

    returns: np.ndarray
    """Undiscounted sum of rewards (float64)."""
    lengths: np.ndarray
    """Actions taken (int64)."""
    successes: np.ndarray
    """True if the episode terminated (reached a terminal state) rather than being truncated."""
    collisions: np.ndarray
    """Steps whose ``info["collision"]`` was true (int64; 0 for envs without the key)."""
    planning_updates: np.ndarray
    """Model-based value updates made **during** the episode (int64; ``np.cumsum`` for totals)."""
    wall_time: np.ndarray
    """Seconds spent in the episode, greedy evaluation excluded (float64)."""
    greedy_lengths: np.ndarray
    """Lengths of the greedy rollouts on the evaluation env after the episode, int64
    (n_episodes, n_rollouts): one column per evaluation seed (one column without seeds); −1 where
    a rollout did not terminate within the limit, or everywhere if no evaluation env was given."""
    greedy_costs: np.ndarray
    """Costs of the same rollouts, float64 (n_episodes, n_rollouts): the sum of the costs the
    evaluation env reports for its actions (``info["cost"]``: on the navigation env minus the
    reward without the goal bonus, :func:`skidnav.sim.navigation.action_cost`); NaN where the
    length is −1, and where the env reports no cost."""


class Rollout(NamedTuple):
    """One greedy rollout: its ``length`` [actions] and ``cost`` (the sum of ``info["cost"]`` over
    its actions) if it reached the goal, else −1 and NaN."""

    length: int
    cost: float


NOT_REACHED = Rollout(-1, math.nan)
"""A rollout that did not reach the goal (or was not run)."""
_NO_POSE = (math.nan, math.nan, math.nan)
"""The pose :func:`greedy_run` records for an env whose ``info`` has none."""


def _check_spaces(env: gym.Env[Any, Any]) -> None:
    if not isinstance(env.observation_space, (gym.spaces.Discrete, gym.spaces.Box)) or not (
        isinstance(env.action_space, gym.spaces.Discrete)
    ):
        raise UserError("expected an env with Discrete actions and Discrete or Box observations")


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


def record_evaluation(columns: dict[str, list[Any]], rollouts: Sequence[Rollout]) -> None:
    """Append one evaluation's ``rollouts`` to the ``greedy_lengths`` and ``greedy_costs``
    lists of ``columns`` (:func:`log_from_rows`)."""
    columns["greedy_lengths"].append([rollout.length for rollout in rollouts])
    columns["greedy_costs"].append([rollout.cost for rollout in rollouts])


def rollout_summary(lengths: Sequence[int]) -> tuple[float, float]:
    """(share that reached the goal, mean length [actions] of those that did, NaN if none) of
    greedy rollout lengths as :func:`greedy_rollout` returns them (−1: not reached)."""
    reached = [length for length in lengths if length >= 0]
    return len(reached) / len(lengths), (float(np.mean(reached)) if reached else math.nan)


def run_episode(
    agent: Learner, env: gym.Env[Any, Any], state: Any, max_steps: int | None
) -> tuple[float, int, bool, int]:
    """One learning episode from ``state`` (already reset); returns (return, length, terminated,
    collisions). The episode is truncated after ``max_steps`` actions if given."""
    total, length, collisions = 0.0, 0, 0
    while True:
        action = agent.act(state)
        next_state, reward, terminated, truncated, info = env.step(action)
        length += 1
        truncated = bool(truncated) or (max_steps is not None and length >= max_steps)
        collisions += int(bool(info.get("collision", False)))
        total += float(reward)
        next_state = as_state(next_state)
        agent.observe(state, action, float(reward), next_state, bool(terminated), truncated, info)
        state = next_state
        if terminated or truncated:
            agent.end_episode()
            return total, length, bool(terminated), collisions


def train_agent(
    agent: Learner,
    env: gym.Env[Any, Any],
    n_episodes: int,
    *,
    max_steps: int | None = None,
    greedy_eval_env: gym.Env[Any, Any] | None = None,
    greedy_max_steps: int | None = None,
    greedy_seeds: Sequence[int] | None = None,
    seed: int | None = None,
) -> TrainingLog:
    """Train ``agent`` for ``n_episodes`` episodes on ``env``.

    ``max_steps`` truncates each episode (the env's own time limit applies too). ``seed`` seeds the
    first ``env.reset`` (and, without ``greedy_seeds``, ``seed + 1`` the evaluation env's first
    reset); later resets continue the env's own generator, as Gymnasium intends. After each
    episode the greedy policy is evaluated on ``greedy_eval_env`` (:func:`greedy_evaluation`:
    one rollout per seed of ``greedy_seeds``), each rollout stopped after ``greedy_max_steps``
    actions (default: ``max_steps``, else 10,000).
    """
    _check_spaces(env)
    return train_loop(
        agent, env, n_episodes, max_steps=max_steps, greedy_eval_env=greedy_eval_env,
        greedy_max_steps=greedy_max_steps, greedy_seeds=greedy_seeds, seed=seed,
    )  # fmt: skip


def train_loop(
    agent: Learner,
    env: gym.Env[Any, Any],
    n_episodes: int,
    *,
    max_steps: int | None = None,
    greedy_eval_env: gym.Env[Any, Any] | None = None,
    greedy_max_steps: int | None = None,
    greedy_seeds: Sequence[int] | None = None,
    seed: int | None = None,
) -> TrainingLog:
    """The episodes of :func:`train_agent` (same arguments and log) on an env whose spaces the
    caller has checked: a family of other actions (``mppi-kinematic``'s wheel speeds) trains
    through the same loop and evaluations."""
    if n_episodes < 0 or (max_steps is not None and max_steps < 1):
        raise ValueError(
            f"expected n_episodes >= 0 and max_steps >= 1, got {n_episodes}, {max_steps}"
        )
    limit = greedy_max_steps or max_steps or 10_000
    columns: dict[str, list[Any]] = {name: [] for name in TrainingLog._fields}
    for episode in range(n_episodes):
        start = time.perf_counter()
        planned_before = agent.planning_updates
        state, _ = env.reset(seed=seed if episode == 0 else None)
        total, length, success, collisions = run_episode(agent, env, as_state(state), max_steps)
        columns["wall_time"].append(time.perf_counter() - start)
        columns["returns"].append(total)
        columns["lengths"].append(length)
        columns["successes"].append(success)
        columns["collisions"].append(collisions)
        columns["planning_updates"].append(agent.planning_updates - planned_before)
        greedy = [NOT_REACHED] * (1 if greedy_seeds is None else len(greedy_seeds))
        if greedy_eval_env is not None:
            if episode == 0 and seed is not None and greedy_seeds is None:
                greedy_eval_env.reset(seed=seed + 1)
            greedy = greedy_evaluation(agent, greedy_eval_env, limit, greedy_seeds)
        record_evaluation(columns, greedy)
    return log_from_rows(columns, 1 if greedy_seeds is None else len(greedy_seeds))


LOG_DTYPES = (
    np.float64, np.int64, np.bool_, np.int64, np.int64, np.float64, np.int64, np.float64,
)  # fmt: skip
"""dtypes of the :class:`TrainingLog` fields, in order."""


def log_from_rows(columns: dict[str, list[Any]], n_rollouts: int) -> TrainingLog:
    """A :class:`TrainingLog` from per-episode lists keyed by field name (``greedy_lengths``
    and ``greedy_costs`` hold one list of ``n_rollouts`` values per episode:
    :func:`record_evaluation`)."""
    arrays: dict[str, np.ndarray] = {
        name: np.array(columns[name], dtype=dtype)
        for name, dtype in zip(TrainingLog._fields, LOG_DTYPES, strict=True)
    }
    for name in ("greedy_lengths", "greedy_costs"):
        arrays[name] = arrays[name].reshape(-1, n_rollouts)
    return TrainingLog(**arrays)


def train_for_steps(
    agent: Learner, env: gym.Env[Any, Any], n_steps: int, *, seed: int | None = None
) -> np.ndarray:
    """Train for exactly ``n_steps`` real steps, starting new episodes as needed (an unfinished
    last episode is left open, without ``end_episode``). Returns the cumulative reward after each
    step, float64 (n_steps,)."""
    _check_spaces(env)
    cumulative = np.zeros(n_steps, dtype=np.float64)
    observation, _ = env.reset(seed=seed)
    state, total = as_state(observation), 0.0
    for step in range(n_steps):
        action = agent.act(state)
        observation, reward, terminated, truncated, info = env.step(action)
        total += float(reward)
        cumulative[step] = total
        next_state = as_state(observation)
        agent.observe(
            state, action, float(reward), next_state, bool(terminated), bool(truncated), info
        )
        state = next_state
        if terminated or truncated:
            agent.end_episode()
            state = as_state(env.reset()[0])
    return cumulative
