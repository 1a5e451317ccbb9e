"""The fused compiled trainers give the same numbers as the plain loops, with and without numba."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.tabular.fast_training import (
    evaluate_q_fast,
    train_agent_fast,
    train_for_steps_fast,
)
from skidnav.agents.tabular.registry import make_agent
from skidnav.agents.training import Evaluation, TrainingLog, train_agent, train_for_steps
from skidnav.envs.mazes import blocking_maze, dyna_maze
from skidnav.experiments.reference.oracle import compute_oracle
from skidnav.world.discretization import Discretization

AGENTS = (
    "q-learning",
    "dyna-q",
    "dyna-q-plus",
    "prioritized-sweeping",
    "dyna-kinematic",
    "trajectory-prioritized",
    "dyna-full",
)
SRC = Path(__file__).resolve().parents[2] / "src"


def _run(trainer: Any, name: str, world_seed: int = 2) -> tuple[TrainingLog, Any]:
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=world_seed,
                   slip="slippery", max_episode_steps=300)  # fmt: skip
    evaluation = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=world_seed,
                          slip="slippery", max_episode_steps=300)  # fmt: skip
    context = {"task": env.unwrapped.task} if name in AGENTS[4:] else {}  # type: ignore[attr-defined]
    config = {"epsilon": 0.2} if name == "q-learning" else {"epsilon": 0.2, "planning_steps": 8}
    agent = make_agent(name, 12_500, 4, config, np.random.default_rng(7), **context)
    log = trainer(agent, env, 6, max_steps=250, evaluation=Evaluation(evaluation), seed=11)
    return log, agent


@pytest.mark.parametrize("name", AGENTS)
def test_fast_trainer_matches_the_python_loop(name: str) -> None:
    slow, slow_agent = _run(train_agent, name)
    fast, fast_agent = _run(train_agent_fast, name)
    for field in TrainingLog._fields:
        if field != "wall_time":
            np.testing.assert_array_equal(getattr(fast, field), getattr(slow, field), err_msg=field)
    np.testing.assert_array_equal(fast_agent.q, slow_agent.q)
    assert fast_agent.steps == slow_agent.steps == slow.lengths.sum()
    assert fast_agent.planning_updates == slow_agent.planning_updates
    assert fast_agent.rng.random() == slow_agent.rng.random()


def _step_by_step_cost(q: np.ndarray, env: Any, seed: int, max_steps: int) -> tuple[float, int]:
    """The cost of the greedy rollout of ``q`` re-run with the plain env: minus the sum of its
    rewards, the goal's +10 replaced by what a free step ending there costs, 1 + 10·η²/12 of
    the goal's region (NaN if the goal is not reached); and the collisions on the way. Each
    step's ``info["cost"]`` must be that cost."""
    nav = env.unwrapped
    state, _ = nav.reset(seed=seed)
    cost, collisions = 0.0, 0
    for _ in range(max_steps):
        state, reward, terminated, _, info = nav.step(int(np.argmax(q[state])))
        if terminated:
            eta = nav.slip_field.eta.ravel()[info["region"]]
            assert info["cost"] == 1.0 + 10.0 * (eta * eta / 12.0)
            return cost + info["cost"], collisions
        assert info["cost"] == -reward
        cost += -reward
        collisions += info["collision"]
    return float("nan"), collisions


def test_the_evaluation_costs_are_the_env_rewards_without_the_goal_bonus() -> None:
    evaluation = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=14,
                          slip="slippery", max_episode_steps=300)  # fmt: skip
    q = compute_oracle(evaluation, 8, 0, [0], 300).q  # a policy that reaches the goal, mostly
    seeds = list(range(10))
    lengths, costs = evaluate_q_fast(q, evaluation, seeds, 100)
    replayed = np.array([_step_by_step_cost(q, evaluation, s, 100) for s in seeds])
    np.testing.assert_array_equal(costs, replayed[:, 0])
    collisions = replayed[:, 1]
    reached = lengths > 0
    assert 2 <= reached.sum() < len(seeds) and collisions[reached].max() > 0
    assert (costs[reached] > lengths[reached]).all()  # the slippery floor costs more
    assert np.isnan(costs[~reached]).all()


def test_other_envs_fall_back_to_the_python_loop() -> None:
    logs = []
    for trainer in (train_agent, train_agent_fast):
        agent = make_agent("dyna-q", 48, 4, {"planning_steps": 5}, np.random.default_rng(0))
        logs.append(trainer(agent, gym.make("CliffWalking-v1"), 3, max_steps=200, seed=0))
    np.testing.assert_array_equal(logs[0].lengths, logs[1].lengths)


MAZE_AGENTS = AGENTS[:4]
"""The agents the fused maze loop runs (the model-based ones need the navigation env)."""


def _maze_config(name: str) -> dict[str, Any]:
    return {"epsilon": 0.2} if name == "q-learning" else {"epsilon": 0.2, "planning_steps": 8}


