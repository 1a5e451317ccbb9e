"""The start plan: the fewest actions from the exact start pose, the calibration of the
convergence test."""

from __future__ import annotations

import itertools

import gymnasium as gym
import numpy as np

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.experiments.reference.start_plan import start_plan
from skidnav.robot.params import RobotParams
from skidnav.sim.navigation import transition
from skidnav.world.discretization import Discretization


def _arena(world_seed: int, map_kind: str = "obstacles") -> gym.Env:  # type: ignore[type-arg]
    robot = RobotParams(arena_width=0.3, arena_height=0.3)
    grid = Discretization(n_x=10, n_y=10, n_headings=10, arena_width=0.3, arena_height=0.3)
    return gym.make("skidnav/SkidSteerNav-v0", map_kind=map_kind, world_seed=world_seed,
                    robot=robot, discretization=grid, max_episode_steps=200)  # fmt: skip


def _reaches(nav: object, actions: tuple[int, ...] | np.ndarray) -> int:
    """Actions until the goal without slip noise, or −1."""
    task = nav.task  # type: ignore[attr-defined]
    pose = nav.start_pose().copy()  # type: ignore[attr-defined]
    noise, log = np.zeros(2 * task.robot.substeps), np.empty((task.robot.substeps, 6))
    for step, action in enumerate(actions, start=1):
        if transition(task, pose, int(action), 0.0, noise, log).terminated:
            return step
    return -1


def test_the_start_plan_is_the_fewest_actions_to_the_goal() -> None:
    checked = 0
    for world_seed in range(6):
        env = _arena(world_seed)
        plan = start_plan(env, [1, 2, 3], 200)
        assert len(plan.actions) > 0, world_seed
        nav = env.unwrapped
        assert _reaches(nav, plan.actions) == len(plan.actions)
        if len(plan.actions) <= 6:  # no shorter sequence of the four actions gets there
            shorter = itertools.product(range(4), repeat=len(plan.actions) - 1)
            assert all(_reaches(nav, sequence) == -1 for sequence in shorter)
            checked += 1
        # Replayed from the evaluation resets: the thesis floor's slip hardly moves it.
        assert (plan.rollout_lengths == len(plan.actions)).sum() >= 2
    assert checked >= 2, "no plan short enough to check against every shorter sequence"


def test_an_unreachable_goal_gives_no_plan() -> None:
    env = _arena(0, "free")
    nav = env.unwrapped
    nav.task.occupancy[:, :] = 1  # every cell a wall: the robot cannot leave its cell
    nav.task.occupancy[nav.task.goal_i, nav.task.goal_j] = 0
    start = nav.start_pose()
    i, j = nav.discretization.cell(start[0], start[1])
    nav.task.occupancy[i, j] = 0
    plan = start_plan(env, [1], 50)
    assert len(plan.actions) == 0 and plan.rollout_lengths.tolist() == [-1]
