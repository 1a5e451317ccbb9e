"""Training ``mppi-kinematic`` on the navigation env with wheel-speed actions, one real step at a
time: :func:`train_mppi` is the project's one episode loop with the plain episodes and greedy
evaluations of :func:`~skidnav.agents.training.train_agent`
(:func:`skidnav.agents.training.train_plain`) on an env of two wheel speeds, and returns the
same :class:`~skidnav.agents.training.TrainingLog`.

The env must be the navigation env with ``action="continuous"``, and its observation the pose
(``observation="pose"``) or the features (whose first four entries hold the pose). The greedy
evaluations roll out the agent's frozen planner
(:meth:`~skidnav.agents.mpc.agent.MPPIKinematicAgent.greedy_action`), which draws none of the
agent's numbers, so no evaluation changes training.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from skidnav.agents.family import check_wheel_speed_env
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.training import NO_EVALUATION, Evaluation, TrainingLog, train_plain


def train_mppi(
    agent: MPPIKinematicAgent,
    env: gym.Env[Any, Any],
    episodes: int,
    /,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """Train ``agent`` for ``episodes`` episodes on ``env``: the plain loop
    (:func:`~skidnav.agents.training.train_plain`, with the seeds, ``max_steps`` and
    :class:`~skidnav.agents.training.Evaluation` of every trainer), the evaluations rolling out
    the frozen planner. ``planning_updates`` of the log counts the sequences rolled out through
    the model while learning (K per action). ValueError for an env of other spaces."""
    check_wheel_speed_env(env)
    return train_plain(agent, env, episodes, max_steps=max_steps, evaluation=evaluation, seed=seed)
