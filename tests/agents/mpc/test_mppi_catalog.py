"""mppi-kinematic through the catalog and the one runner: its entry (family, observation, config,
build, training), its greedy rollouts (each forgets the last one's plan), and ``skidnav run`` of
a tiny config giving the same numbers serially and in worker processes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pandas as pd
import pytest

from skidnav.agents.catalog import agent_names, entry
from skidnav.agents.greedy import greedy_evaluation
from skidnav.agents.interface import Agent, StepLearningAgent
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.training import Evaluation
from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.experiments.store import ResultStore
from tests.experiments.exp_support import comparable

TINY = Path(__file__).with_name("mppi-tiny.toml")
"""Two seeds of two episodes of 60 half-second actions on the free map."""


def wheel_speed_env(**options: Any) -> gymnasium.Env[Any, Any]:
    """World 3's free map, slippery floor, wheel speeds every 0.5 s (or ``options``)."""
    settings = {
        "map_kind": "free", "world_seed": 3, "slip": "slippery", "action": "continuous",
        "observation": "pose", "control_period": 0.5, "max_episode_steps": 60, **options,
    }  # fmt: skip
    return gymnasium.make("skidnav/SkidSteerNav-v0", **settings)


def test_its_entry_describes_the_family_observation_and_config() -> None:
    described = entry("mppi-kinematic")
    assert "mppi-kinematic" in agent_names()
    assert (described.family.name, described.observation) == ("mpc", "box")
    assert described.env_observation(None) == "features"  # its default: pose, goal, ranges
    assert described.env_observation("features") == "features"
    assert described.config_class is MPPIConfig
    assert described.config({"samples": 8}) == MPPIConfig(samples=8)
    with pytest.raises(
        UserError, match=r"^expected samples .* in agent 'mppi-kinematic'$"
    ) as error:
        described.config({"samples": 1})
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"action": "discrete"}, "two wheel speeds \\(action='continuous'\\)"),
        ({"observation": "discrete"}, "observing the pose or the features"),
    ],
)
def test_an_env_of_other_spaces_is_refused_in_one_line(
    options: dict[str, str], message: str
) -> None:
    env = wheel_speed_env(**options).unwrapped
    with pytest.raises(UserError, match=f"^agent 'mppi-kinematic': expected an env .*{message}"):
        entry("mppi-kinematic").build(env, {}, np.random.SeedSequence(0), 60)


def test_built_by_the_catalog_it_learns_and_its_greedy_rollouts_start_afresh() -> None:
    env, evaluation = wheel_speed_env().unwrapped, wheel_speed_env().unwrapped
    built = entry("mppi-kinematic").build(
        env, {"samples": 64, "horizon": 8}, np.random.SeedSequence(2), 60
    )
    agent = built.agent
    assert isinstance(agent, MPPIKinematicAgent)
    assert isinstance(agent, StepLearningAgent) and isinstance(agent, Agent)
    env.reset(seed=4)
    log = built.train(env, 2, max_steps=60, evaluation=Evaluation(evaluation, [7, 8]))
    assert log.greedy_lengths.shape == (2, 2) and agent.steps == log.lengths.sum()
    assert (log.planning_updates == 64 * log.lengths).all()
    assert log.successes.any()  # 0.25 m to the goal: it gets there within 30 s
    # the same seed twice: the same rollout, whatever the one before left in the plan
    first, again = greedy_evaluation(agent, evaluation, 60, [7, 7])
    assert first == again and first.length > 0
    steps = agent.steps
    assert agent.greedy_action(np.array([0.3, 0.25, 0.0])).shape == (2,)
    assert agent.steps == steps  # a greedy action learns nothing


def test_skidnav_run_gives_the_same_numbers_serially_and_in_processes(tmp_path: Path) -> None:
    serial, processes = tmp_path / "serial", tmp_path / "processes"
    argv = ["run", str(TINY), "--no-progress", "--out"]
    assert main([*argv, str(serial), "--backend", "serial"]) == 0
    assert main([*argv, str(processes), "--backend", "process", "--jobs", "2"]) == 0
    pd.testing.assert_frame_equal(comparable(processes), comparable(serial))
    episodes, summaries = ResultStore(serial).load_tables()
    assert len(episodes) == 2 * 2 and (episodes["agent"] == "mppi-kinematic").all()
    assert episodes["greedy_success"].between(0, 1).all() and episodes["success"].any()
    assert (episodes["planning_updates"] == 64 * episodes["length"]).all()
    # wheel-speed actions: no oracle of the four discrete actions, so no L*
    assert summaries["oracle_length"].isna().all() and summaries["action_limit"].eq(60).all()
