"""mppi-kinematic with a robot of a footprint (the Jackal): its rollouts collide as the simulator
does, its cost-to-go plans in the footprint's configuration space, its laser map reads a field
of view narrower than a full turn, and its route may run at the learned speed."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import gymnasium
import numpy as np
import pytest

from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.dynamics import top_speeds
from skidnav.agents.mpc.loading import load_mppi_agent
from skidnav.agents.mpc.observations import pose_of, ranges_of
from skidnav.agents.training import run_episode
from skidnav.envs.navigation import with_control_period
from skidnav.models.kinematic_prediction import PREDICT_COLLISION
from skidnav.robot.presets import JACKAL
from skidnav.world.barn import load_barn_world
from skidnav.world.discretization import Discretization
from tests.agents.mpc.support import nav_env
from tests.agents.mpc.test_mppi_costs import costs_of

GRID = Discretization(n_x=21, n_y=21, arena_width=3.0, arena_height=3.0)
"""3 m × 3 m in cells of 0.15 m, BARN's."""
ROBOT = dataclasses.replace(with_control_period(JACKAL, 0.1), arena_width=3.0, arena_height=3.0)
"""The Jackal (0.458 m × 0.416 m, 2 m/s) at 0.1-s actions on that arena."""
POINT = dataclasses.replace(ROBOT, footprint_length=0.0, footprint_width=0.0)
"""The same robot colliding by its centre."""
NARROW = ((8, 10), (11, 10))
"""Two wall cells 0.45 m apart, centre to centre: a gap of 0.30 m between their discs, wider
than a point and narrower than the Jackal (0.416 m)."""
WIDE = ((6, 10), (14, 10))
"""Two wall cells 1.2 m apart: a gap of 1.05 m."""


def agent_on(
    robot: object, walls: tuple[tuple[int, int], ...], **options: object
) -> MPPIKinematicAgent:
    """An agent of ``robot`` on :data:`GRID` (goal cell (10, 18)) that knows the cells
    ``walls`` for walls (two collisions each: blocked), planning with the datasheet's mean."""
    settings = {"samples": 2, "horizon": 10, "cost_to_go": "cells", "footprint_padding": 0.0,
                "collision_cost": 100.0, "sample_uncertainty": False, **options}  # fmt: skip
    agent = MPPIKinematicAgent(
        robot, GRID, (10, 18), MPPIConfig(**settings), np.random.default_rng(0)
    )  # type: ignore[arg-type]
    for cell in walls:
        agent.evidence.hits[cell] = 2
    agent.evidence.reweigh(agent.evidence.coefficients)
    assert all(agent.evidence.cost_map.blocked[cell] for cell in walls)
    return agent


def test_a_sequence_through_a_gap_narrower_than_the_footprint_is_a_collision() -> None:
    """Full speed ahead from (1.5 m, 0.95 m), facing +y, through the middle of the gap to the
    goal cell: the point robot gets there in 9 control steps; the Jackal's rectangle meets the
    walls' discs (the simulator's rule), pays C and stays stuck; through the wide gap it is as
    fast as the point."""
    start = np.array([1.5, 0.95, math.pi / 2])
    ahead = np.full((1, 10, 2), ROBOT.wheel_speed)
    point = costs_of(agent_on(POINT, NARROW), start, ahead)[0]
    jackal = costs_of(agent_on(ROBOT, NARROW), start, ahead)[0]
    assert point == 9.0  # 1.8 m at 0.2 m per control step: in the goal cell, no cost
    assert jackal > 100.0  # at least one collision of C = 100, and no goal
    assert costs_of(agent_on(ROBOT, WIDE), start, ahead)[0] == point


def test_the_cost_to_go_is_dilated_by_the_footprint() -> None:
    """The narrow gap is open to the point robot's route and closed to the Jackal's: its cells
    are lethal (within the inscribed radius of a wall's disc), its route goes around the two
    walls, longer but finite; the lattice of the states mode treats the lethal cells as walls."""
    point, jackal = agent_on(POINT, NARROW), agent_on(ROBOT, NARROW)
    gap = ((9, 10), (10, 10))
    assert not any(point.evidence.cost_map.lethal[cell] for cell in gap)
    assert all(jackal.evidence.cost_map.lethal[cell] for cell in gap)
    assert (point.evidence.cost_map.lethal == point.evidence.cost_map.blocked).all()
    assert (jackal.evidence.cost_map.lethal >= jackal.evidence.cost_map.blocked).all()
    below = (10, 8)  # two cells short of the gap, the goal ten cells straight ahead
    straight = point.evidence.cost_map.cost_to_go[below]
    assert math.isclose(straight, 10 * 0.15 / 0.2, rel_tol=1e-12)
    around = jackal.evidence.cost_map.cost_to_go[below]
    assert straight < around < straight + 10.0  # a detour of a few cells, no lethal cell entered
    states = agent_on(ROBOT, NARROW, cost_to_go="states")
    lattice = states.evidence.lattice
    for i, j in gap:
        first = (i * GRID.n_y + j) * GRID.n_headings
        assert (lattice.outcome[first : first + GRID.n_headings] == PREDICT_COLLISION).all()


