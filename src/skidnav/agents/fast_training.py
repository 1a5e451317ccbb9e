"""The fused compiled trainers: :func:`train_agent_fast`, a drop-in for
:func:`skidnav.agents.training.train_agent` on ``skidnav/SkidSteerNav-v0`` and on the grid mazes
(:class:`skidnav.envs.mazes.GridMazeEnv`), and :func:`train_for_steps_fast`, a drop-in for
:func:`skidnav.agents.training.train_for_steps` on the mazes.

Whole episodes run in one numba call (:mod:`skidnav.kernels.trainer`,
:mod:`skidnav.kernels.maze_trainer`): simulation, ε-greedy, TD update, model update and planning.
Between episodes Python does what the agent does in ``end_episode`` (ε decay, trajectory
bookkeeping, kinematic refits with scikit-learn) and the greedy evaluation rollout (also
compiled). Same signature, same output, and the same numbers as the plain loop for the same seed
(tested), except ``wall_time``. Agents or envs it does not know fall back to the plain loop. The
navigation env's ``trail`` (for rendering) is not recorded.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from skidnav.agents.core import TabularAgent
from skidnav.agents.dyna_kinematic import ModelBasedAgent
from skidnav.agents.training import TrainingLog, log_from_rows, train_agent, train_for_steps
from skidnav.kernels import kinematic_planning as kp
from skidnav.kernels import maze_trainer, trainer
from skidnav.kernels.priority_queue import make_heap

logger = logging.getLogger(__name__)

_BIG = np.iinfo(np.int64).max // 4


def _unwrapped(env: gym.Env[Any, Any]) -> tuple[Any, int]:
    """The innermost env and the smallest ``TimeLimit`` along the wrappers (``_BIG`` if none)."""
    limit = _BIG
    layer: Any = env
    while isinstance(layer, gym.Wrapper):
        if isinstance(layer, gym.wrappers.TimeLimit):
            limit = min(limit, int(layer._max_episode_steps))
        layer = layer.env
    return layer, limit


def _navigation_env(env: gym.Env[Any, Any]) -> tuple[Any, int] | None:
    """The unwrapped navigation env and the smallest step limit along the wrappers (None if the
    env is not ``SkidSteerNavEnv`` with discrete observations)."""
    layer, limit = _unwrapped(env)
    if not hasattr(layer, "task") or getattr(layer, "observation_kind", None) != "discrete":
        return None
    return layer, min(limit, int(layer.max_episode_steps))


def _maze_env(env: gym.Env[Any, Any]) -> tuple[Any, int] | None:
    """The unwrapped grid maze (``skidnav.envs.mazes.GridMazeEnv``, known by its
    ``maze_arrays``) and the smallest step limit along the wrappers; None for other envs."""
    layer, limit = _unwrapped(env)
    if not callable(getattr(layer, "maze_arrays", None)):
        return None
    return layer, min(limit, layer.max_episode_steps or _BIG)


def _learner_arrays(agent: TabularAgent, reserve: int) -> trainer.LearnerArrays:
    """The agent's arrays for the fused loop, after reserving room for ``reserve`` steps."""
    planner = None
    data, counts = np.zeros((1, 1, 5)), np.zeros(1, dtype=np.int64)
    if isinstance(agent, ModelBasedAgent):
        agent.reserve_episode(reserve)
        planner = agent.planner
        shares = agent.shares
        if agent.kinematic is not None:
            data, counts = agent.kinematic.data, agent.kinematic.counts
            # The navigation env logs every step: as ``observe`` does at the first one.
            planner.counters[kp.USE_KINEMATIC] = 1
    model = getattr(agent, "model", None)
    if model is not None:
        model.reserve(reserve)
    placeholder = _placeholder()
    n_states = agent.n_states
    visited = np.zeros(n_states if hasattr(agent, "visited_states") else 1, dtype=np.int64)
    is_visited = getattr(agent, "_is_visited", np.zeros(1, dtype=np.bool_))
    if hasattr(agent, "visited_states"):
        visited[: agent.visited_states.size] = agent.visited_states
    return trainer.LearnerArrays(
        q=agent.q,
        model=(model or placeholder.model).arrays,
        heap=getattr(agent, "queue", None) or make_heap(1),
        last_tried=getattr(agent, "last_tried", np.zeros((1, 1), dtype=np.int64)),
        visited=visited,
        is_visited=is_visited,
        planner=planner or placeholder.planner,
        shares=shares if planner is not None else placeholder.shares,
        kinematic_data=data,
        kinematic_counts=counts,
    )


