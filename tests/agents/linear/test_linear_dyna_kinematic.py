"""linear-dyna-kinematic: Linear Dyna plus planning from perturbed visited poses through the
learned kinematic model (docs/agents/linear-dyna.md, "linear-dyna-kinematic")."""

from __future__ import annotations

import copy
import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from skidnav.agents import kinematic_planning as kp
from skidnav.agents.catalog import entry
from skidnav.agents.linear.dyna_kinematic import LinearDynaKinematicAgent
from skidnav.agents.linear.registry import load_linear_agent, make_linear_agent
from skidnav.agents.training import train_agent
from skidnav.errors import CorruptFileError, UserError
from skidnav.experiments.config_checks import check_config
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import ResultStore
from tests.saved_file_support import arrays_of, write_npz

from .support import make, small_pose_env

NAME = "linear-dyna-kinematic"


def agent_on(env: gym.Env[Any, Any], seed: int, **options: Any) -> LinearDynaKinematicAgent:
    """The agent on ``env``'s observation with its task, α = 0.5 and ``options``."""
    config = {"alpha": 0.5, **options}
    agent = make_linear_agent(
        NAME, env.observation_space, 4, config, np.random.default_rng(seed),  # type: ignore[arg-type]
        task=env.unwrapped.task,  # type: ignore[attr-defined]
    )  # fmt: skip
    assert isinstance(agent, LinearDynaKinematicAgent)
    return agent


def drawn_action(rng: np.random.Generator) -> int:
    """The action the next kinematic update of ``rng`` draws (its fifth draw: one uniform for
    the pose, three normals, one uniform for the action), ``rng`` untouched."""
    probe = copy.deepcopy(rng)
    probe.random()
    probe.standard_normal(3)
    return int(probe.random() * 4)


def ready_for_one_update(agent: LinearDynaKinematicAgent, pose: tuple[float, float, float]) -> None:
    """A single remembered pose, no perturbation, kinematic planning switched on."""
    agent.steps = 1
    agent.visited_poses[0] = pose
    agent.planner.counters[kp.USE_KINEMATIC] = 1


def test_without_kinematic_steps_it_is_linear_dyna_bit_for_bit() -> None:
    env_dyna, env_kinematic = small_pose_env(), small_pose_env()
    dyna = make("linear-dyna", env_dyna, 3, planning_steps=3, planning_memory=40)
    agent = agent_on(env_kinematic, 3, planning_steps=3, planning_memory=40, kinematic_steps=0)
    log_dyna = train_agent(dyna, env_dyna, 20, max_steps=30, seed=3)
    log = train_agent(agent, env_kinematic, 20, max_steps=30, seed=3)
    assert log.lengths.tolist() == log_dyna.lengths.tolist()
    for name in ("w", "next_model", "reward_model", "visited"):
        assert getattr(agent, name).tobytes() == getattr(dyna, name).tobytes(), name
    assert agent.rng.bit_generator.state == dyna.rng.bit_generator.state
    assert agent.planning_updates == dyna.planning_updates
    # the kinematic side learned all the same: samples, refits, rewards, the goal cell
    assert agent.kinematic is not None and agent.kinematic.counts.sum() > 1000
    assert agent.kinematic.refits >= 1 and agent.planner.goals[3, 6]


