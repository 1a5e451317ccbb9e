"""mppi-kinematic's laser-built map: the readings of the feature observations mark the cells
their rays crossed free and the cells where they ended walls; never a free cell blocked, and
behind a wall it gets to the goal without running into it."""

from __future__ import annotations

import numpy as np

from skidnav.agents.greedy import greedy_run
from skidnav.agents.mpc.laser import record_rays
from skidnav.agents.mpc.training import train_mppi
from skidnav.sim.lidar import lidar_ranges
from skidnav.world.discretization import Discretization
from tests.agents.mpc.support import WALL_BETWEEN, SealedEnv, agent_for, nav_env


def test_rays_end_in_wall_cells_and_cross_only_free_ones() -> None:
    """Readings of the simulated lidar from a few poses of a 1 m × 1 m arena with a wall column
    at x in [0.7, 0.8) m: every end cell is a wall (or the border), every crossed cell free, and
    the ray straight ahead ends in the wall's cell."""
    shape = Discretization(n_x=11, n_y=11, arena_width=1.0, arena_height=1.0).grid_shape()
    walls = np.zeros((11, 11), dtype=np.uint8)
    walls[7, :] = 1
    walls[[0, 10], :] = walls[:, [0, 10]] = 1  # the border
    ends = np.zeros((11, 11), dtype=np.int64)
    crossings, hits = np.zeros_like(ends), np.zeros_like(ends)
    ranges = np.empty(16)
    for x, y, heading in [(0.25, 0.6, 0.0), (0.45, 0.3, 0.7), (0.55, 0.55, -2.0)]:
        lidar_ranges(walls, 1.0, 1.0, x, y, heading, 0.4, ranges)
        assert record_rays(x, y, heading, ranges, 0.4, shape, ends, crossings, hits)
    assert ends.sum() > 0 and crossings.sum() > 0
    assert (walls[ends > 0] == 1).all()
    assert (walls[crossings > 0] == 0).all()
    assert ends[7, 6] >= 1  # straight ahead of the first pose, 0.45 m away


def test_a_reading_at_the_range_limit_marks_no_wall() -> None:
    grid = Discretization(n_x=11, n_y=11, arena_width=1.0, arena_height=1.0).grid_shape()
    ends = np.zeros((11, 11), dtype=np.int64)
    crossings, hits = np.zeros_like(ends), np.zeros_like(ends)
    ranges = np.full(4, 0.15)  # four rays from a cell's centre into its four neighbours
    changed = record_rays(0.35, 0.35, 0.0, ranges, 0.15, grid, ends, crossings, hits)
    assert not changed and ends.sum() == 0
    assert crossings.sum() == 4 and crossings[[4, 2, 3, 3], [3, 3, 4, 2]].all()


def test_on_features_it_maps_the_wall_before_touching_it_and_on_poses_from_collisions_only() -> (
    None
):
    """The same agent seed and world through an env that exposes only reset, step and the
    spaces: with feature observations it blocks most of the wall's cells, never a free one, and
    reaches the goal in its first episode without a collision; over poses it learns no reading
    and finds the wall by running into it."""
    results = {}
    for observation in ("features", "pose"):
        env = nav_env(WALL_BETWEEN, observation=observation)
        agent = agent_for(env, seed=0)
        log = train_mppi(agent, SealedEnv(env), 1, max_steps=600, seed=0)
        walls = env.unwrapped.grid_map.occupancy
        blocked = agent.evidence.cost_map.blocked
        assert not blocked[~walls].any()
        results[observation] = log, blocked, agent.evidence
    log, blocked, evidence = results["features"]
    assert log.successes[0] and log.collisions[0] == 0
    assert blocked[6, 3:8].all()  # the wall between start and goal
    assert evidence.ray_ends.sum() > 0 and evidence.ray_crossings.sum() > 0
    log, blocked, evidence = results["pose"]
    assert log.collisions[0] >= 1
    assert evidence.ray_ends.sum() == 0 and evidence.ray_crossings.sum() == 0


def test_crossing_rays_undo_a_wrong_collision_guess() -> None:
    """A cell wrongly guessed a wall (three hits, blocked) that the lidar then sees through
    stops being blocked."""
    env = nav_env(WALL_BETWEEN, observation="features")
    agent = agent_for(env, seed=0)
    agent.evidence.hits[3, 5] = 3  # just ahead of the start (1, 5), a free cell
    agent.evidence.reweigh(agent.dynamics.mean)
    assert agent.evidence.cost_map.blocked[3, 5]
    observation, _ = env.reset(seed=0)
    for _ in range(3):
        action = np.zeros(2)
        next_observation, reward, terminated, truncated, info = env.step(action)
        agent.observe(observation, action, reward, next_observation, terminated, truncated, info)
        observation = next_observation
    assert agent.evidence.ray_crossings[3, 5] >= 4
    assert not agent.evidence.cost_map.blocked[3, 5]


def test_a_frozen_planner_sees_walls_it_never_learned_and_forgets_them_after_a_rollout() -> None:
    """A planner frozen before any episode (the true model, an empty map) marks the wall from
    its lidar during its rollout and drives around it to the goal, while the agent's own map
    stays empty; the next rollout starts again from the frozen map. Over poses, with no
    readings, the frozen map stays empty and the rollout runs into the wall until it ends."""
    env = nav_env(WALL_BETWEEN, observation="features")
    agent = agent_for(env, seed=0, true=True)
    rollout = greedy_run(agent, SealedEnv(env), 600, seed=0)
    assert rollout.length > 0  # reached the goal behind the wall
    assert agent.evidence.ray_ends.sum() == 0 and agent.steps == 0  # nothing learned
    policy = agent.policy(seed=0)
    observation, _ = env.reset(seed=0)
    policy.wheel_speeds(observation)
    assert policy.evidence.ray_ends.sum() > 0
    policy.reset()
    assert policy.evidence.ray_ends.sum() == 0 and policy.evidence.ray_crossings.sum() == 0
    blind = nav_env(WALL_BETWEEN, observation="pose")
    blind_agent = agent_for(blind, seed=0, true=True)
    assert greedy_run(blind_agent, SealedEnv(blind), 600, seed=0).length == -1
