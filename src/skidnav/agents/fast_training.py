"""The fused compiled trainer: :func:`train_agent_fast`, a drop-in for
:func:`skidnav.agents.training.train_agent` on ``skidnav/SkidSteerNav-v0``.

Whole episodes run in one numba call (:mod:`skidnav.kernels.trainer`): simulation, ε-greedy,
TD update, model update and planning. Between episodes Python does what the agent does in
``end_episode`` (ε decay, trajectory bookkeeping, kinematic refits with scikit-learn) and the
greedy evaluation rollout (also compiled). Same signature, same :class:`TrainingLog`, and the same
numbers as ``train_agent`` for the same seed (tested), except ``wall_time``. Agents or envs it does
not know fall back to ``train_agent``. The env's ``trail`` (for rendering) is not recorded.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import gymnasium as gym
import numpy as np

from skidnav.agents.core import TabularAgent
from skidnav.agents.dyna_kinematic import ModelBasedAgent
from skidnav.agents.training import TrainingLog, train_agent
from skidnav.kernels import kinematic_planning as kp
from skidnav.kernels import trainer
from skidnav.kernels.priority_queue import make_heap

logger = logging.getLogger(__name__)

_BIG = np.iinfo(np.int64).max // 4


def _navigation_env(env: gym.Env[Any, Any]) -> tuple[Any, int] | None:
    """The unwrapped navigation env and the smallest step limit along the wrappers (None if the
    env is not ``SkidSteerNavEnv`` with discrete observations)."""
    limit = _BIG
    layer: Any = env
    while isinstance(layer, gym.Wrapper):
        if isinstance(layer, gym.wrappers.TimeLimit):
            limit = min(limit, int(layer._max_episode_steps))
        layer = layer.env
    if not hasattr(layer, "task") or getattr(layer, "observation_kind", None) != "discrete":
        return None
    return layer, min(limit, int(layer.max_episode_steps))


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


def _fast_episode(
    agent: TabularAgent, nav: Any, env_limit: int, max_steps: int, seed: int | None
) -> tuple[float, int, bool, int, int]:
    """Reset ``nav``, run one fused episode, finish it in Python; returns (return, length,
    terminated, collisions, planning updates)."""
    state, _ = nav.reset(seed=seed)
    arrays = _learner_arrays(agent, min(max_steps, env_limit))
    tally = np.zeros(trainer.N_TALLY, dtype=np.int64)
    tally[trainer.STEPS] = agent.steps
    n_visited = agent.visited_states.size if hasattr(agent, "visited_states") else 0
    tally[trainer.N_VISITED] = n_visited
    settings = _settings(agent, max_steps, env_limit)
    total, nav.time = trainer.run_episode(
        nav.task, nav.pose, int(state), float(nav.time), arrays, settings, tally,
        nav.np_random, agent.rng,
    )  # fmt: skip
    nav.elapsed_steps = int(tally[trainer.ELAPSED])
    agent.steps = int(tally[trainer.STEPS])
    agent.planning_updates += int(tally[trainer.PLANNING_UPDATES])
    if hasattr(agent, "visited_states"):
        agent.visited_states = arrays.visited[: tally[trainer.N_VISITED]].copy()
    agent.end_episode()
    return (
        float(total), int(tally[trainer.LENGTH]), bool(tally[trainer.TERMINATED]),
        int(tally[trainer.COLLISIONS]), int(tally[trainer.PLANNING_UPDATES]),
    )  # fmt: skip


def _greedy(agent: TabularAgent, eval_nav: Any, limit: int, env_limit: int) -> int:
    state, _ = eval_nav.reset()
    length, eval_nav.time = trainer.greedy_episode(
        eval_nav.task, eval_nav.pose, int(state), float(eval_nav.time), agent.q, limit,
        env_limit, eval_nav.np_random,
    )  # fmt: skip
    return int(length)


def train_agent_fast(
    agent: TabularAgent,
    env: gym.Env[Any, Any],
    n_episodes: int,
    *,
    max_steps: int | None = None,
    greedy_eval_env: gym.Env[Any, Any] | None = None,
    greedy_max_steps: int | None = None,
    seed: int | None = None,
) -> TrainingLog:
    """As :func:`skidnav.agents.training.train_agent`, with compiled episodes (see module doc)."""
    found = _navigation_env(env)
    eval_found = None if greedy_eval_env is None else _navigation_env(greedy_eval_env)
    if (
        found is None
        or not _supported(agent, found[0])
        or (greedy_eval_env is not None and eval_found is None)
    ):
        logger.info("train_agent_fast: falling back to train_agent for %s", agent.name)
        return train_agent(
            agent, env, n_episodes, max_steps=max_steps, greedy_eval_env=greedy_eval_env,
            greedy_max_steps=greedy_max_steps, seed=seed,
        )  # fmt: skip
    if n_episodes < 0 or (max_steps is not None and max_steps < 1):
        raise ValueError(
            f"expected n_episodes >= 0 and max_steps >= 1, got {n_episodes}, {max_steps}"
        )
    nav, env_limit = found
    limit = greedy_max_steps or max_steps or 10_000
    rows = []
    for episode in range(n_episodes):
        start = time.perf_counter()
        result = _fast_episode(
            agent, nav, env_limit, max_steps or _BIG, seed if episode == 0 else None
        )
        elapsed = time.perf_counter() - start
        greedy = -1
        if eval_found is not None:
            if episode == 0 and seed is not None:
                eval_found[0].reset(seed=seed + 1)
            greedy = _greedy(agent, eval_found[0], limit, eval_found[1])
        rows.append((result[0], result[1], result[2], result[3], result[4], elapsed, greedy))
    columns = list(zip(*rows, strict=True)) if rows else [()] * 7
    dtypes = (np.float64, np.int64, np.bool_, np.int64, np.int64, np.float64, np.int64)
    return TrainingLog(*(np.array(c, dtype=d) for c, d in zip(columns, dtypes, strict=True)))
