"""``kinematic_model``: the learned kinematic model, its prior alone, or the simulator's truth."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.catalog import entry
from skidnav.agents.linear.registry import load_linear_agent
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import load_agent, make_agent
from skidnav.agents.training import train_agent
from skidnav.errors import CorruptFileError, UserError
from skidnav.experiments.configfile import parse_config
from skidnav.models.kinematic import KinematicModel
from skidnav.realtime.config import config_from_mapping
from skidnav.realtime.control.run import agent_context as robot_context
from skidnav.realtime.control.run import new_agent
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from tests.experiments.exp_support import TINY_TOML

OPTIONS = {"alpha": 0.5, "planning_steps": 10, "kinematic_refit_every": 100}


def _env() -> gym.Env[Any, Any]:
    return gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=2, slip="slippery")


def _trained(source: str, episodes: int = 6) -> tuple[Any, gym.Env[Any, Any]]:
    env = _env()
    params = {**OPTIONS, "kinematic_model": source}
    built = entry("dyna-full").build(env.unwrapped, params, np.random.SeedSequence(4), 300)
    agent = built.agent
    train_agent_fast(agent, env, episodes, seed=4, max_steps=300)
    return agent, env


def test_learned_refits_prior_and_true_hold_their_velocities() -> None:
    env = _env()
    nav: Any = env.unwrapped
    prior = KinematicModel(RobotParams(), nav.discretization).velocities
    truth = nav.true_kinematics
    assert not np.allclose(prior, truth)  # the slippery floor is not the nominal robot
    agents = {source: _trained(source)[0] for source in ("learned", "prior", "true")}
    for agent in agents.values():
        assert agent.kinematic.counts.sum() > 1000  # all of them keep the samples
    assert agents["learned"].kinematic.refits >= 1
    assert not np.allclose(agents["learned"].kinematic.velocities, prior)
    assert agents["prior"].kinematic.refits == 0
    np.testing.assert_array_equal(agents["prior"].kinematic.velocities, prior)
    assert agents["true"].kinematic.refits == 0
    np.testing.assert_array_equal(agents["true"].kinematic.velocities, truth)
    np.testing.assert_array_equal(agents["true"].planner.velocities, truth)  # what it plans with
    # the learned model comes closer to the truth than the prior is
    learned_error = np.abs(agents["learned"].kinematic.velocities - truth).mean()
    assert learned_error < 0.5 * np.abs(prior - truth).mean()


def test_only_an_agent_asking_for_the_truth_is_handed_it() -> None:
    nav: Any = _env().unwrapped
    dyna_full = entry("dyna-full")
    assert "true_kinematics" not in dyna_full.context(nav, {"kinematic_model": "prior"})
    assert "true_kinematics" not in dyna_full.context(nav, {})
    context = dyna_full.context(nav, {"kinematic_model": "true"})
    np.testing.assert_array_equal(context["true_kinematics"], nav.true_kinematics)
    with pytest.raises(ValueError, match=r"^expected the simulator's true_kinematics"):
        make_agent("dyna-full", nav.discretization.n_states, 4, {"kinematic_model": "true"},
                   task=nav.task)  # fmt: skip
    with pytest.raises(UserError, match="expected kinematic_model in"):
        make_agent("dyna-kinematic", 10, 4, {"kinematic_model": "truth"})


def test_the_truth_is_refused_on_the_physics_robot_and_on_a_real_one() -> None:
    text = TINY_TOML.replace('name = "dyna-q"', 'name = "dyna-full"').replace(
        "params = { planning_steps = 5 }", 'params = { kinematic_model = "true" }'
    )
    parse_config(text)  # on the kinematic simulator
    with pytest.raises(UserError, match="kinematic_model 'learned' or 'prior' with"):
        parse_config(text + '\n[env]\ndynamics = "mujoco"\n')
    robot, grid = RobotParams(), Discretization()
    config = config_from_mapping({"agents": {"dyna-full": {"kinematic_model": "true"}}})
    context = robot_context("dyna-full", robot, grid)
    with pytest.raises(UserError, match=r"^agent 'dyna-full': expected the simulator's"):
        new_agent("dyna-full", config, context, grid, np.random.default_rng(0))


def test_a_true_agent_saves_its_truth_and_continues_identically(tmp_path: Path) -> None:
    agent, env = _trained("true", episodes=3)
    agent.save(tmp_path / "agent")
    loaded = load_agent(tmp_path / "agent")  # the truth comes from the file
    np.testing.assert_array_equal(loaded.kinematic.velocities, agent.kinematic.velocities)
    assert loaded.kinematic.held and loaded.config.kinematic_model == "true"
    twin = copy.deepcopy(env)
    train_agent_fast(agent, env, 2)
    train_agent_fast(loaded, twin, 2)
    assert loaded.q.tobytes() == agent.q.tobytes()
    meta = json.loads((tmp_path / "agent.json").read_text())
    meta["true_kinematics"] = meta["true_kinematics"][:-1]
    (tmp_path / "agent.json").write_text(json.dumps(meta))
    with pytest.raises(CorruptFileError, match="true_kinematics of 49 × 4 × 3") as error:
        load_agent(tmp_path / "agent")
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("source", ["prior", "true"])
def test_the_linear_agent_holds_its_model_too(source: str, tmp_path: Path) -> None:
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=2,
                   slip="slippery", observation="pose")  # fmt: skip
    params = {"kinematic_steps": 5, "kinematic_refit_every": 50, "kinematic_model": source}
    built = entry("linear-dyna-kinematic").build(
        env.unwrapped, params, np.random.SeedSequence(1), 60
    )
    agent: Any = built.agent
    train_agent(agent, env, 3, max_steps=60, seed=1)
    assert agent.kinematic.refits == 0 and agent.kinematic.counts.sum() > 50
    expected = (
        env.unwrapped.true_kinematics  # type: ignore[attr-defined]
        if source == "true"
        else KinematicModel(RobotParams(), agent.context.discretization).velocities
    )
    np.testing.assert_array_equal(agent.kinematic.velocities, expected)
    agent.save(tmp_path / "agent")
    loaded = load_linear_agent(tmp_path / "agent.npz")
    np.testing.assert_array_equal(loaded.kinematic.velocities, expected)  # type: ignore[attr-defined]
