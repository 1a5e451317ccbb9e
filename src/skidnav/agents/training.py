"""The episode loop, written once, and the plain training loop: any agent on any Gymnasium env
with Discrete actions and Discrete (tabular agents) or Box (agents on continuous states)
observations.

:func:`train_episodes` is the one episode loop: a family hands it an :data:`EpisodeFunction`
and an :data:`EvaluationFunction`, and it owns the reset seeds, the timing, the greedy
:class:`Evaluation` after each episode and the :class:`TrainingLog` of per-episode arrays.
:func:`train_agent` is that loop with the plain pair (:func:`plain_episodes`,
:func:`plain_evaluations`); a compiled trainer passes its own pair. Every family trainer has
the signature ``trainer(agent, env, episodes, /, *, max_steps=None, evaluation=NO_EVALUATION,
seed=None) -> TrainingLog``. :func:`train_for_steps` runs a fixed number of real steps across
episodes (the cumulative-reward view of Sutton & Barto (2018) Examples 8.2 and 8.3).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple, Protocol, TypeAlias

import gymnasium as gym
import numpy as np

from skidnav.agents.callbacks import current_listener
from skidnav.agents.greedy import (
    NOT_REACHED,
    Greedy,
    Rollout,
    as_state,
    greedy_evaluation,
)
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


class Evaluation(NamedTuple):
    """How the greedy policy is measured after each training episode: rollouts on ``env``
    (:func:`greedy_evaluation`), one per seed of ``seeds``, each cut at :meth:`limit` actions.
    The same seeds at every evaluation meet the same slip noise (common random numbers)."""

    env: gym.Env[Any, Any] | None = None
    """Where the greedy rollouts run; None: no evaluation (every rollout :data:`NOT_REACHED`)."""
    seeds: Sequence[int] | None = None
    """One rollout per seed (each from ``env.reset(seed=s)``); None: one rollout continuing the
    env's own generator (whose first reset the loop seeds with the training seed + 1)."""
    max_steps: int | None = None
    """Actions per rollout; None: the training ``max_steps``, else 10,000."""

    @property
    def n_rollouts(self) -> int:
        """Rollouts per evaluation: one per seed, else one."""
        return 1 if self.seeds is None else len(self.seeds)

    def limit(self, max_steps: int | None) -> int:
        """Actions per rollout when training cuts episodes at ``max_steps`` (None: uncut)."""
        return self.max_steps or max_steps or 10_000

    def start(self, seed: int | None) -> None:
        """Seed the env's first reset with ``seed + 1`` if there are an env, a training ``seed``
        and no ``seeds`` (whose rollouts each reset with their own seed)."""
        if self.env is not None and seed is not None and self.seeds is None:
            self.env.reset(seed=seed + 1)

    def run(self, evaluate: EvaluationFunction, limit: int) -> list[Rollout]:
        """One evaluation's rollouts: ``evaluate(limit)`` if there is an env, else
        :data:`NOT_REACHED` each."""
        return [NOT_REACHED] * self.n_rollouts if self.env is None else evaluate(limit)


NO_EVALUATION = Evaluation()
"""Training without greedy evaluations (the log's ``greedy_lengths`` all −1)."""


class Episode(NamedTuple):
    """One learning episode, as an :data:`EpisodeFunction` returns it."""

    total: float
    """Its return: the undiscounted sum of rewards."""
    length: int
    """Actions taken."""
    terminated: bool
    """True if it reached a terminal state rather than being truncated."""
    collisions: int
    """Steps whose ``info["collision"]`` was true."""
    planning_updates: int
    """Model-based updates made during the episode (its ``end_episode`` included)."""


EpisodeFunction: TypeAlias = Callable[[int | None], Episode]
"""A family's learning episode: from ``env.reset(seed=seed)`` (None: the env's own generator)
to the episode's end (goal, the env's limit or the training ``max_steps``)."""
EvaluationFunction: TypeAlias = Callable[[int], list[Rollout]]
"""A family's greedy evaluation: the rollouts of one :class:`Evaluation`, each cut at the
given number of actions."""


def _check_spaces(env: gym.Env[Any, Any]) -> None:
    if not isinstance(env.observation_space, (gym.spaces.Discrete, gym.spaces.Box)) or not (
        isinstance(env.action_space, gym.spaces.Discrete)
    ):
        raise UserError("expected an env with Discrete actions and Discrete or Box observations")


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


def plain_episodes(
    agent: Learner, env: gym.Env[Any, Any], max_steps: int | None
) -> EpisodeFunction:
    """The :data:`EpisodeFunction` of the plain loop: ``env.reset(seed=seed)``, then
    :func:`run_episode` (``max_steps`` actions at most, if given)."""

    def episode(seed: int | None) -> Episode:
        planned_before = agent.planning_updates
        state, _ = env.reset(seed=seed)
        total, length, terminated, collisions = run_episode(agent, env, as_state(state), max_steps)
        return Episode(
            total, length, terminated, collisions, agent.planning_updates - planned_before
        )

    return episode


