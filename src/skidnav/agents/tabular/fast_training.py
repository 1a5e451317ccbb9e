"""The fused compiled trainers: :func:`train_agent_fast`, a drop-in for
:func:`skidnav.agents.training.train_agent` on ``skidnav/SkidSteerNav-v0`` and on the grid mazes
(:class:`skidnav.envs.mazes.GridMazeEnv`), and :func:`train_for_steps_fast`, a drop-in for
:func:`skidnav.agents.training.train_for_steps` on the same envs.

Episodes run in compiled stretches (:func:`skidnav.agents.tabular.fused_loop.learn_stretch`, at most
:data:`STRETCH` steps each): the env's compiled step (:mod:`skidnav.agents.tabular.env_steps`),
ε-greedy,
and the agent's own learning step — the very kernel its ``observe`` calls, so there is one learning
step per agent. Between stretches Python makes room in the agent's buffers (``reserve``); between
episodes it does what the agent does in ``end_episode`` (ε decay, trajectory bookkeeping, kinematic
refits by the compiled Bayesian ridge) and the greedy evaluation rollouts (also compiled). Same
signature, the same loop (:func:`skidnav.agents.training.train_episodes`: seeds, evaluations,
log), and the same numbers as the plain loop for the same seed (tested), except
``wall_time``. Other envs (the navigation env with ``dynamics="mujoco"`` among them: its physics is
not compiled), or agents that are not a :class:`~skidnav.agents.tabular.agent.TabularAgent`, fall
back to the plain loop. The navigation env's ``trail`` (for rendering) is not recorded.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from skidnav.agents.greedy import Rollout
from skidnav.agents.learning import NO_LOG_ROWS, NO_POSE
from skidnav.agents.tabular import env_steps, fused_loop
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.agents.tabular.fused_loop import ELAPSED, ENDED, LENGTH, Limits
from skidnav.agents.training import (
    NO_EVALUATION,
    Episode,
    EpisodeFunction,
    Evaluation,
    EvaluationFunction,
    TrainingLog,
    train_agent,
    train_episodes,
    train_for_steps,
)

logger = logging.getLogger(__name__)

_BIG = np.iinfo(np.int64).max // 4
STRETCH = 4096
"""Most steps of one compiled call: the room :meth:`TabularAgent.reserve` makes before it."""


def _unwrapped(env: gym.Env[Any, Any]) -> tuple[Any, int]:
    """The innermost env and the smallest step limit along the wrappers (``TimeLimit``) and of
    the env itself (a grid maze's optional ``max_episode_steps``); ``_BIG`` if none."""
    limit = _BIG
    layer: Any = env
    while isinstance(layer, gym.Wrapper):
        if isinstance(layer, gym.wrappers.TimeLimit):
            limit = min(limit, int(layer._max_episode_steps))
        layer = layer.env
    return layer, min(limit, getattr(layer, "max_episode_steps", None) or _BIG)


class FusedEnv:
    """An unwrapped env the compiled loop drives, with the smallest step limit along its
    wrappers; subclasses convert the env's state to and from the loop's
    (:mod:`skidnav.agents.tabular.env_steps`)."""

    def __init__(self, env: Any, limit: int) -> None:
        self.env, self.limit = env, limit

    def reset(self, seed: int | None) -> int:
        """``env.reset(seed=seed)``; the start state."""
        return int(self.env.reset(seed=seed)[0])

    def kernel_state(self) -> Any:
        """The env's state as its compiled step takes it."""
        raise NotImplementedError

    def write_back(self, kernel: Any, state: int, elapsed: int) -> None:
        """Leave the env where the loop left ``kernel`` (``elapsed``: steps since its reset)."""
        raise NotImplementedError

    @staticmethod
    def find(env: gym.Env[Any, Any]) -> FusedEnv | None:
        """The fused view of ``env``, or None if the loop cannot drive it."""
        layer, limit = _unwrapped(env)
        if callable(getattr(layer, "maze_arrays", None)):
            return FusedMaze(layer, limit)
        if (
            hasattr(layer, "task")
            and getattr(layer, "observation_kind", None) == "discrete"
            and getattr(layer, "dynamics", "kinematic") == "kinematic"  # compiled: ICR model only
        ):
            return FusedNavigation(layer, limit)
        return None


class FusedNavigation(FusedEnv):
    """``SkidSteerNavEnv`` with discrete observations."""

    def kernel_state(self) -> env_steps.NavigationState:
        substeps = self.env.task.robot.substeps
        return env_steps.NavigationState(
            self.env.task, self.env.pose, np.array([float(self.env.time)]),
            np.empty(2 * substeps), np.empty((substeps, 6)),
        )  # fmt: skip

    def write_back(self, kernel: Any, state: int, elapsed: int) -> None:
        self.env.time = float(kernel.clock[0])


class FusedMaze(FusedEnv):
    """A grid maze (known by its ``maze_arrays``)."""

    def kernel_state(self) -> env_steps.MazeState:
        total = np.array([self.env.progress()[2]], dtype=np.int64)
        return env_steps.MazeState(self.env.maze_arrays(), total, NO_POSE, NO_LOG_ROWS)

    def write_back(self, kernel: Any, state: int, elapsed: int) -> None:
        self.env.restore_progress(state, elapsed, int(kernel.total_steps[0]))


def _learn(
    agent: TabularAgent, fused: FusedEnv, state: int, steps: tuple[int, int], rewards: np.ndarray
) -> tuple[float, int, np.ndarray]:
    """Learn from ``state`` (the env just reset) until the episode ends (goal, env limit or
    ``max_steps``) or ``budget`` steps are taken (``steps`` = (max_steps, budget)), in compiled
    stretches; leave the env where it stopped. ``rewards`` (float64, empty or (budget,))
    receives each step's reward. Returns (return, last state, tally)."""
    max_steps, budget = steps
    tally = np.zeros(fused_loop.N_TALLY, dtype=np.int64)
    kernel, env_rng = fused.kernel_state(), fused.env.np_random
    own = type(agent.learning_arrays()).__module__.startswith("skidnav.")
    stretch = fused_loop.learn_stretch if own else fused_loop.learn_stretch_uncached
    total = 0.0
    while tally[LENGTH] < budget and not tally[ENDED]:
        chunk = int(min(STRETCH, budget - tally[LENGTH], fused.limit - tally[ELAPSED]))
        agent.reserve(chunk)
        limits = Limits(fused.limit, max_steps, int(tally[LENGTH]) + chunk)
        total, state = stretch(
            kernel, state, agent.learning_arrays(), agent.learning_settings(),
            float(agent.epsilon), agent.counters, tally, limits, (total, rewards),
            (env_rng, agent.rng),
        )  # fmt: skip
    fused.write_back(kernel, state, int(tally[ELAPSED]))
    return float(total), int(state), tally


def _episodes(agent: TabularAgent, fused: FusedEnv, max_steps: int | None) -> EpisodeFunction:
    """The compiled :data:`~skidnav.agents.training.EpisodeFunction`: reset the env, run one
    episode in compiled stretches, finish it in Python."""

    def episode(seed: int | None) -> Episode:
        planned_before = agent.planning_updates
        steps = (max_steps or _BIG, max_steps or _BIG)
        total, _, tally = _learn(agent, fused, fused.reset(seed), steps, _NO_REWARDS)
        agent.end_episode()  # may plan (dyna-sweep): counted with the episode, as in the plain loop
        return Episode(
            total, int(tally[LENGTH]), bool(tally[fused_loop.TERMINATED]),
            int(tally[fused_loop.COLLISIONS]), agent.planning_updates - planned_before,
        )  # fmt: skip

    return episode


def _evaluations(
    agent: TabularAgent, fused: FusedEnv | None, seeds: Sequence[int] | None
) -> EvaluationFunction:
    """The compiled :data:`~skidnav.agents.training.EvaluationFunction`: a :func:`_greedy`
    rollout on ``fused`` (the evaluation env) per seed, else one continuing its generator."""

    def evaluate(limit: int) -> list[Rollout]:
        assert fused is not None  # the loop evaluates only with an env
        each: Sequence[int | None] = [None] if seeds is None else list(seeds)
        return [_greedy(agent.q, fused, limit, seed) for seed in each]

    return evaluate


def _greedy(q: np.ndarray, fused: FusedEnv, max_steps: int, seed: int | None) -> Rollout:
    """One compiled greedy rollout from ``reset(seed=seed)``: its length and cost, or −1 and
    NaN (:class:`~skidnav.agents.greedy.Rollout`)."""
    state = fused.reset(seed)
    kernel = fused.kernel_state()
    length, cost, state, taken = fused_loop.greedy_stretch(
        kernel, state, q, max_steps, fused.limit, fused.env.np_random
    )
    fused.write_back(kernel, state, taken)
    return Rollout(int(length), float(cost))


_NO_REWARDS = np.zeros(0)


def _fused_envs(
    agent: Any, env: gym.Env[Any, Any], evaluation_env: gym.Env[Any, Any] | None
) -> tuple[FusedEnv, FusedEnv | None] | None:
    """The fused views of the training and evaluation envs, or None if the plain loop must run
    (an agent that is not a TabularAgent, an env the loop cannot drive, a Q table of another
    size)."""
    fused = FusedEnv.find(env)
    if not isinstance(agent, TabularAgent) or fused is None:
        return None
    if agent.n_states != fused.env.observation_space.n:
        return None
    if evaluation_env is None:
        return fused, None
    evaluation = FusedEnv.find(evaluation_env)
    return None if evaluation is None else (fused, evaluation)


def train_agent_fast(
    agent: TabularAgent,
    env: gym.Env[Any, Any],
    episodes: int,
    /,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """As :func:`skidnav.agents.training.train_agent`: the one loop
    (:func:`~skidnav.agents.training.train_episodes`) with compiled episodes and evaluations
    (see module doc)."""
    fused = _fused_envs(agent, env, evaluation.env)
    if fused is None:
        logger.info("train_agent_fast: falling back to train_agent for %s", agent.name)
        return train_agent(
            agent, env, episodes, max_steps=max_steps, evaluation=evaluation, seed=seed
        )
    training, greedy = fused
    return train_episodes(
        _episodes(agent, training, max_steps), _evaluations(agent, greedy, evaluation.seeds),
        episodes, max_steps=max_steps, evaluation=evaluation, seed=seed,
    )  # fmt: skip


def evaluate_q_fast(
    q: np.ndarray, env: gym.Env[Any, Any], seeds: Sequence[int], max_steps: int
) -> tuple[np.ndarray, np.ndarray]:
    """Greedy rollouts of the Q table ``q`` (n_states, n_actions) on the navigation env, one per
    seed (each from ``reset(seed=seed)``, at most ``max_steps`` actions), compiled: the
    evaluation every agent gets after each episode. Returns (lengths int64 (len(seeds),), −1
    where the goal was not reached; costs float64 (len(seeds),), NaN there)."""
    fused = FusedEnv.find(env)
    if not isinstance(fused, FusedNavigation):
        raise ValueError(
            "expected the skid-steer navigation env with discrete observations and "
            "dynamics='kinematic'"
        )
    q = np.ascontiguousarray(q, dtype=np.float64)
    rollouts = [_greedy(q, fused, max_steps, int(s)) for s in seeds]
    lengths = np.array([rollout.length for rollout in rollouts], np.int64)
    return lengths, np.array([rollout.cost for rollout in rollouts], np.float64)


def train_for_steps_fast(
    agent: TabularAgent, env: gym.Env[Any, Any], n_steps: int, *, seed: int | None = None
) -> np.ndarray:
    """As :func:`skidnav.agents.training.train_for_steps` (cumulative reward after each step,
    float64 (n_steps,)), compiled; envs or agents the loop cannot drive use the plain loop."""
    fused = _fused_envs(agent, env, None)
    if fused is None:
        logger.info("train_for_steps_fast: falling back to train_for_steps for %s", agent.name)
        return train_for_steps(agent, env, n_steps, seed=seed)
    training = fused[0]
    rewards = np.zeros(n_steps, dtype=np.float64)
    state = training.reset(seed)
    done = 0
    while done < n_steps:
        _, state, tally = _learn(agent, training, state, (_BIG, n_steps - done), rewards[done:])
        done += int(tally[LENGTH])
        if tally[ENDED]:
            agent.end_episode()
            state = training.reset(None)
    # The rewards are summed in step order, as the plain loop does.
    return np.cumsum(rewards)