_PLACEHOLDER: list[ModelBasedAgent] = []


def _placeholder() -> ModelBasedAgent:
    """A tiny agent whose arrays fill the unused slots of :class:`trainer.LearnerArrays`."""
    if not _PLACEHOLDER:
        _PLACEHOLDER.append(ModelBasedAgent(1, 4))
    return _PLACEHOLDER[0]


def _supported(agent: TabularAgent, nav: Any) -> bool:
    """True if the fused loop reproduces this agent on this env exactly."""
    if agent.name not in trainer.AGENT_KINDS or agent.n_states != nav.observation_space.n:
        return False
    if isinstance(agent, ModelBasedAgent):  # it must see the env's own geometry
        return bool(agent.kernel_grid == nav.task.grid and agent.kernel_robot == nav.task.robot)
    return True


def _settings(agent: TabularAgent, max_steps: int, env_limit: int) -> trainer.LearnerSettings:
    config = agent.config
    return trainer.LearnerSettings(
        kind=trainer.AGENT_KINDS[agent.name], epsilon=float(agent.epsilon),
        alpha=float(config.alpha), gamma=float(config.gamma),
        planning_steps=int(getattr(config, "planning_steps", 0)),
        mode=int(getattr(config, "planning_mode_code", 0)),
        kappa=float(getattr(config, "kappa", 0.0)), theta=float(getattr(config, "theta", 0.0)),
        max_steps=max_steps, env_limit=env_limit,
    )  # fmt: skip


def _start_tally(agent: TabularAgent, size: int = trainer.N_TALLY) -> np.ndarray:
    """The int64 counters of a compiled call, (size,), with the agent's steps and visits."""
    tally = np.zeros(size, dtype=np.int64)
    tally[trainer.STEPS] = agent.steps
    tally[trainer.N_VISITED] = agent.visited_states.size if hasattr(agent, "visited_states") else 0
    return tally


def _absorb(agent: TabularAgent, arrays: trainer.LearnerArrays, tally: np.ndarray) -> None:
    """Copy the counters of a compiled call back into the agent."""
    agent.steps = int(tally[trainer.STEPS])
    agent.planning_updates += int(tally[trainer.PLANNING_UPDATES])
    if hasattr(agent, "visited_states"):
        agent.visited_states = arrays.visited[: tally[trainer.N_VISITED]].copy()


def _fast_episode(
    agent: TabularAgent, nav: Any, env_limit: int, max_steps: int, seed: int | None
) -> tuple[float, int, bool, int, int]:
    """Reset ``nav``, run one fused episode, finish it in Python; returns (return, length,
    terminated, collisions, planning updates)."""
    state, _ = nav.reset(seed=seed)
    planned_before = agent.planning_updates
    arrays = _learner_arrays(agent, min(max_steps, env_limit))
    tally = _start_tally(agent)
    settings = _settings(agent, max_steps, env_limit)
    total, nav.time = trainer.run_episode(
        nav.task, nav.pose, int(state), float(nav.time), arrays, settings, tally,
        nav.np_random, agent.rng,
    )  # fmt: skip
    nav.elapsed_steps = int(tally[trainer.ELAPSED])
    _absorb(agent, arrays, tally)
    agent.end_episode()  # may plan too (dyna-sweep): counted with the episode, as the plain loop
    return (
        float(total), int(tally[trainer.LENGTH]), bool(tally[trainer.TERMINATED]),
        int(tally[trainer.COLLISIONS]), agent.planning_updates - planned_before,
    )  # fmt: skip


def _greedy(q: np.ndarray, eval_nav: Any, limit: int, env_limit: int, seed: int | None) -> int:
    state, _ = eval_nav.reset(seed=seed)
    length, eval_nav.time = trainer.greedy_episode(
        eval_nav.task, eval_nav.pose, int(state), float(eval_nav.time), q, limit, env_limit,
        eval_nav.np_random,
    )  # fmt: skip
    return int(length)


