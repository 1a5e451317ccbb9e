"""What the rollouts pay and what the cost-to-go says: collisions with known walls, the goal,
wall evidence that can be cleared, the lattice's Bellman equation and its local refresh."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.costmap import interpolated_state_value
from skidnav.agents.mpc.lattice import goal_distances, refresh_table, state_values
from skidnav.agents.mpc.rollouts import RolloutDraws, rollout_costs
from skidnav.models.kinematic_prediction import PREDICT_COLLISION
from tests.agents.mpc.support import agent_for, nav_env


def costs_of(agent: MPPIKinematicAgent, pose: np.ndarray, controls: np.ndarray) -> np.ndarray:
    """The rollout costs of ``controls`` (K, H, 2) from ``pose`` through the mean model."""
    k, h = controls.shape[:2]
    out = np.zeros(k)
    draws = RolloutDraws(np.zeros((k, 5)), np.zeros((k, h, 3)), 0.0, 1)
    rollout_costs(
        pose, controls, draws, agent.dynamics, agent.evidence.cost_map, agent.costs,
        agent.kernel_robot, agent.kernel_grid, out,
    )  # fmt: skip
    return out


def test_a_known_wall_costs_each_attempt_and_the_goal_ends_the_sequence() -> None:
    env = nav_env()
    agent = agent_for(env, true=True, horizon=10)
    grid = env.unwrapped.discretization
    x, y = grid.cell_centre(5, 5)  # the cell left of the wall (6, 3..7)
    wall = np.array([x + 0.024, y, 0.0])  # 2 mm from the wall, facing it
    forward = np.full((1, 10, 2), 1.7)
    standing = np.zeros((1, 10, 2))
    before = costs_of(agent, wall, np.concatenate([forward, standing]))
    agent.evidence.hits[6, 5] = 2  # two collisions: blocked (2 > 0 passes + 1)
    agent.evidence.reweigh(agent.dynamics.mean)
    assert agent.evidence.cost_map.blocked[6, 5]
    after = costs_of(agent, wall, np.concatenate([forward, standing]))
    assert after[0] > before[0] + 9 * 10 * 2 / 3  # 10 attempts at C · p = 10 · 2/3 each
    assert after[1] > before[1]  # standing there is worth less now: the route goes around
    gx, gy = grid.cell_centre(*env.unwrapped.grid_map.goal)
    near_goal = np.array([gx - 0.045, gy, 0.0])  # 1.9 cm from the goal cell
    steps = math.ceil((0.045 - grid.cell_width / 2) / (0.0225 * 1.7 * 0.1))  # of 3.8 mm
    assert costs_of(agent, near_goal, forward)[0] == steps  # the steps into the goal, no more


def test_wall_evidence_is_weighed_and_a_wrong_guess_is_cleared() -> None:
    agent = agent_for(nav_env(), free_prior=1.0)
    evidence = agent.evidence
    evidence.hits[3, 3] = 1
    evidence.reweigh(agent.dynamics.mean)
    assert not evidence.cost_map.blocked[3, 3]  # one collision against the prior's pass
    assert evidence.cost_map.wall_probability[3, 3] == 0.5
    evidence.hits[3, 3] = 2
    evidence.reweigh(agent.dynamics.mean)
    assert evidence.cost_map.blocked[3, 3]
    log = np.array([[0.0, 1.7, 1.7, 0.0, 0.0, 0.0]] * 2)  # two sub-steps standing in (3, 3)
    x, y = nav_env().unwrapped.discretization.cell_centre(3, 3)
    evidence.record_step(np.array([x, y, 0.0]), (1.7, 1.7), log, False, agent.dynamics)
    assert evidence.passes[3, 3] == 2 and not evidence.cost_map.blocked[3, 3]
    assert evidence.cost_map.wall_probability[3, 3] == 2 / (2 + 2 + 1)
    assert evidence.cost_map.wall_probability[4, 4] == 0.0  # never hit: optimism


def test_the_lattice_values_meet_their_bellman_equation() -> None:
    agent = agent_for(nav_env())
    agent.evidence.hits[6, 3:8] = 3
    agent.evidence.reweigh(agent.dynamics.mean)
    lattice, cost_map = agent.evidence.lattice, agent.evidence.cost_map
    value, grid = lattice.value, agent.kernel_grid
    goal = agent.goal
    goal_states = (goal[0] * grid.n_y + goal[1]) * grid.n_headings + np.arange(grid.n_headings)
    assert (value[goal_states] == 0.0).all() and np.isfinite(value).all()
    cells = np.arange(value.size) // grid.n_headings
    entering = 10.0 * cost_map.wall_probability.ravel()
    backed = (
        lattice.action_steps[None, :]
        + 10.0 * (lattice.outcome == PREDICT_COLLISION)
        + np.where(
            cells[lattice.next_state] != cells[:, None], entering[cells[lattice.next_state]], 0
        )
        + value[lattice.next_state]
    ).min(axis=1)
    reached = value < value.max()
    reached[goal_states] = False
    assert np.allclose(value[reached], backed[reached])
    start = (2 * grid.n_y + 5) * grid.n_headings  # the start cell, left of the wall
    beyond = (9 * grid.n_y + 5) * grid.n_headings  # the cell right of the wall, by the goal
    assert (
        value[start : start + grid.n_headings].min()
        > value[beyond : beyond + grid.n_headings].max()
    )


def test_the_lattice_does_not_squeeze_between_walls_meeting_at_a_corner() -> None:
    """Walls on the diagonal cells (i, i − 2), from the bottom border to the top-right corner,
    part the start's side from the goal's, joined only where two walls meet at a corner: no
    state of the start's side reaches the goal through the lattice (each gets the unreached
    value, the largest reached one plus ``blocked_cost``)."""
    agent = agent_for(nav_env())
    grid = agent.kernel_grid
    for i in range(2, grid.n_x):
        agent.evidence.hits[i, i - 2] = 3
    agent.evidence.reweigh(agent.dynamics.mean)
    value = agent.evidence.lattice.value
    cells = np.arange(grid.n_x * grid.n_y)
    i, j = cells // grid.n_y, cells % grid.n_y
    start_side = np.repeat(j > i - 2, grid.n_headings)
    goal_side = np.repeat(j < i - 2, grid.n_headings)
    unreached = value.max()  # the largest reached value plus blocked_cost = 1000
    assert agent.goal[1] < agent.goal[0] - 2 and value[goal_side].min() == 0.0
    assert (value[goal_side] < unreached).mean() > 0.9
    assert (value[start_side] == unreached).all()


def test_a_local_refresh_equals_a_full_one() -> None:
    agent = agent_for(nav_env())
    evidence = agent.evidence
    for cells in ([(6, 5)], [(6, 4), (6, 6)], [(2, 2)]):
        for cell in cells:
            evidence.hits[cell] += 3
        evidence.reweigh(agent.dynamics.mean)  # local: the cells around the new walls
    local = evidence.lattice.next_state.copy(), evidence.lattice.outcome.copy()
    refresh_table(
        evidence.lattice, agent.dynamics.mean, evidence.cost_map.blocked, agent.goal,
        evidence.lattice_robots, agent.kernel_grid, np.ones_like(evidence.cost_map.blocked),
    )  # fmt: skip
    assert np.array_equal(local[0], evidence.lattice.next_state)
    assert np.array_equal(local[1], evidence.lattice.outcome)
    values = evidence.lattice.value.copy()
    state_values(
        evidence.lattice, evidence.cost_map.wall_probability, *agent.goal, 10.0, 1000.0,
        agent.kernel_grid,
    )  # fmt: skip
    assert np.array_equal(values, evidence.lattice.value)


def test_a_repair_after_wall_probabilities_change_equals_a_search_bit_for_bit() -> None:
    """The values repaired around the cells whose wall probability changed (rising, falling, to
    0 and to near 1, one cell or many, the goal's among them) are a whole search's, bit for bit;
    the repair of one cell's change touches a small part of the lattice, and a wide change is
    searched again."""
    agent = agent_for(nav_env())
    evidence, grid = agent.evidence, agent.kernel_grid
    evidence.hits[6, 3:8] = 3  # the wall: lethal cells, so some states do not reach the goal
    evidence.reweigh(agent.dynamics.mean)
    probability = evidence.cost_map.wall_probability
    rng = np.random.default_rng(0)
    searched = np.zeros_like(evidence.distance)
    works: list[int] = []
    for round_ in range(60):
        count = 1 if round_ % 3 else int(rng.integers(2, 40))
        cells = rng.integers(0, [grid.n_x, grid.n_y], size=(count, 2))
        lethal = evidence.cost_map.lethal[cells[:, 0], cells[:, 1]]
        cells = cells[~lethal]  # a lethal cell's change refreshes the lattice: not a repair
        levels = rng.choice([0.0, 0.3, 0.6, 0.95, rng.uniform()], size=len(cells))
        if round_ == 7:
            cells, levels = np.array([agent.goal]), np.array([0.5])
        probability[cells[:, 0], cells[:, 1]] = levels
        work = evidence.update_values(refreshed=False)
        goal_distances(
            evidence.lattice, probability, *agent.goal, evidence.costs.collision_cost, grid,
            searched,
        )  # fmt: skip
        assert np.array_equal(evidence.distance, searched)
        assert np.array_equal(evidence.supported, searched)
        works.append(work if count == 1 else -work)
    assert np.isinf(searched).any() and np.isfinite(searched).mean() > 0.5
    values = evidence.lattice.value.copy()
    state_values(
        evidence.lattice, probability, *agent.goal, evidence.costs.collision_cost,
        evidence.costs.blocked_cost, grid,
    )  # fmt: skip
    assert np.array_equal(values, evidence.lattice.value)
    single = [work for work in works if work >= 0]
    assert np.median(single) < 0.1 * searched.size and max(single) > 0
    assert -searched.size in works  # a change too wide to repair: searched again


def test_the_interpolated_value_is_the_state_value_at_a_state_centre() -> None:
    agent = agent_for(nav_env())
    grid, discretization = agent.kernel_grid, agent.discretization
    cost_map = agent.evidence.cost_map
    for i, j, h in [(3, 4, 0), (8, 2, 7), (5, 8, 19)]:
        x, y = discretization.cell_centre(i, j)
        heading = discretization.heading_centre(h)
        state = discretization.state(x, y, heading)
        assert (
            interpolated_state_value(x, y, heading, cost_map, grid) == (cost_map.state_value[state])
        )


@pytest.mark.parametrize("risk", ["mean", "worst"])
def test_a_sequence_costs_the_mean_or_the_worst_of_its_model_draws(risk: str) -> None:
    """With M = 3 draws per sequence each sequence's cost is the mean (or the largest) of its
    three rollouts' costs, and the draws of one sequence differ (the model is uncertain)."""
    env = nav_env()
    agent = agent_for(env, seed=0, model_draws=3, risk=risk, samples=16, horizon=20)
    agent.act(np.array([0.1, 0.25, 0.0]))
    draws = agent.planner.draw_costs.reshape(16, 3)
    expected = draws.max(axis=1) if risk == "worst" else draws.mean(axis=1)
    assert agent.planner.costs == pytest.approx(expected, rel=1e-12)
    assert (draws.max(axis=1) > draws.min(axis=1)).any()
