"""The fused compiled episode: simulator, behaviour, TD update, model update and planning in one
numba loop (used by :func:`skidnav.agents.fast_training.train_agent_fast`).

Every step calls the same kernels, in the same order, with the same random streams as the plain
Python loop (:func:`skidnav.agents.training.run_episode` driving
``SkidSteerNavEnv.step`` and the agent's ``observe``), so both give identical numbers:

1. ``epsilon_greedy(q, s, ε, agent_rng)`` (:mod:`skidnav.kernels.tabular`);
2. ``draw_noise(env_rng, noise)`` then ``transition(task, pose, a, time, noise, log)``
   (:mod:`skidnav.kernels.navigation`); the clock advances by one action;
3. the agent's learning step, by ``kind`` (:data:`AGENT_KINDS`) — the body of its ``_learn``;
4. truncation after the env's limit or the trainer's ``max_steps``.

What the Python agents do between episodes (``end_episode``: ε decay, trajectory bookkeeping,
kinematic refits with scikit-learn) stays in Python.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.kernels import kinematic_planning as kp
from skidnav.kernels.multinomial import MultinomialArrays, model_observe
from skidnav.kernels.navigation import NavigationTask, draw_noise, transition
from skidnav.kernels.planning import dyna_planning, dyna_plus_planning, sweep_step
from skidnav.kernels.priority_queue import HeapArrays
from skidnav.kernels.tabular import epsilon_greedy, greedy_first, td_update

Q_LEARNING, DYNA_Q, DYNA_Q_PLUS, PRIORITIZED_SWEEPING, MODEL_BASED = range(5)
AGENT_KINDS = {
    "q-learning": Q_LEARNING,
    "dyna-q": DYNA_Q,
    "dyna-q-plus": DYNA_Q_PLUS,
    "prioritized-sweeping": PRIORITIZED_SWEEPING,
    "dyna-kinematic": MODEL_BASED,
    "trajectory-prioritized": MODEL_BASED,
    "dyna-full": MODEL_BASED,
    "dyna-sweep": MODEL_BASED,
}
"""Agent registry name → the learning step the fused loop runs."""

# columns of the int64 ``tally`` array
STEPS, PLANNING_UPDATES, N_VISITED, LENGTH, COLLISIONS, TERMINATED, ELAPSED = range(7)
N_TALLY = 7


class LearnerSettings(NamedTuple):
    """Scalars of one episode (numba-friendly)."""

    kind: int
    epsilon: float
    alpha: float
    gamma: float
    planning_steps: int
    mode: int
    kappa: float
    theta: float
    max_steps: int
    env_limit: int


class LearnerArrays(NamedTuple):
    """Every array an agent learns into (unused ones are small placeholders).

    ``visited`` int64 (n_states,) and ``is_visited`` bool (n_states,) are Dyna-Q+'s visited
    states; ``kinematic_data``/``kinematic_counts`` the kinematic model's sample buffers.
    """

    q: np.ndarray
    model: MultinomialArrays
    heap: HeapArrays
    last_tried: np.ndarray
    visited: np.ndarray
    is_visited: np.ndarray
    planner: kp.PlannerArrays
    shares: kp.PlanningShares
    kinematic_data: np.ndarray
    kinematic_counts: np.ndarray


@jit
def classic_learn(
    agent: LearnerArrays,
    settings: LearnerSettings,
    tally: np.ndarray,
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
    rng: np.random.Generator,
) -> None:
    """The ``_learn`` of Q-learning, Dyna-Q, Dyna-Q+ and prioritized sweeping."""
    s = settings
    if s.kind == PRIORITIZED_SWEEPING:
        tally[PLANNING_UPDATES] += sweep_step(
            agent.q, agent.model, agent.heap, state, action, reward, next_state, terminated,
            s.planning_steps, s.theta, s.alpha, s.gamma, s.mode, rng,
        )  # fmt: skip
        return
    if s.kind == DYNA_Q_PLUS:
        agent.last_tried[state, action] = tally[STEPS]
        if not agent.is_visited[state]:
            agent.is_visited[state] = True
            agent.visited[tally[N_VISITED]] = state
            tally[N_VISITED] += 1
    td_update(agent.q, state, action, reward, next_state, terminated, s.alpha, s.gamma)
    if s.kind == Q_LEARNING:
        return
    model_observe(agent.model, state, action, reward, next_state, terminated)
    if s.planning_steps == 0:
        return
    if s.kind == DYNA_Q:
        tally[PLANNING_UPDATES] += dyna_planning(
            agent.q, agent.model, s.planning_steps, s.alpha, s.gamma, s.mode, rng
        )
    else:
        tally[PLANNING_UPDATES] += dyna_plus_planning(
            agent.q, agent.model, agent.visited, tally[N_VISITED], agent.last_tried,
            tally[STEPS], s.kappa, s.planning_steps, s.alpha, s.gamma, s.mode, rng,
        )  # fmt: skip


@jit
def _model_based_learn(
    agent: LearnerArrays,
    settings: LearnerSettings,
    tally: np.ndarray,
    task: NavigationTask,
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
    collided: bool,
    pose: np.ndarray,
    log: np.ndarray,
    n_logged: int,
    rng: np.random.Generator,
) -> None:
    """The ``_learn`` of :class:`skidnav.agents.dyna_kinematic.ModelBasedAgent`."""
    s = settings
    td_update(agent.q, state, action, reward, next_state, terminated, s.alpha, s.gamma)
    model_observe(agent.model, state, action, reward, next_state, terminated)
    kp.planner_observe(
        agent.planner, state, action, reward, next_state, terminated, collided, pose,
        task.robot, task.grid,
    )  # fmt: skip
    if agent.planner.counters[kp.USE_KINEMATIC] != 0:
        n_regions = agent.kinematic_counts.shape[0]
        kp.feed_log(agent.kinematic_data, agent.kinematic_counts, log, n_logged, n_regions)
    if s.planning_steps > 0:
        tally[PLANNING_UPDATES] += kp.combined_planning(
            agent.q, agent.model, agent.planner, agent.shares, task.grid, rng
        )


@jit
def run_episode(
    task: NavigationTask,
    pose: np.ndarray,
    state: int,
    time: float,
    agent: LearnerArrays,
    settings: LearnerSettings,
    tally: np.ndarray,
    env_rng: np.random.Generator,
    agent_rng: np.random.Generator,
) -> tuple[float, float]:
    """One learning episode from ``state`` (pose already reset, ``tally[ELAPSED]`` the env's step
    counter). Updates ``pose``, ``tally`` and the agent's arrays in place; returns (return, time
    at the end [s])."""
    noise = np.empty(2 * task.robot.substeps)
    log = np.empty((task.robot.substeps, 6))
    duration = task.robot.dt * task.robot.substeps
    total = 0.0
    while True:
        action = epsilon_greedy(agent.q, state, settings.epsilon, agent_rng)
        draw_noise(env_rng, noise)
        outcome = transition(task, pose, action, time, noise, log)
        time += duration
        tally[ELAPSED] += 1
        tally[LENGTH] += 1
        tally[STEPS] += 1
        tally[COLLISIONS] += 1 if outcome.collided else 0
        total += outcome.reward
        terminated = outcome.terminated
        if settings.kind == MODEL_BASED:
            _model_based_learn(
                agent, settings, tally, task, state, action, outcome.reward, outcome.state,
                terminated, outcome.collided, pose, log, outcome.n_logged, agent_rng,
            )  # fmt: skip
        else:
            classic_learn(
                agent, settings, tally, state, action, outcome.reward, outcome.state,
                terminated, agent_rng,
            )  # fmt: skip
        state = outcome.state
        truncated = tally[ELAPSED] >= settings.env_limit or tally[LENGTH] >= settings.max_steps
        if terminated or truncated:
            tally[TERMINATED] = 1 if terminated else 0
            return total, time


@jit
def greedy_episode(
    task: NavigationTask,
    pose: np.ndarray,
    state: int,
    time: float,
    q: np.ndarray,
    max_steps: int,
    env_limit: int,
    env_rng: np.random.Generator,
) -> tuple[int, float]:
    """Greedy rollout (``greedy_first``, no learning) from a reset pose: returns (actions taken if
    the goal was reached else −1, the clock at the end [s])."""
    noise = np.empty(2 * task.robot.substeps)
    log = np.empty((task.robot.substeps, 6))
    duration = task.robot.dt * task.robot.substeps
    for step in range(1, max_steps + 1):
        draw_noise(env_rng, noise)
        outcome = transition(task, pose, greedy_first(q, state), time, noise, log)
        time += duration
        state = outcome.state
        if outcome.terminated:
            return step, time
        if step >= env_limit:
            return -1, time
    return -1, time