def test_a_planned_update_by_hand() -> None:
    env = small_pose_env()
    agent = agent_on(env, 0, n_tilings=1, tiles=[4], gamma=0.9, kinematic_steps=1,
                     kinematic_position_std=0.0, kinematic_heading_std=0.0)  # fmt: skip
    pose, next_pose = (0.05, 0.10, 0.0), (0.07, 0.10, 0.0)
    ready_for_one_update(agent, pose)
    agent.planner.velocities[...] = (0.02, 0.0, 0.0)  # every action: 2 cm/s straight ahead
    agent.planner.reward_stats[:-2] = (-2.0, 1.0)  # a free step: −2
    agent.w[:] = np.arange(agent.w.size, dtype=np.float64).reshape(agent.w.shape) / 100
    action = drawn_action(agent.rng)
    x, x_next = agent.features(np.array(pose)), agent.features(np.array(next_pose))
    assert x.tolist() != x_next.tolist()  # x: tile 0 (0.05 / 0.0625), x′: tile 1
    before = agent.w[action, x[0]]
    # 1 s at 2 cm/s: x′ = (0.07, 0.10, 0); target −2 + 0.9 · max_a′ w[a′, x′]
    target = -2.0 + 0.9 * agent.w[:, x_next[0]].max()
    assert agent.plan_kinematic(1) == 1
    assert agent.w[action, x[0]] == pytest.approx(before + 0.5 * (target - before), abs=1e-12)
    # A known goal cell at x′: a predicted arrival, the goal's mean reward and no bootstrap.
    agent.planner.goals[agent.context.discretization.cell(*next_pose[:2])] = True  # type: ignore[union-attr]
    agent.planner.reward_stats[-1] = (10.0, 1.0)
    action = drawn_action(agent.rng)
    before = agent.w[action, x[0]]
    assert agent.plan_kinematic(1) == 1
    assert agent.w[action, x[0]] == pytest.approx(before + 0.5 * (10.0 - before), abs=1e-12)


def seed_drawing(action: int) -> int:
    """A generator seed whose first kinematic update draws ``action``."""
    return next(s for s in range(1000) if drawn_action(np.random.default_rng(s)) == action)


@pytest.mark.parametrize("action", [0, 3])
def test_a_move_into_a_wall_is_blocked_as_the_mdp_blocks_it(action: int) -> None:
    # The small arena has no slip and the nominal robot: the untrained kinematic model is the
    # true kinematics, so with the map's walls known the planner's step is the env's step.
    env = small_pose_env()
    agent = agent_on(env, seed_drawing(action), kinematic_steps=1, kinematic_position_std=0.0,
                     kinematic_heading_std=0.0)  # fmt: skip
    pose = (0.12, 0.045, -math.pi / 2)  # facing the bottom border wall (cells j = 0, y < 1/32)
    ready_for_one_update(agent, pose)
    unwrapped: Any = env.unwrapped
    agent.planner.walls[...] = unwrapped.task.occupancy != 0
    agent.planner.reward_stats[:-2] = (-1.0, 1.0)
    agent.planner.reward_stats[-2] = (-10.0, 1.0)
    agent.w[:] = np.random.default_rng(1).normal(size=agent.w.shape)
    env.reset(seed=0)
    unwrapped.pose[:] = pose
    observation, reward, terminated, _, info = env.step(action)
    assert not terminated
    if action == 0:  # forward hits the wall: stopped at the last free sub-step, in cell j = 1
        grid = agent.context.discretization  # type: ignore[union-attr]
        assert info["collision"] and grid.cell(*info["pose"][:2])[1] == 1
    expected_reward = -10.0 if info["collision"] else -1.0
    assert reward == expected_reward  # the env's reward is the mean the planner uses (no slip)
    target = expected_reward + agent.config.gamma * agent.q_values(observation).max()  # bootstraps
    q_before = agent.q_values(np.array(pose))[action]
    agent.plan_kinematic(1)
    q_after = agent.q_values(np.array(pose))[action]
    assert q_after == pytest.approx(q_before + 0.5 * (target - q_before), abs=1e-9)


def test_the_planner_observes_poses_as_the_env() -> None:
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=2,
                   observation="features", lidar_rays=6, lidar_range=0.25)  # fmt: skip
    agent = agent_on(env, 0, dimensions=[4, 7, 8], tiles=[3], planning_memory=10)
    unwrapped: Any = env.unwrapped
    for pose in [(0.1, 0.2, 0.3), (0.4, 0.05, -2.0), (0.55, 0.45, 3.1)]:
        expected = agent.features(unwrapped.features(np.array(pose)))
        assert agent.observation_tiles(pose).tolist() == expected.tolist()
        observation = unwrapped.features(np.array(pose))
        assert agent.pose_of(observation) == pytest.approx(pose, abs=1e-12)


