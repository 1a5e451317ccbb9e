"""dyna-sweep: value iteration over the learned models, and what it buys on a real arena."""

from __future__ import annotations

from pathlib import Path

import gymnasium
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.model_sweep import model_value_iteration
from skidnav.agents.tabular.registry import load_agent, make_agent
from skidnav.agents.training import Evaluation
from skidnav.experiments.metrics import (
    ConvergenceRule,
    convergence_episode,
    evaluation_summary,
    within_tolerance,
)
from skidnav.experiments.reference.oracle import compute_oracle

PARAMS = {
    "alpha": 0.5, "gamma": 0.95, "epsilon": 0.1, "planning_steps": 10,
    "planning_mode": "most-probable",
}  # fmt: skip
"""The thesis's planning target: with the expected one (the default) one of the three evaluation
seeds of this world loops from episode 17 on (2 of 3 rollouts reach the goal, in 8 actions), so
the run is censored at 40 episodes (measured)."""


def _arena(world_seed: int) -> gymnasium.Env:  # type: ignore[type-arg]
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="obstacles", slip="thesis", world_seed=world_seed,
        max_episode_steps=300,
    )  # fmt: skip


def _convergence(name: str, episodes: int) -> tuple[int, bool, object]:
    env, evaluation = _arena(4), _arena(4)
    oracle = compute_oracle(evaluation, 16, 0, [0, 1, 2], 300)
    if name == "q-learning":
        agent = make_agent(name, 12500, 4, {"alpha": 0.5, "epsilon": 0.1}, np.random.default_rng(4))
    else:
        agent = make_agent(
            name, 12500, 4, PARAMS, np.random.default_rng(4), task=env.unwrapped.task
        )
    env.reset(seed=4)
    log = train_agent_fast(
        agent, env, episodes, max_steps=300, evaluation=Evaluation(evaluation, [0, 1, 2])
    )
    mean, share = evaluation_summary(log.greedy_lengths)
    rule = ConvergenceRule(oracle.start_value, 0.1, 5, level=0.9)
    passed = within_tolerance(mean, share, rule)
    episode, converged = convergence_episode(passed, rule.window, rule.level)
    return episode, converged, agent


def test_dyna_sweep_converges_where_q_learning_has_not_started() -> None:
    episode, converged, agent = _convergence("dyna-sweep", 40)
    # measured: 31. Its first 10 passes in a row start at episode 3, but evaluations 17–30 fail:
    # a policy that did not stay converged there.
    assert converged and episode <= 35
    assert agent.planning_updates > 10 * agent.steps  # the solutions, beyond 10 per real step
    q_episode, q_converged, _ = _convergence("q-learning", 40)
    assert not q_converged and q_episode == 36  # censored at N − W + 1


def test_the_solution_is_a_fixed_point(tmp_path: Path) -> None:
    _, _, agent = _convergence("dyna-sweep", 10)
    assert agent.planner.goals.any()
    sweeps, _ = model_value_iteration(
        agent.q, agent.model.arrays, agent.planner, 0.95, agent.kernel_grid, 100_000, 1e-10
    )
    before = agent.q.copy()
    again, _ = model_value_iteration(
        agent.q, agent.model.arrays, agent.planner, 0.95, agent.kernel_grid, 1, 1e-10
    )
    assert sweeps > 1 and again == 1
    assert np.abs(agent.q - before).max() <= 1e-10
    # Saved and loaded, it knows it has solved these models.
    agent.save(tmp_path / "sweep")
    loaded = load_agent(tmp_path / "sweep")
    assert loaded._solved == agent._solved and len(agent._solved) == 3
    assert np.array_equal(loaded.q, agent.q)
