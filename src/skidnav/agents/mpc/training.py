"""Training ``mppi-kinematic`` on the navigation env with wheel-speed actions, one real step at a
time: :func:`train_mppi` is the project's loop (:func:`skidnav.agents.training.train_loop`, the
episodes and greedy evaluations of :func:`~skidnav.agents.training.train_agent`) on an env of
two wheel speeds, and returns the same :class:`~skidnav.agents.training.TrainingLog`.

The env must be the navigation env with ``action="continuous"``, and its observation the pose
(``observation="pose"``) or the features (whose first four entries hold the pose). The greedy
evaluations roll out the agent's frozen planner
(:meth:`~skidnav.agents.mpc.agent.MPPIKinematicAgent.greedy_action`), which draws none of the
agent's numbers, so no evaluation changes training.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym

from skidnav.agents.family import check_wheel_speed_env
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.training import TrainingLog, train_loop


def train_mppi(
    agent: MPPIKinematicAgent,
    env: gym.Env[Any, Any],
    episodes: int,
    max_steps: int | None = None,
    *,
    greedy_eval_env: gym.Env[Any, Any] | None = None,
    greedy_max_steps: int | None = None,
    greedy_seeds: Sequence[int] | None = None,
    seed: int | None = None,
) -> TrainingLog:
    """Train ``agent`` for ``episodes`` episodes on ``env``, with the semantics of
    :func:`~skidnav.agents.training.train_agent`: ``seed`` seeds the first reset, ``max_steps``
    truncates an episode, and after each episode the frozen planner is rolled out on
    ``greedy_eval_env`` once per seed of ``greedy_seeds`` (else once, continuing that env's
    generator, first reset with ``seed + 1``), each stopped after ``greedy_max_steps`` actions
    (default ``max_steps``, else 10,000). ``planning_updates`` of the log counts the sequences
    rolled out through the model while learning (K per action). ValueError for an env of other
    spaces."""
    check_wheel_speed_env(env)
    return train_loop(
        agent, env, episodes, max_steps=max_steps, greedy_eval_env=greedy_eval_env,
        greedy_max_steps=greedy_max_steps, greedy_seeds=greedy_seeds, seed=seed,
    )  # fmt: skip