_NO_REWARDS = np.zeros(0)


def _maze_stretch(
    agent: TabularAgent, maze: Any, state: int, limits: tuple[int, int, int], rewards: np.ndarray
) -> tuple[float, int, np.ndarray]:
    """Run the fused maze loop from ``state`` (``limits`` = env limit, ``max_steps``, step
    budget), leave the env where it stopped; returns (return, last state, tally)."""
    env_limit, max_steps, budget = limits
    # A maze pair has at most two outcomes (walls before and after the change): this bounds the
    # model's growth however long the stretch is.
    arrays = _learner_arrays(agent, min(budget, max_steps, 2 * agent.q.size))
    tally = _start_tally(agent, maze_trainer.N_MAZE_TALLY)
    _, tally[trainer.ELAPSED], tally[maze_trainer.TOTAL_STEPS] = maze.progress()
    total, state = maze_trainer.maze_episode(
        maze.maze_arrays(), int(state), arrays, _settings(agent, max_steps, env_limit), tally,
        rewards, budget, agent.rng,
    )  # fmt: skip
    maze.restore_progress(state, tally[trainer.ELAPSED], tally[maze_trainer.TOTAL_STEPS])
    _absorb(agent, arrays, tally)
    return float(total), int(state), tally


def _fast_maze_episode(
    agent: TabularAgent, maze: Any, env_limit: int, max_steps: int, seed: int | None
) -> tuple[float, int, bool, int, int]:
    """As :func:`_fast_episode`, on a grid maze (no collisions)."""
    state, _ = maze.reset(seed=seed)
    total, _, tally = _maze_stretch(agent, maze, state, (env_limit, max_steps, _BIG), _NO_REWARDS)
    agent.end_episode()
    length, terminated = int(tally[trainer.LENGTH]), bool(tally[trainer.TERMINATED])
    return total, length, terminated, 0, int(tally[trainer.PLANNING_UPDATES])


def _maze_greedy(
    q: np.ndarray, eval_maze: Any, limit: int, env_limit: int, seed: int | None
) -> int:
    state, _ = eval_maze.reset(seed=seed)
    total_steps = eval_maze.progress()[2]
    length, state, taken = maze_trainer.maze_greedy(
        eval_maze.maze_arrays(), int(state), q, limit, env_limit, total_steps
    )
    eval_maze.restore_progress(state, taken, total_steps + taken)
    return int(length)


def _supported_maze(agent: TabularAgent, maze: Any) -> bool:
    """True if the fused maze loop reproduces this agent on this maze exactly."""
    kind = trainer.AGENT_KINDS.get(agent.name, trainer.MODEL_BASED)
    return kind != trainer.MODEL_BASED and agent.n_states == maze.observation_space.n


Episode = Callable[[TabularAgent, Any, int, int, int | None], tuple[float, int, bool, int, int]]
"""(agent, env, env limit, max_steps, seed) → (return, length, terminated, collisions, updates)."""
Greedy = Callable[[np.ndarray, Any, int, int, int | None], int]
"""(Q table, evaluation env, step limit, env limit, reset seed) → greedy length or −1."""


def _fused_functions(
    agent: TabularAgent, env: gym.Env[Any, Any], greedy_eval_env: gym.Env[Any, Any] | None
) -> tuple[Episode, tuple[Any, int], Greedy, tuple[Any, int] | None] | None:
    """The fused episode and greedy functions for this agent and these envs, with the unwrapped
    envs and their limits; None if the plain loop must be used."""
    found, eval_found = _maze_env(env), None
    episode: Episode
    greedy: Greedy
    if found is not None and _supported_maze(agent, found[0]):
        episode, greedy = _fast_maze_episode, _maze_greedy
        eval_found = None if greedy_eval_env is None else _maze_env(greedy_eval_env)
    else:
        found = _navigation_env(env)
        if found is None or not _supported(agent, found[0]):
            return None
        episode, greedy = _fast_episode, _greedy
        eval_found = None if greedy_eval_env is None else _navigation_env(greedy_eval_env)
    if greedy_eval_env is not None and eval_found is None:
        return None
    return episode, found, greedy, eval_found