def plain_evaluations(agent: Greedy, evaluation: Evaluation) -> EvaluationFunction:
    """The :data:`EvaluationFunction` of the plain loop: :func:`greedy_evaluation` of ``agent``
    on ``evaluation.env`` with ``evaluation.seeds``."""

    def evaluate(limit: int) -> list[Rollout]:
        assert evaluation.env is not None  # the loop evaluates only with an env
        return greedy_evaluation(agent, evaluation.env, limit, evaluation.seeds)

    return evaluate


def train_agent(
    agent: Learner,
    env: gym.Env[Any, Any],
    episodes: int,
    /,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """Train ``agent`` for ``episodes`` episodes on ``env`` (Discrete actions, Discrete or Box
    observations; UserError otherwise): :func:`train_episodes` of the plain loop
    (:func:`plain_episodes`, :func:`plain_evaluations`), with its ``max_steps``,
    ``evaluation`` and ``seed``."""
    _check_spaces(env)
    return train_plain(agent, env, episodes, max_steps=max_steps, evaluation=evaluation, seed=seed)


def train_plain(
    agent: Learner,
    env: gym.Env[Any, Any],
    episodes: int,
    /,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """:func:`train_agent` on an env whose spaces the caller has checked: a family of other
    actions (``mppi-kinematic``'s wheel speeds) trains through the same loop."""
    return train_episodes(
        plain_episodes(agent, env, max_steps), plain_evaluations(agent, evaluation), episodes,
        max_steps=max_steps, evaluation=evaluation, seed=seed,
    )  # fmt: skip


def train_episodes(
    run: EpisodeFunction,
    evaluate: EvaluationFunction,
    episodes: int,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """The episode loop of every family that can run one episode at a time.

    1. Check the arguments (ValueError unless ``episodes`` >= 0 and ``max_steps``, if given,
       >= 1); the rollout limit is ``evaluation.limit(max_steps)``.
    2. Run ``episodes`` episodes (``run``), the first from ``reset(seed=seed)``, the others
       continuing the env's own generator, as Gymnasium intends; each is timed.
    3. After each, record the greedy evaluation (:meth:`Evaluation.run`; after the first
       episode, :meth:`Evaluation.start` seeds the evaluation env with ``seed + 1``), and stop
       if a training callback asks (:mod:`skidnav.agents.callbacks`).
    4. Return the :class:`TrainingLog` of the episodes run.
    """
    if episodes < 0 or (max_steps is not None and max_steps < 1):
        raise ValueError(f"expected episodes >= 0 and max_steps >= 1, got {episodes}, {max_steps}")
    limit = evaluation.limit(max_steps)
    rows = LogRows(evaluation.n_rollouts)
    for episode in range(episodes):
        start = time.perf_counter()
        result = run(seed if episode == 0 else None)
        wall_time = time.perf_counter() - start
        if episode == 0:
            evaluation.start(seed)
        rows.add(result, wall_time, evaluation.run(evaluate, limit))
        if rows.stopped:
            break
    return rows.log()


class LogRows:
    """A :class:`TrainingLog` written one episode at a time (:meth:`add`), each evaluation of
    ``n_rollouts`` rollouts: every family's loop records its episodes here, so the training
    callback (:func:`skidnav.agents.callbacks.listening`, read when the rows are made) is told
    of each here, and :attr:`stopped` says when it asked to stop."""

    dtypes = (
        np.float64, np.int64, np.bool_, np.int64, np.int64, np.float64, np.int64, np.float64,
    )  # fmt: skip
    """dtypes of the :class:`TrainingLog` fields, in order."""
    episode_fields = ("returns", "lengths", "successes", "collisions", "planning_updates")
    """The :class:`TrainingLog` fields of an :class:`Episode`, in order."""

    def __init__(self, n_rollouts: int) -> None:
        self.n_rollouts = n_rollouts
        self.columns: dict[str, list[Any]] = {name: [] for name in TrainingLog._fields}
        self.listener = current_listener()
        self.stopped = False
        """True once the training callback asked to stop (it is not called again)."""

    def __len__(self) -> int:
        """Episodes recorded."""
        return len(self.columns["returns"])

    def add(self, episode: Episode, wall_time: float, rollouts: Sequence[Rollout]) -> None:
        """Record ``episode``, its ``wall_time`` [s] and the ``rollouts`` of the greedy
        evaluation after it."""
        for name, value in zip(self.episode_fields, episode, strict=True):
            self.columns[name].append(value)
        self.columns["wall_time"].append(wall_time)
        self.columns["greedy_lengths"].append([rollout.length for rollout in rollouts])
        self.columns["greedy_costs"].append([rollout.cost for rollout in rollouts])
        if self.listener is not None and not self.stopped:
            self.stopped = self.listener.tell(
                len(self), episode.length, episode.total, episode.terminated, wall_time
            )

    def log(self) -> TrainingLog:
        """The arrays of the episodes recorded so far."""
        arrays: dict[str, np.ndarray] = {
            name: np.array(self.columns[name], dtype=dtype)
            for name, dtype in zip(TrainingLog._fields, self.dtypes, strict=True)
        }
        for name in ("greedy_lengths", "greedy_costs"):
            arrays[name] = arrays[name].reshape(-1, self.n_rollouts)
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