@pytest.mark.parametrize("name", MAZE_AGENTS)
def test_fast_maze_trainer_matches_the_python_loop(name: str) -> None:
    runs = []
    for trainer in (train_agent, train_agent_fast):
        agent = make_agent(name, 54, 4, _maze_config(name), np.random.default_rng(5))
        env, evaluation = dyna_maze(max_episode_steps=400), dyna_maze(max_episode_steps=40)
        log = trainer(agent, env, 8, max_steps=300, evaluation=Evaluation(evaluation), seed=5)
        runs.append((log, agent, env.progress(), evaluation.progress()))
    (slow, slow_agent, *slow_envs), (fast, fast_agent, *fast_envs) = runs
    for field in TrainingLog._fields:
        if field != "wall_time":
            np.testing.assert_array_equal(getattr(fast, field), getattr(slow, field), err_msg=field)
    assert slow.successes.any() and (slow.lengths == 300).any()  # both ends of an episode
    np.testing.assert_array_equal(fast_agent.q, slow_agent.q)
    assert (fast_agent.steps, fast_agent.episodes) == (slow_agent.steps, slow_agent.episodes)
    assert fast_agent.planning_updates == slow_agent.planning_updates
    assert fast_agent.rng.random() == slow_agent.rng.random()
    assert fast_envs == slow_envs  # the envs are left where the plain loop leaves them


@pytest.mark.parametrize("name", MAZE_AGENTS)
def test_fast_step_budget_matches_the_python_loop(name: str) -> None:
    runs = []
    for trainer in (train_for_steps, train_for_steps_fast):
        agent = make_agent(name, 54, 4, _maze_config(name), np.random.default_rng(6))
        env = blocking_maze(change_after=1000)  # the walls change mid-run
        runs.append((trainer(agent, env, 3000, seed=6), agent, env.progress()))
    (slow, slow_agent, slow_env), (fast, fast_agent, fast_env) = runs
    np.testing.assert_array_equal(fast, slow)
    assert slow[-1] >= 1 and slow_agent.episodes >= 1
    np.testing.assert_array_equal(fast_agent.q, slow_agent.q)
    assert (fast_agent.steps, fast_agent.episodes) == (slow_agent.steps, slow_agent.episodes)
    assert fast_agent.rng.random() == slow_agent.rng.random()
    assert fast_env == slow_env


_SCRIPT = """
import json, sys
import numpy as np, gymnasium as gym
import skidnav.envs
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import make_agent
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
robot = RobotParams(arena_width=0.3, arena_height=0.3)
grid = Discretization(n_x=10, n_y=10, n_headings=10, arena_width=0.3, arena_height=0.3)
env = gym.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1, slip="slippery",
               robot=robot, discretization=grid, max_episode_steps=80)
agent = make_agent("dyna-full", 1000, 4, {"planning_steps": 5, "kinematic_refit_every": 50},
                   np.random.default_rng(3), task=env.unwrapped.task)
log = train_agent_fast(agent, env, 4, seed=5)
print(json.dumps({"q": agent.q.ravel().tolist(), "lengths": log.lengths.tolist(),
                  "returns": log.returns.tolist(), "refits": agent.kinematic.refits,
                  "coefficients": agent.kinematic.coefficients.ravel().tolist()}))
"""


def _subprocess(disable_jit: bool, script: str = _SCRIPT) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    env.pop("NUMBA_DISABLE_JIT", None)
    if disable_jit:
        env["NUMBA_DISABLE_JIT"] = "1"
    result = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True,
        timeout=240,
    )  # fmt: skip
    return json.loads(result.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def test_identical_without_numba() -> None:
    compiled = _subprocess(disable_jit=False)
    interpreted = _subprocess(disable_jit=True)
    assert compiled["refits"] >= 1
    assert compiled == interpreted


_MAZE_SCRIPT = """
import json
import numpy as np
from skidnav.agents.tabular.fast_training import (
    evaluate_q_fast, train_agent_fast, train_for_steps_fast,
)
from skidnav.agents.tabular.registry import make_agent
from skidnav.envs.mazes import dyna_maze, shortcut_maze
out = {}
for index, name in enumerate(("q-learning", "dyna-q", "dyna-q-plus", "prioritized-sweeping")):
    options = {"planning_steps": 5} if index else {}
    agent = make_agent(name, 54, 4, options, np.random.default_rng(index))
    log = train_agent_fast(agent, dyna_maze(max_episode_steps=300), 4, seed=index)
    cumulative = train_for_steps_fast(agent, shortcut_maze(change_after=200), 500, seed=index)
    out[name] = [agent.q.ravel().tolist(), log.lengths.tolist(), cumulative.tolist(),
                 agent.planning_updates, agent.rng.random()]
print(json.dumps(out))
"""


def test_maze_trainer_identical_without_numba() -> None:
    compiled = _subprocess(disable_jit=False, script=_MAZE_SCRIPT)
    interpreted = _subprocess(disable_jit=True, script=_MAZE_SCRIPT)
    assert compiled == interpreted


def test_agent_without_the_env_geometry_falls_back() -> None:
    grid = Discretization(n_x=10, n_y=10, n_headings=10)
    logs = []
    for trainer in (train_agent, train_agent_fast):
        env = gym.make("skidnav/SkidSteerNav-v0", map_kind="free", discretization=grid,
                       max_episode_steps=50)  # fmt: skip
        agent = make_agent("dyna-full", 1000, 4, None, np.random.default_rng(0))  # no task
        logs.append(trainer(agent, env, 3, seed=0))
    np.testing.assert_array_equal(logs[0].returns, logs[1].returns)