def test_the_kinematic_planning_speeds_up_learning_on_the_small_arena() -> None:
    # 60 episodes of at most 12 actions, the goal five forward actions away, seed 0.
    env_dyna, env_kinematic = small_pose_env(), small_pose_env()
    log_dyna = train_agent(make("linear-dyna", env_dyna, 0), env_dyna, 60, max_steps=12, seed=0)
    agent = agent_on(env_kinematic, 0)
    log = train_agent(agent, env_kinematic, 60, max_steps=12, seed=0)
    first, last = log.successes[:20].mean(), log.successes[-20:].mean()
    assert last >= 0.8 and last > first + 0.2  # measured: 0.55 → 0.95
    assert log.successes[:20].mean() > log_dyna.successes[:20].mean() + 0.2  # dyna: 0.2
    assert agent.planning_updates > agent.steps * 5  # the kinematic updates are counted
    # every wall the agent guessed from its collisions is a wall of the map
    occupancy: np.ndarray = env_kinematic.unwrapped.task.occupancy  # type: ignore[attr-defined]
    assert agent.planner.walls.any() and occupancy[agent.planner.walls].all()


def test_the_runner_builds_it_with_its_task() -> None:
    env = small_pose_env()
    agent = entry(NAME).build(env.unwrapped, {"tiles": [2]}, np.random.SeedSequence(0), 12).agent
    assert isinstance(agent, LinearDynaKinematicAgent) and agent.kinematic is not None
    bare = make(NAME, env, 0)  # no task: linear-dyna
    assert isinstance(bare, LinearDynaKinematicAgent) and bare.kinematic is None


RUNNER_CONFIG = """
[experiment]
name = "linear-dyna-kinematic"
episodes = 3
max_steps = 30
seeds = 1
root_seed = 5
presets = ["rough"]
bootstrap_samples = 100
convergence_window = 2
eval_rollouts = 2
oracle_samples = 4

[env]
observation = "features"

[[maps]]
kind = "free"

[[agents]]
name = "linear-dyna-kinematic"
params = { dimensions = [4, 5, 6], kinematic_steps = 20 }
"""


def test_the_experiment_runner_runs_it(tmp_path: Path) -> None:
    # The runner's warm-up trains on a throwaway world of a few cells before the run itself.
    config = parse_config(RUNNER_CONFIG)
    check_config(config)
    run_experiment(config, tmp_path, backend="serial")
    episodes, summaries = ResultStore(tmp_path).load_tables()
    assert summaries["agent"].tolist() == [NAME] and len(episodes) == 3
    assert (episodes["planning_updates"] > 0).all()


def test_bad_configs_and_contexts_are_one_line_errors() -> None:
    env = small_pose_env()
    for options, message in [
        ({"kinematic_steps": -1}, "kinematic_steps"),
        ({"kinematic_heading_std": math.inf}, "kinematic_heading_std"),
        ({"kinematic_window": 0}, "window"),
    ]:
        with pytest.raises(UserError, match=message) as error:
            agent_on(env, 0, **options)
        assert "\n" not in str(error.value)
    space = gym.spaces.Box(low=np.zeros(2), high=np.ones(2), dtype=np.float64)
    with pytest.raises(UserError, match="'pose' or 'features' observation"):
        make_linear_agent(NAME, space, 4, {}, task=env.unwrapped.task)  # type: ignore[attr-defined]


def trained(tmp_path: Path) -> LinearDynaKinematicAgent:
    env = small_pose_env()
    agent = agent_on(env, 5, tiles=[2], planning_memory=50, kinematic_refit_every=100)
    train_agent(agent, env, 4, max_steps=12, seed=5)
    assert agent.kinematic is not None and agent.kinematic.refits >= 1
    agent.save(tmp_path / "agent")
    return agent


