"""PPO and SAC (Stable-Baselines3) on wheel speeds: they learn a near goal, the same seed gives
the same network, their frozen policies meet the contract, their saved files round-trip or are
refused in one line."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.deep.common import DeepConfig
from skidnav.agents.deep.ppo import PPOAgent, PPOConfig, load_ppo
from skidnav.agents.deep.sac import SACAgent, SACConfig, load_sac
from skidnav.agents.deep.wheel_speeds import WheelSpeedAgent
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import CorruptFileError
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.mapfile import parse_map
from tests.agents.deep.test_dqn import TINY
from tests.saved_file_support import arrays_of, write_npz

MAX_STEPS = 30
EVAL_SEEDS = range(100, 105)
TINY_CONFIGS: dict[str, DeepConfig] = {
    "ppo": PPOConfig(n_steps=128, batch_size=64, learning_rate=1e-3, gamma=0.95),
    "sac": SACConfig(learning_starts=100, batch_size=64, learning_rate=1e-3, gamma=0.95),
}
"""Sized for the tiny map (the goal two full-speed actions of 1 s ahead)."""
AGENTS: dict[str, tuple[type[WheelSpeedAgent[Any]], Any]] = {
    "ppo": (PPOAgent, load_ppo),
    "sac": (SACAgent, load_sac),
}
TRAINING_EPISODES = {"ppo": 80, "sac": 40}


def tiny_env(observation: str = "features", action: str = "continuous") -> gym.Env[Any, Any]:
    """The 0.2 m arena of the DQN test, with wheel-speed actions of 1 s."""
    return gym.make(
        "skidnav/SkidSteerNav-v0", grid_map=parse_map(TINY), observation=observation,
        action=action, robot=RobotParams(arena_width=0.2, arena_height=0.2),
        discretization=Discretization(n_x=8, n_y=8, n_headings=10, arena_width=0.2,
                                      arena_height=0.2),
        max_episode_steps=MAX_STEPS,
    )  # fmt: skip


def new_agent(name: str, seed: int = 0, **changes: Any) -> WheelSpeedAgent[Any]:
    config = TINY_CONFIGS[name]
    if changes:
        config = type(config).from_mapping({**config.__dict__, **changes})
    return AGENTS[name][0](tiny_env(), config, seed=seed)


def policy_returns(policy: WheelSpeedPolicy) -> tuple[float, float]:
    """(mean return, share of goals reached) of ``policy`` over the fixed evaluation seeds."""
    env, totals, reached = tiny_env(), [], 0
    for seed in EVAL_SEEDS:
        observation, _ = env.reset(seed=seed)
        total = 0.0
        for _ in range(MAX_STEPS):
            action = np.array(policy.wheel_speeds(observation), dtype=np.float32)
            observation, reward, terminated, truncated, _ = env.step(action)
            total += float(reward)
            if terminated or truncated:
                reached += int(terminated)
                break
        totals.append(total)
    return float(np.mean(totals)), reached / len(EVAL_SEEDS)


@pytest.fixture(scope="module", params=["ppo", "sac"])
def trained(request: pytest.FixtureRequest) -> tuple[str, WheelSpeedAgent[Any], Any, Any]:
    """(name, agent, its policy before training, the training log)."""
    name = request.param
    agent = new_agent(name)
    untrained = agent.policy()
    return name, agent, untrained, agent.train_episodes(TRAINING_EPISODES[name])


def test_the_trained_policy_reaches_the_goal_the_untrained_one_does_not(
    trained: tuple[str, WheelSpeedAgent[Any], Any, Any],
) -> None:
    name, agent, untrained, log = trained
    assert len(log.returns) == TRAINING_EPISODES[name] == agent.episodes
    assert agent.steps == log.lengths.sum()
    before, reached_before = policy_returns(untrained)
    after, reached_after = policy_returns(agent.policy())
    assert reached_before == 0 and before <= -MAX_STEPS  # measured −30 (ppo), −120 (sac)
    assert reached_after == 1 and after >= 6  # five actions at most: measured 7 (four)
    assert log.successes[-10:].mean() >= 0.8  # measured 1.0


def test_a_frozen_policy_meets_the_contract_and_stays_frozen(
    trained: tuple[str, WheelSpeedAgent[Any], Any, Any],
) -> None:
    _, agent, _, _ = trained
    policy = agent.policy()
    assert isinstance(policy, WheelSpeedPolicy)
    assert (policy.lidar_rays, policy.lidar_range) == (8, 0.3)
    observation = tiny_env().reset(seed=0)[0]
    speeds = policy.wheel_speeds(observation)
    assert np.allclose(speeds, agent.greedy_action(observation))
    assert all(abs(speed) <= 1.7 for speed in speeds)
    import torch

    with torch.no_grad():  # training moves the live network, not the frozen copy
        for parameter in agent.network().parameters():
            parameter.add_(0.5)
    try:
        assert policy.wheel_speeds(observation) == speeds
        assert not np.allclose(speeds, agent.greedy_action(observation))
    finally:
        with torch.no_grad():
            for parameter in agent.network().parameters():
                parameter.sub_(0.5)


@pytest.mark.parametrize("name", ["ppo", "sac"])
def test_the_same_seed_gives_the_same_network(name: str) -> None:
    first, second, other = new_agent(name), new_agent(name), new_agent(name, seed=1)
    logs = [agent.train_episodes(4) for agent in (first, second, other)]
    assert np.array_equal(logs[0].returns, logs[1].returns)
    weights = [agent.weights() for agent in (first, second, other)]
    assert all(np.array_equal(weights[0][key], weights[1][key]) for key in weights[0])
    assert not all(np.array_equal(weights[0][key], weights[2][key]) for key in weights[0])


@pytest.mark.parametrize("name", ["ppo", "sac"])
def test_a_stopped_training_resumes_from_the_new_episode(name: str) -> None:
    """The step that ended a call is finished as Stable-Baselines3 would have: the next call
    starts from the reset observation, and a replay buffer keeps the last transition."""
    agent = new_agent(name)
    agent.train_episodes(2)
    start = agent.scale(tiny_env().reset(seed=0)[0])
    assert np.allclose(agent.model._last_obs, start)
    if name == "sac":
        assert agent.model.replay_buffer.size() == agent.steps  # type: ignore[attr-defined]


def test_a_saved_agent_acts_the_same_after_loading(
    trained: tuple[str, WheelSpeedAgent[Any], Any, Any], tmp_path: Path
) -> None:
    name, agent, _, _ = trained
    agent.save(tmp_path / name)
    loaded = AGENTS[name][1](tmp_path / name, tiny_env())
    assert type(loaded) is type(agent) and loaded.config == agent.config
    for key, value in agent.weights().items():
        assert np.array_equal(loaded.weights()[key], value)
    space = tiny_env().observation_space
    space.seed(0)
    for observation in (space.sample() for _ in range(5)):
        assert loaded.policy().wheel_speeds(observation) == agent.policy().wheel_speeds(observation)


def test_a_damaged_misshapen_or_foreign_file_is_one_line(
    trained: tuple[str, WheelSpeedAgent[Any], Any, Any], tmp_path: Path
) -> None:
    name, agent, _, _ = trained
    load = AGENTS[name][1]
    agent.save(tmp_path / "a")
    arrays = arrays_of(tmp_path / "a.npz")
    first = sorted(arrays)[0]
    write_npz(tmp_path / "a.npz", {**arrays, first: arrays[first][..., :1]})
    with pytest.raises(CorruptFileError, match=rf"a\.npz.*{first}.*shape") as error:
        load(tmp_path / "a", tiny_env())
    assert "\n" not in str(error.value)
    (tmp_path / "a.npz").write_bytes(b"not a zip archive")
    with pytest.raises(CorruptFileError, match=r"a\.npz"):
        load(tmp_path / "a", tiny_env())
    agent.save(tmp_path / "b")
    fewer_rays = gym.make("skidnav/SkidSteerNav-v0", observation="features", lidar_rays=4,
                          action="continuous")  # fmt: skip
    with pytest.raises(CorruptFileError, match="another observation space"):
        load(tmp_path / "b", fewer_rays)
    other = "sac" if name == "ppo" else "ppo"
    with pytest.raises(CorruptFileError, match=f"not a skidnav {other.upper()} file"):
        AGENTS[other][1](tmp_path / "b", tiny_env())


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: PPOConfig(gamma=1.5), r"ppo: gamma = 1\.5 is out of range"),
        (lambda: PPOConfig(batch_size=256, n_steps=128), "ppo: batch_size = 256 is out of range"),
        (lambda: PPOConfig(n_steps=True), "ppo: n_steps = True is not an integer"),
        (lambda: SACConfig(gamma="0.9"), "sac: gamma = '0.9' is not a number"),
        (lambda: SACConfig(ent_coef="auto_0.1"), "sac: ent_coef = 'auto_0.1' is out of range"),
        (lambda: SACConfig(tau=float("nan")), "sac: tau = nan is out of range"),
        (lambda: SACConfig(hidden=(64, 0)), r"sac: hidden = \(64, 0\) is out of range"),
        (lambda: SACConfig.from_mapping({"alpha": 0.2}), "unknown key 'alpha' in sac"),
        (lambda: PPOAgent(tiny_env(observation="pose")), "ppo: expected the feature observation"),
        (lambda: SACAgent(tiny_env(action="discrete")), "sac: expected Box actions"),
    ],
)
def test_bad_settings_are_one_line(make: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make()


@pytest.mark.parametrize(
    ("name", "action", "wanted"),
    [("ppo", "discrete", "Box"), ("sac", "discrete", "Box"), ("dqn", "continuous", "Discrete")],
)
def test_the_api_refuses_an_env_of_other_actions_in_one_line(
    name: str, action: str, wanted: str
) -> None:
    import skidnav
    from skidnav.errors import UserError

    env = skidnav.make_env("free", observation="features", action=action)
    with pytest.raises(UserError) as refused:
        skidnav.make_agent(name, env)
    message = str(refused.value)
    assert message.startswith(f"agent {name!r} takes {wanted} actions, the env gives ")
    assert message.endswith("(set [env] action)") and "\n" not in message


def test_a_saved_policy_loads_without_its_world(
    trained: tuple[str, WheelSpeedAgent[Any], Any, Any], tmp_path: Path
) -> None:
    """Through the saved-file door (the families' policy loaders): the real-time loop's way to
    run a policy."""
    from skidnav.agents.saved import load_policy

    name, agent, _, _ = trained
    _, json_path = agent.save(tmp_path / name)
    policy = load_policy(json_path)
    assert (policy.lidar_rays, policy.lidar_range) == (8, 0.3)
    space = tiny_env().observation_space
    space.seed(1)
    for observation in (space.sample() for _ in range(5)):
        assert policy.wheel_speeds(observation) == agent.policy().wheel_speeds(observation)
    meta = json.loads(json_path.read_text())
    huge = 10**400  # no float holds it
    low = meta["observation_low"]
    edits = [
        ("lidar_rays", 7, "cannot load policy"),
        ("lidar_range", "far", "cannot load policy"),
        ("action_high", [-2, -2], "cannot load policy"),
        ("observation_low", [huge, *low[1:]], "cannot load policy"),
        ("action_low", [huge, -1.7], "cannot load policy"),
        ("seed", "7", "seed '7' is not an integer"),
        ("version", 1.0, "file of version"),
        ("config", {**meta["config"], "batch_size": huge}, "batch_size = .* out of range"),
        ("config", {**meta["config"], "hidden": [4096] * 8}, "hidden = .* out of range"),
    ]
    if name == "sac":
        edits += [
            ("config", {**meta["config"], "ent_coef": huge}, "ent_coef = .* out of range"),
            ("config", {**meta["config"], "buffer_size": 10**13}, "buffer_size = .* range"),
        ]
    else:
        edits.append(("config", {**meta["config"], "n_steps": 10**13}, "n_steps = .* range"))
    for key, value, match in edits:
        json_path.write_text(json.dumps({**meta, key: value}))
        with pytest.raises(CorruptFileError, match=match) as error:
            load_policy(json_path)
        assert "\n" not in str(error.value)