@pytest.fixture(scope="module")
def barn_env() -> gymnasium.Env:
    """World 0 of BARN as the study drives it: the Jackal, a 271-ray 270° laser of 10 m."""
    world = load_barn_world(0)
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=world.map.grid, start_pose=world.start_pose,
        goal_disc=(*world.goal, world.goal_radius), discretization=world.discretization,
        robot="jackal", control_period=0.1, slip="nominal", lidar_rays=271, lidar_range=10.0,
        lidar_fov=1.5 * math.pi, action="continuous", observation="features",
    )  # fmt: skip


def test_the_laser_map_reads_the_features_field_of_view(barn_env: gymnasium.Env) -> None:
    """The agent takes the env's 270° layout: every reading that ends marks a wall cell of the
    world, or a cell on the arena's border where the lidar stops too. Read as a full turn, the
    same readings would end in free cells inside the arena."""
    agent = MPPIKinematicAgent.from_env(barn_env, MPPIConfig(cost_to_go="cells"))
    assert agent.lidar_fov == 1.5 * math.pi
    observation, _ = barn_env.reset(seed=0)
    pose, ranges = pose_of(observation, 271), ranges_of(observation, 271)
    walls = np.asarray(barn_env.unwrapped.grid_map.occupancy, dtype=bool).copy()
    walls[[0, -1], :] = walls[:, [0, -1]] = True  # the border
    evidence = agent.evidence
    evidence.record_readings(pose, ranges, 10.0, agent.lidar_fov)
    assert evidence.ray_ends.sum() > 100 and not evidence.ray_ends[~walls].any()
    evidence.ray_ends[...] = 0
    evidence.record_readings(pose, ranges, 10.0, 2.0 * math.pi)
    assert evidence.ray_ends[~walls].any()


def test_the_field_of_view_is_saved_and_an_older_file_had_a_full_turn(
    barn_env: gymnasium.Env, tmp_path: Path
) -> None:
    agent = MPPIKinematicAgent.from_env(barn_env, MPPIConfig(cost_to_go="cells"))
    agent.save(tmp_path / "agent")
    assert load_mppi_agent(tmp_path / "agent").lidar_fov == 1.5 * math.pi
    meta = json.loads((tmp_path / "agent.json").read_text())
    del meta["lidar_fov"]
    meta["version"] = 3
    (tmp_path / "agent.json").write_text(json.dumps(meta))
    assert load_mppi_agent(tmp_path / "agent").lidar_fov == 2.0 * math.pi


def test_the_route_runs_at_the_learned_speed_on_a_slow_floor() -> None:
    """On the ice the model learns a robot slower than the datasheet's: with
    ``route_speed = "learned"`` the cells' cost-to-go counts control steps at that speed once
    refitted (a metre of progress worth more steps), with "nominal" at the datasheet's."""
    costs, agents = {}, {}
    for speed in ("nominal", "learned"):
        env = nav_env(slip="ice-physics")
        nav = env.unwrapped
        agent = MPPIKinematicAgent(
            nav.robot, nav.discretization, nav.grid_map.goal,
            MPPIConfig(samples=16, horizon=10, cost_to_go="cells", route_speed=speed),
            np.random.default_rng(0),
        )  # fmt: skip
        nominal = agent.costs.step_length
        observation, _ = env.reset(seed=0)
        run_episode(agent, env, observation, 60)
        assert agent.model.refits >= 1
        costs[speed], agents[speed] = (nominal, agent.costs.step_length), agent
    assert costs["nominal"][1] == costs["nominal"][0]
    learned = agents["learned"]
    fastest = top_speeds(learned.dynamics.mean, learned.robot.wheel_speed)
    assert fastest is not None
    assert costs["learned"][1] == fastest[0] * learned.robot.action_duration
    assert costs["learned"][1] < 0.8 * costs["learned"][0]