def test_a_loaded_agent_continues_as_the_saved_one(tmp_path: Path) -> None:
    agent = trained(tmp_path)
    loaded = load_linear_agent(tmp_path / "agent.npz")
    assert isinstance(loaded, LinearDynaKinematicAgent) and loaded.config == agent.config
    for key, array in agent.state_arrays().items():
        assert loaded.state_arrays()[key].tobytes() == array.tobytes(), key
    assert loaded.kinematic is not None and agent.kinematic is not None
    assert loaded.kinematic.velocities.tobytes() == agent.kinematic.velocities.tobytes()
    assert loaded.context.goal_cell == (3, 6)  # type: ignore[union-attr]
    train_agent(agent, small_pose_env(), 3, max_steps=12, seed=6)
    train_agent(loaded, small_pose_env(), 3, max_steps=12, seed=6)
    assert loaded.w.tobytes() == agent.w.tobytes()
    assert loaded.rng.bit_generator.state == agent.rng.bit_generator.state


def test_damaged_files_are_one_line_errors(tmp_path: Path) -> None:
    trained(tmp_path)
    npz_path, json_path = tmp_path / "agent.npz", tmp_path / "agent.json"
    arrays = arrays_of(npz_path)
    counts = arrays["kinematic_counts"].copy()
    counts[0] = -5
    cases = {
        "map_occupancy": ({**arrays, "map_occupancy": arrays["map_occupancy"] * 3}, "0 and 1"),
        "poses": ({**arrays, "visited_poses": arrays["visited_poses"][:-1]}, "visited_poses"),
        "counters": ({**arrays, "planner_counters": arrays["planner_counters"] + 7}, "counters"),
        "counts": ({**arrays, "kinematic_counts": counts}, "sample counts"),
        "evidence": (
            {**arrays, "planner_free_evidence": arrays["planner_free_evidence"] - 1},
            "evidence are not counts",
        ),
    }
    for case, (members, message) in cases.items():
        write_npz(npz_path, members)
        with pytest.raises(CorruptFileError, match=message) as error:
            load_linear_agent(npz_path)
        assert "\n" not in str(error.value) and str(npz_path) in str(error.value), case
    meta = json.loads(json_path.read_text())
    meta["context"]["goal_cell"] = [99, 0]
    json_path.write_text(json.dumps(meta))
    with pytest.raises(CorruptFileError, match="goal cell inside the grid") as error:
        load_linear_agent(npz_path)
    assert "\n" not in str(error.value) and str(json_path) in str(error.value)


TRAINING = """
import sys
import numpy as np
from skidnav.agents.linear.registry import make_linear_agent
from skidnav.agents.training import train_agent
from tests.agents.linear.support import small_pose_env

env = small_pose_env()
agent = make_linear_agent(
    "linear-dyna-kinematic", env.observation_space, 4,
    {"tiles": [2], "n_tilings": 4, "planning_steps": 2, "planning_memory": 20,
     "kinematic_steps": 5, "kinematic_refit_every": 50},
    np.random.default_rng(4), task=env.unwrapped.task,
)
log = train_agent(agent, env, 4, max_steps=12, seed=4)
np.savez(sys.argv[1], w=agent.w, lengths=log.lengths)
"""


def test_the_same_weights_without_jit(tmp_path: Path) -> None:
    root = Path(__file__).resolve().parents[3]
    results = []
    for disable in ("0", "1"):
        env = {**os.environ, "NUMBA_DISABLE_JIT": disable}
        env["PYTHONPATH"] = os.pathsep.join([str(root / "src"), str(root)])
        out = tmp_path / f"jit{disable}.npz"
        subprocess.run([sys.executable, "-c", TRAINING, str(out)], check=True, env=env, timeout=240)
        with np.load(out) as archive:
            results.append({key: archive[key] for key in archive.files})
    assert results[0]["w"].tobytes() == results[1]["w"].tobytes()
    assert results[0]["lengths"].tolist() == results[1]["lengths"].tolist()
    assert np.any(results[0]["w"] != 0.0)
