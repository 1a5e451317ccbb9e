"""The env steps the fused loop (:mod:`skidnav.agents.tabular.fused_loop`) drives: compiled twins of
``env.step`` that draw the same numbers and change the same state.

An env step is
``step(env, state, action, rng) -> (next state, reward, terminated, collided, rows logged, cost)``
(the cost the env reports in ``info["cost"]``) on a NamedTuple ``env`` holding the env's mutable
state in arrays, with a ``pose`` (float64 (3,)) and a ``log`` (float64 (n, 6)) the agents'
experience carries (:class:`skidnav.agents.learning.Experience`). It is registered for the
NamedTuple's class in :data:`ENV_STEPS` and called through :func:`env_step`.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from skidnav._jit import dispatch_on_type, jit
from skidnav.agents.learning import NO_LOG
from skidnav.sim.maze import MOVE_COST, MazeArrays, maze_move
from skidnav.sim.navigation import NavigationTask, draw_noise, transition

ENV_STEPS: dict[type, Any] = {}
"""NamedTuple class of an env's state → its compiled step."""


@dispatch_on_type(ENV_STEPS)
def env_step(
    env: Any, state: int, action: int, rng: np.random.Generator
) -> tuple[int, float, bool, bool, int, float]:
    """One step of the env whose state ``env`` is: the step registered for ``type(env)``."""
    return ENV_STEPS[type(env)](env, state, action, rng)


class NavigationState(NamedTuple):
    """The navigation env (``SkidSteerNavEnv``) as the compiled loop moves it: its task, its pose
    float64 (3,) [m, m, rad], its clock float64 (1,) [s], and scratch arrays for the slip noise
    float64 (2 · substeps,) and the kinematic log float64 (substeps, 6)."""

    task: NavigationTask
    pose: np.ndarray
    clock: np.ndarray
    noise: np.ndarray
    log: np.ndarray


@jit
def navigation_step(
    env: NavigationState, state: int, action: int, rng: np.random.Generator
) -> tuple[int, float, bool, bool, int, float]:
    """``SkidSteerNavEnv.step``: noise from ``rng``, one action of the simulator, the clock
    advanced by the action's duration."""
    draw_noise(rng, env.noise)
    outcome = transition(env.task, env.pose, action, env.clock[0], env.noise, env.log)
    env.clock[0] += env.task.robot.dt * env.task.robot.substeps
    return (
        outcome.state, outcome.reward, outcome.terminated, outcome.collided, outcome.n_logged,
        outcome.cost,
    )  # fmt: skip


class MazeState(NamedTuple):
    """A grid maze (``GridMazeEnv``) as the compiled loop moves it: its walls and goal, the steps
    it has taken since construction int64 (1,) (the walls change after ``change_after``), and
    the pose and log of an env that measures neither (−1 (3,) and (0, 6))."""

    maze: MazeArrays
    total_steps: np.ndarray
    pose: np.ndarray
    log: np.ndarray


@jit
def maze_step(
    env: MazeState, state: int, action: int, rng: np.random.Generator
) -> tuple[int, float, bool, bool, int, float]:
    """``GridMazeEnv.step``: the move, reward 1 and termination at the goal, cost
    :data:`~skidnav.sim.maze.MOVE_COST` (draws nothing)."""
    next_state = maze_move(env.maze, state, action, env.total_steps[0])
    env.total_steps[0] += 1
    terminated = next_state == env.maze.goal
    return next_state, 1.0 if terminated else 0.0, terminated, False, NO_LOG, MOVE_COST


ENV_STEPS[NavigationState] = navigation_step
ENV_STEPS[MazeState] = maze_step
