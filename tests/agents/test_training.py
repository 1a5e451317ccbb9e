"""The plain training loop on Gymnasium's toy-text envs and on the mazes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from skidnav.agents.greedy import greedy_path, greedy_rollout
from skidnav.agents.tabular.registry import available_agents, make_agent
from skidnav.agents.training import Evaluation, TrainingLog, train_agent, train_for_steps
from skidnav.envs.mazes import blocking_maze, dyna_maze


def test_log_fields_on_frozen_lake() -> None:
    env = gym.make("FrozenLake-v1", is_slippery=True)
    agent = make_agent("dyna-q", 16, 4, {"planning_steps": 3}, np.random.default_rng(0))
    log = train_agent(
        agent, env, 40, max_steps=30, evaluation=Evaluation(gym.make("FrozenLake-v1")), seed=0
    )
    assert isinstance(log, TrainingLog)
    assert all(len(column) == 40 for column in log)
    assert log.lengths.max() <= 30
    # Terminated = goal or hole; an episode that did not terminate ran into the 30-step limit.
    assert log.successes[log.returns > 0].all()
    assert (log.successes | (log.lengths == 30)).all()
    assert log.planning_updates.sum() == agent.planning_updates == 3 * log.lengths.sum()
    assert (log.collisions == 0).all() and (log.wall_time > 0).all()
    assert (
        (log.greedy_lengths == -1) | ((log.greedy_lengths >= 1) & (log.greedy_lengths <= 30))
    ).all()


def test_cliff_walking_learns_the_cliff_path() -> None:
    env = gym.make("CliffWalking-v1")
    agent = make_agent(
        "dyna-q", 48, 4, {"planning_steps": 10, "alpha": 0.5}, np.random.default_rng(1)
    )
    evaluation = Evaluation(gym.make("CliffWalking-v1"))
    log = train_agent(agent, env, 60, max_steps=500, evaluation=evaluation)
    assert log.greedy_lengths[-1, 0] == 13  # Q-learning's optimal path along the cliff
    assert np.isnan(log.greedy_costs).all()  # the env reports no cost


@pytest.mark.parametrize("name", available_agents())
def test_every_agent_learns_the_cliff_path(name: str) -> None:
    """Every registered agent on a Gymnasium toy-text env (no navigation geometry): after 100
    episodes (Q-learning needs ~65, the planning agents ~15) the greedy policy has walked the
    13-step cliff path at every one of the last 20 evaluations."""
    options = {"alpha": 0.5} if name == "q-learning" else {"alpha": 0.5, "planning_steps": 10}
    agent = make_agent(name, 48, 4, options, np.random.default_rng(0))
    log = train_agent(
        agent, gym.make("CliffWalking-v1"), 100, max_steps=500,
        evaluation=Evaluation(gym.make("CliffWalking-v1")), seed=0,
    )  # fmt: skip
    assert log.greedy_lengths[-20:, 0].tolist() == [13] * 20


@pytest.mark.parametrize("name", available_agents())
def test_every_agent_takes_six_actions_on_taxi(name: str) -> None:
    agent = make_agent(name, 500, 6, {"alpha": 0.5}, np.random.default_rng(0))
    log = train_agent(agent, gym.make("Taxi-v4"), 3, max_steps=100, seed=0)
    assert agent.q.shape == (500, 6) and agent.steps == log.lengths.sum()
    assert np.count_nonzero(agent.q) > 10


def test_taxi_is_solved_by_dyna_q() -> None:
    env = gym.make("Taxi-v4")
    agent = make_agent(
        "dyna-q", 500, 6, {"planning_steps": 10, "alpha": 0.5}, np.random.default_rng(2)
    )
    log = train_agent(agent, env, 250, max_steps=200, seed=2)
    assert log.successes[-20:].mean() > 0.9
    assert log.returns[-20:].mean() > 0


def test_truncation_by_max_steps_reaches_the_agent() -> None:
    seen: list[tuple[bool, bool]] = []

    class Recorder:
        planning_updates = 0

        def act(self, state: int) -> int:
            return 2  # left: never reaches the goal

        def greedy_action(self, state: int) -> int:
            return 2

        def observe(self, *args: object) -> None:
            seen.append((bool(args[4]), bool(args[5])))

        def end_episode(self) -> None:
            seen.append((False, False))

    log = train_agent(Recorder(), dyna_maze(), 2, max_steps=4, evaluation=Evaluation(dyna_maze()))
    assert log.lengths.tolist() == [4, 4] and not log.successes.any()
    assert seen[:5] == [(False, False)] * 3 + [(False, True), (False, False)]
    assert log.greedy_lengths.tolist() == [[-1], [-1]]
    assert np.isnan(log.greedy_costs).all() and log.greedy_costs.shape == (2, 1)


def test_a_maze_move_costs_one() -> None:
    agent = make_agent("dyna-q", 54, 4, {"planning_steps": 10}, np.random.default_rng(3))
    evaluation = Evaluation(dyna_maze(), [0, 1])
    log = train_agent(agent, dyna_maze(), 12, max_steps=400, evaluation=evaluation, seed=3)
    reached = log.greedy_lengths > 0
    assert reached.any() and not reached.all()
    assert log.greedy_costs.dtype == np.float64 and log.greedy_costs.shape == (12, 2)
    assert np.array_equal(log.greedy_costs[reached], log.greedy_lengths[reached])
    assert np.isnan(log.greedy_costs[~reached]).all()


def test_train_for_steps_counts_cumulative_reward() -> None:
    env = blocking_maze(change_after=300)
    agent = make_agent("dyna-q", 54, 4, {"planning_steps": 10}, np.random.default_rng(0))
    cumulative = train_for_steps(agent, env, 600, seed=0)
    assert cumulative.shape == (600,) and np.all(np.diff(cumulative) >= 0)
    assert cumulative[-1] == agent.episodes  # +1 per goal reached
    assert env.total_steps == 600 and env.walls[3, 8] and not env.walls[3, 0]


class Forward:
    """Always the first action (forward on the skid-steer env, up in the mazes)."""

    def greedy_action(self, state: object) -> int:
        return 0


def test_greedy_path_records_the_reset_pose_and_every_action_pose() -> None:
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1).unwrapped
    poses, reached = greedy_path(Forward(), env, 6, seed=3)
    length = greedy_rollout(Forward(), env, 6, seed=3)
    assert reached == (length >= 0)
    assert poses.shape == ((length if reached else 6) + 1, 3) and poses.dtype == np.float64
    _, info = env.reset(seed=3)
    expected = [info["pose"]]
    for _ in range(len(poses) - 1):
        expected.append(env.step(0)[4]["pose"])
    np.testing.assert_array_equal(poses, np.asarray(expected))
    assert poses[1, 0] > poses[0, 0]  # it moved forward (+x) from the start


def test_greedy_path_of_an_env_without_poses_is_nan_rows() -> None:
    poses, reached = greedy_path(Forward(), dyna_maze(), 4)
    assert poses.shape == (5, 3) and np.isnan(poses).all() and not reached
