"""The weights' temperature is in seconds: a 4-s horizon that gains as little over standing still
as the stalled planner's did (docs/agents/mppi-kinematic.md, "The stall") still drives, at 1-s
actions as at 0.1-s ones. A temperature of one control step whatever the period made the weights
ten times flatter at 1-s actions, and the plan averaged to standing still."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.costmap import empty_cost_map
from skidnav.agents.mpc.dynamics import fixed_dynamics
from skidnav.agents.mpc.planner import MPPIPlanner
from skidnav.agents.mpc.planning_robot import map_costs
from skidnav.envs.navigation import with_control_period
from skidnav.models.kinematic_regression import nominal_coefficients
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization

GRID = Discretization()
GAIN = 0.4
"""Value [s] a second of full speed ahead gains: the stall's 1.4–1.7 over a 4-s horizon."""


def first_commands(period: float, config: MPPIConfig, steps: int = 8) -> np.ndarray:
    """The planner's commands (steps, 2) [rad/s] from rest at one pose, facing +x, under a
    value that falls by :data:`GAIN` seconds per second of driving ahead (the goal far away)."""
    robot = with_control_period(RobotParams(), period)
    speed = robot.wheel_radius * robot.wheel_speed  # [m/s] full speed ahead
    width = GRID.arena_width / (GRID.n_x - 1)
    cells = np.arange(GRID.n_x)[:, None, None] * np.ones((1, GRID.n_y, GRID.n_headings))
    seconds = 100.0 - GAIN * (cells + 0.5) * width / speed
    cost_map = empty_cost_map(GRID.n_x, GRID.n_y, (seconds / period).ravel())
    costs = map_costs(config, robot, (GRID.n_x - 1, GRID.n_y - 1))
    dynamics = fixed_dynamics(np.tile(nominal_coefficients(robot), (GRID.n_regions, 1)))
    planner = MPPIPlanner(
        config, robot.kernel_constants(), GRID.grid_shape(), np.random.default_rng(0)
    )
    pose = np.array([0.2, 0.25, 0.0])
    return np.array([planner.step(pose, dynamics, cost_map, costs) for _ in range(steps)])


@pytest.mark.parametrize(("period", "horizon", "steps"), [(0.1, 40, 30), (1.0, 4, 8)])
def test_a_small_gain_of_driving_is_followed_at_any_control_period(
    period: float, horizon: int, steps: int
) -> None:
    """Within 3 s (0.1-s actions) or 8 s (1-s actions) from rest the plan drives ahead at more
    than 0.6 Ω (measured: 1.2 and 1.57 rad/s of Ω = 1.7)."""
    config = MPPIConfig(horizon=horizon, sample_uncertainty=False)
    commands = first_commands(period, config, steps)
    assert commands[-steps // 3 :].mean() > 0.6 * RobotParams().wheel_speed, commands


def test_one_control_step_of_temperature_at_1_s_actions_barely_drives() -> None:
    """The mechanism: the same planner with λ = 1 s, one control step of 1 s (the temperature
    before it was in seconds), still crawls after 8 s (measured: 0.5 rad/s)."""
    config = MPPIConfig(horizon=4, sample_uncertainty=False, temperature=1.0)
    assert first_commands(1.0, config)[-4:].mean() < 0.4 * RobotParams().wheel_speed