def train_agent_fast(
    agent: TabularAgent,
    env: gym.Env[Any, Any],
    n_episodes: int,
    *,
    max_steps: int | None = None,
    greedy_eval_env: gym.Env[Any, Any] | None = None,
    greedy_max_steps: int | None = None,
    greedy_seeds: Sequence[int] | None = None,
    seed: int | None = None,
) -> TrainingLog:
    """As :func:`skidnav.agents.training.train_agent`, with compiled episodes (see module doc)."""
    fused = _fused_functions(agent, env, greedy_eval_env)
    if fused is None:
        logger.info("train_agent_fast: falling back to train_agent for %s", agent.name)
        return train_agent(
            agent, env, n_episodes, max_steps=max_steps, greedy_eval_env=greedy_eval_env,
            greedy_max_steps=greedy_max_steps, greedy_seeds=greedy_seeds, seed=seed,
        )  # fmt: skip
    if n_episodes < 0 or (max_steps is not None and max_steps < 1):
        raise ValueError(
            f"expected n_episodes >= 0 and max_steps >= 1, got {n_episodes}, {max_steps}"
        )
    episode_function, (unwrapped, env_limit), greedy_function, eval_found = fused
    limit = greedy_max_steps or max_steps or 10_000
    seeds: Sequence[int | None] = [None] if greedy_seeds is None else list(greedy_seeds)
    columns: dict[str, list[Any]] = {name: [] for name in TrainingLog._fields}
    for episode in range(n_episodes):
        start = time.perf_counter()
        result = episode_function(
            agent, unwrapped, env_limit, max_steps or _BIG, seed if episode == 0 else None
        )
        columns["wall_time"].append(time.perf_counter() - start)
        for name, value in zip(_EPISODE_FIELDS, result, strict=True):
            columns[name].append(value)
        greedy = [-1] * len(seeds)
        if eval_found is not None:
            if episode == 0 and seed is not None and greedy_seeds is None:
                eval_found[0].reset(seed=seed + 1)
            greedy = [
                greedy_function(agent.q, eval_found[0], limit, eval_found[1], s) for s in seeds
            ]
        columns["greedy_lengths"].append(greedy)
    return log_from_rows(columns, len(seeds))


_EPISODE_FIELDS = ("returns", "lengths", "successes", "collisions", "planning_updates")
"""TrainingLog fields of an episode function's result, in order."""


def evaluate_q_fast(
    q: np.ndarray, env: gym.Env[Any, Any], seeds: Sequence[int], max_steps: int
) -> np.ndarray:
    """Greedy rollouts of the Q table ``q`` (n_states, n_actions) on the navigation env, one per
    seed (each from ``reset(seed=seed)``, at most ``max_steps`` actions), compiled: the
    evaluation every agent gets after each episode. Returns the lengths, int64 (len(seeds),),
    −1 where the goal was not reached."""
    found = _navigation_env(env)
    if found is None:
        raise ValueError("expected the skid-steer navigation env with discrete observations")
    nav, env_limit = found
    q = np.ascontiguousarray(q, dtype=np.float64)
    return np.array([_greedy(q, nav, max_steps, env_limit, int(s)) for s in seeds], np.int64)


def train_for_steps_fast(
    agent: TabularAgent, env: gym.Env[Any, Any], n_steps: int, *, seed: int | None = None
) -> np.ndarray:
    """As :func:`skidnav.agents.training.train_for_steps` (cumulative reward after each step,
    float64 (n_steps,)), compiled on the grid mazes; other envs or agents use the plain loop."""
    found = _maze_env(env)
    if found is None or not _supported_maze(agent, found[0]):
        logger.info("train_for_steps_fast: falling back to train_for_steps for %s", agent.name)
        return train_for_steps(agent, env, n_steps, seed=seed)
    maze, env_limit = found
    rewards = np.zeros(n_steps, dtype=np.float64)
    state, _ = maze.reset(seed=seed)
    done = 0
    while done < n_steps:
        limits = (env_limit, _BIG, n_steps - done)
        _, state, tally = _maze_stretch(agent, maze, state, limits, rewards[done:])
        done += int(tally[trainer.LENGTH])
        if tally[maze_trainer.ENDED]:
            agent.end_episode()
            state, _ = maze.reset()
    # The rewards are summed in step order, as the plain loop does.
    return np.cumsum(rewards)
