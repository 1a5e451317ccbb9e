"""The default horizon looks 10 s ahead, at most 40 control steps: 40 steps of the 0.1-s period
(4 s, where every 0.1-s table was measured), 10 of 1-s actions (where 40 steps, 40 s, let
nearly every perturbed sequence meet a wall: docs/agents/mppi-kinematic.md, "The horizon in
seconds"). An unset horizon is the same planner as the one given those steps."""

from __future__ import annotations

import numpy as np
import pytest

import skidnav
from skidnav.agents.mpc.config import MAX_HORIZON, MPPIConfig, steps_ahead, with_horizon
from skidnav.agents.mpc.planner import MPPIPlanner
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from tests.agents.mpc.support import nav_env


@pytest.mark.parametrize(
    ("period", "steps"), [(0.1, 40), (0.2, 40), (0.25, 40), (0.5, 20), (1.0, 10), (2.0, 5)]
)
def test_the_default_horizon_is_ten_seconds_of_at_most_forty_steps(
    period: float, steps: int
) -> None:
    assert MPPIConfig().horizon is None
    assert with_horizon(MPPIConfig(), period).horizon == steps
    assert with_horizon(MPPIConfig(horizon=7), period).horizon == 7  # a given horizon is kept
    assert steps_ahead(100.0) == 1  # never less than one step
    assert steps_ahead(1.0, 4.0, MAX_HORIZON) == 4  # the continuity study's 4 s


@pytest.mark.parametrize("period", [0.1, 1.0])
def test_an_agent_sets_its_horizon_from_its_control_period(period: float) -> None:
    env = skidnav.make_env(observation="pose", action="continuous", control_period=period)
    agent = skidnav.make_agent("mppi-kinematic", env, seed=0)
    assert agent.config.horizon == (40 if period == 0.1 else 10)
    assert agent.planner.plan.shape == (agent.config.horizon, 2)
    env.close()


def test_an_unset_horizon_plans_as_the_steps_it_stands_for() -> None:
    """At 1-s actions, the default and ``horizon = 10`` command the same wheel speeds, step for
    step, from the same seed."""
    commands = []
    for options in ({}, {"horizon": 10}):
        env = skidnav.make_env(
            observation="features", action="continuous", control_period=1.0,
            max_episode_steps=12,
        )  # fmt: skip
        agent = skidnav.make_agent("mppi-kinematic", env, seed=3, samples=32, **options)
        observation, _ = env.reset(seed=5)
        run = []
        for _ in range(12):
            action = agent.act(observation)
            run.append(np.asarray(action, dtype=float))
            following, reward, terminated, truncated, info = env.step(action)
            agent.observe(observation, action, reward, following, terminated, truncated, info)
            observation = following
            if terminated or truncated:
                break
        commands.append(np.array(run))
        env.close()
    assert len(commands[0]) > 1
    np.testing.assert_array_equal(commands[0], commands[1])


def test_a_planner_without_a_horizon_says_so_in_one_line() -> None:
    robot = RobotParams()
    with pytest.raises(ValueError, match="horizon set for a control period") as error:
        MPPIPlanner(
            MPPIConfig(), robot.kernel_constants(), Discretization().grid_shape(),
            np.random.default_rng(0),
        )  # fmt: skip
    assert "\n" not in str(error.value)


def test_the_test_env_runs_at_the_tenth_second_period() -> None:
    """The other mppi tests' env (0.1-s actions) keeps the 40-step default."""
    env = nav_env()
    assert steps_ahead(env.unwrapped.robot.action_duration) == 40
    env.close()
