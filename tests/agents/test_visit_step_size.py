"""Step sizes that decay with a pair's real visits (``alpha_visit_exponent``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skidnav.agents.config import QLearningConfig
from skidnav.agents.linear.config import LinearConfig
from skidnav.agents.tabular.config import PrioritizedSweepingConfig
from skidnav.agents.tabular.registry import load_agent, make_agent
from skidnav.agents.training import train_agent
from skidnav.envs.mazes import dyna_maze
from skidnav.sim.q_values import visit_step_size

DECAYING = ("q-learning", "dyna-q", "dyna-q-plus")


def test_the_step_size_is_alpha_times_visits_to_the_minus_exponent() -> None:
    visits = np.zeros((2, 3), dtype=np.int64)
    sizes = [visit_step_size(visits, 1, 2, 0.8, 0.5) for _ in range(4)]
    assert sizes == pytest.approx([0.8, 0.8 / np.sqrt(2), 0.8 / np.sqrt(3), 0.4])
    assert visits[1, 2] == 4 and visits.sum() == 4
    placeholder = np.zeros((1, 1), dtype=np.int64)
    assert visit_step_size(placeholder, 5, 3, 0.3, 0.0) == 0.3 and placeholder[0, 0] == 0


def test_exponent_one_with_alpha_one_averages_the_targets() -> None:
    """ω = 1, α = 1: the n-th update moves by 1/n, so Q is the sample mean of the targets."""
    agent = make_agent("q-learning", 2, 1, {"alpha": 1.0, "alpha_visit_exponent": 1.0})
    rewards = np.random.default_rng(0).normal(size=50)
    for reward in rewards:
        agent.observe(0, 0, float(reward), 1, terminated=True)
    assert agent.q[0, 0] == pytest.approx(rewards.mean(), abs=1e-12)
    constant = make_agent("q-learning", 2, 1, {"alpha": 1.0})
    for reward in rewards:
        constant.observe(0, 0, float(reward), 1, terminated=True)
    assert constant.q[0, 0] == rewards[-1]  # the constant α = 1 keeps only the last target


@pytest.mark.parametrize("name", [*DECAYING, "dyna-full"])
def test_an_exponent_changes_learning_and_zero_keeps_the_placeholder(name: str) -> None:
    options = {} if name == "q-learning" else {"planning_steps": 5}
    runs = {}
    for exponent in (0.0, 0.8):
        agent = make_agent(
            name, 54, 4, {"alpha": 0.5, "alpha_visit_exponent": exponent, **options},
            np.random.default_rng(1),
        )  # fmt: skip
        train_agent(agent, dyna_maze(), 5, seed=1)
        runs[exponent] = agent
    assert runs[0.0].visits.shape == (1, 1) and runs[0.0].visits[0, 0] == 0
    assert runs[0.8].visits.sum() == runs[0.8].steps
    assert not np.array_equal(runs[0.0].q, runs[0.8].q)


@pytest.mark.parametrize("name", DECAYING)
def test_saved_visits_continue_identically(name: str, tmp_path: Path) -> None:
    planning = {} if name == "q-learning" else {"planning_steps": 5}
    options = {"alpha_visit_exponent": 0.7, **planning}
    agent = make_agent(name, 54, 4, options, np.random.default_rng(2))
    train_agent(agent, dyna_maze(), 4, seed=2)
    agent.save(tmp_path / "agent")
    loaded = load_agent(tmp_path / "agent.npz")
    assert np.array_equal(loaded.visits, agent.visits)
    for each in (agent, loaded):
        env = dyna_maze()
        env.reset(seed=9)
        train_agent(each, env, 3)
    assert np.array_equal(loaded.q, agent.q) and np.array_equal(loaded.visits, agent.visits)


@pytest.mark.parametrize("exponent", [-0.1, 1.5, float("nan")])
def test_an_exponent_outside_zero_one_is_refused(exponent: float) -> None:
    with pytest.raises(ValueError, match="alpha_visit_exponent in"):
        QLearningConfig(alpha_visit_exponent=exponent)


@pytest.mark.parametrize("config_class", [PrioritizedSweepingConfig, LinearConfig])
def test_agents_without_visit_counts_refuse_an_exponent(config_class: type) -> None:
    with pytest.raises(ValueError, match="alpha_visit_exponent 0"):
        config_class(alpha_visit_exponent=0.5)
