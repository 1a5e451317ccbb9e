"""Walls as evidence: a guessed wall cell is weighed against the robot's sightings in it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents import kinematic_planning as kp
from skidnav.agents.planner_learning import planner_observe, weigh_cell
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import make_agent
from skidnav.models.kinematic_prediction import PREDICT_COLLISION, PREDICT_FREE
from skidnav.world.discretization import Discretization


def _planner() -> kp.PlannerArrays:
    grid = Discretization()
    agent = make_agent("dyna-kinematic", grid.n_states, 4, None, discretization=grid)
    return agent.planner  # type: ignore[attr-defined,no-any-return]


def test_a_cell_is_a_wall_while_its_wall_evidence_outweighs_its_free_evidence() -> None:
    planner = _planner()
    weigh_cell(planner, 3, 4, 1, 0)  # one collision guessed into (3, 4)
    assert planner.walls[3, 4] and planner.stale[3, 4]
    assert planner.counters[kp.MAP_CHANGES] == 1
    planner.stale[:] = False
    weigh_cell(planner, 3, 4, 0, 1)  # the robot seen in it: one against one, cleared
    assert not planner.walls[3, 4] and planner.stale[3, 4]
    assert planner.counters[kp.MAP_CHANGES] == 2
    planner.stale[:] = False
    weigh_cell(planner, 3, 4, 1, 0)  # two guesses against one sighting: a wall again
    weigh_cell(planner, 3, 4, 0, 2)  # three sightings against two
    assert not planner.walls[3, 4]
    assert (planner.wall_evidence[3, 4], planner.free_evidence[3, 4]) == (2, 3)
    for _ in range(5):  # a real wall: the robot is never seen in it
        weigh_cell(planner, 7, 7, 1, 0)
    assert planner.walls[7, 7] and planner.walls.sum() == 1
    planner.goals[9, 9] = True  # a known goal is never a wall
    weigh_cell(planner, 9, 9, 4, 0)
    assert not planner.walls[9, 9]


def test_a_step_ending_in_a_guessed_wall_clears_it() -> None:
    """Through the planner's bookkeeping of real steps: the cell of the pose after a step is
    free evidence, so a wrong guess is undone by the robot driving into that cell, and the
    kinematic table around it is recomputed at the episode's end."""
    grid = Discretization()
    agent = make_agent("dyna-kinematic", grid.n_states, 4, None, discretization=grid)
    planner = agent.planner  # type: ignore[attr-defined]
    planner.counters[kp.USE_KINEMATIC] = 1
    x, y = grid.cell_centre(10, 10)
    state = grid.state(x, y, 0.0)
    first = (10 * grid.n_y + 10) * grid.n_headings
    in_cell = slice(first, first + grid.n_headings)  # every heading of cell (10, 10)
    weigh_cell(planner, 10, 10, 1, 0)  # a wrong guess
    agent.end_episode()
    assert (planner.pred_outcome[in_cell] == PREDICT_COLLISION).all()
    planner_observe(
        planner, state, 0, -1.0, state, False, False, np.array([x, y, 0.0]),
        agent.kernel_robot, agent.kernel_grid,  # type: ignore[attr-defined]
    )  # fmt: skip
    assert not planner.walls[10, 10] and planner.free_evidence[10, 10] == 1
    agent.end_episode()
    assert (planner.pred_outcome[in_cell] == PREDICT_FREE).all()


@pytest.mark.parametrize("world", [0, 1])
def test_no_free_cell_stays_a_wall_on_a_slippery_maze(world: int) -> None:
    """dyna-full on a slippery maze (100 episodes of up to 300 actions): wheel-speed loss sends
    colliding sub-steps into cells other than the one the expected motion guesses, so free
    cells beside walls are guessed (before walls were evidence, 16 free cells stayed walls on
    each of these worlds). The robot's sightings clear them: at most one free cell is a wall
    at the end, while over a hundred real walls are known."""
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="maze", world_seed=world, slip="slippery")
    nav = env.unwrapped
    agent = make_agent(
        "dyna-full", nav.discretization.n_states, 4, {"alpha": 0.5, "planning_steps": 10},  # type: ignore[attr-defined]
        np.random.default_rng(0), task=nav.task,  # type: ignore[attr-defined]
    )  # fmt: skip
    train_agent_fast(agent, env, 100, seed=0, max_steps=300)
    free = nav.grid_map.occupancy == 0  # type: ignore[attr-defined]
    planner = agent.planner  # type: ignore[attr-defined]
    assert ((planner.wall_evidence > 0) & free).sum() >= 5  # wrong guesses were made
    assert (planner.walls & free).sum() <= 1
    assert (planner.walls & ~free).sum() >= 100
