"""MPPI's plan update at the wheels' limits: with the clipped perturbations a plan at full speed
is pulled back inside the limit even when full speed is best; with the perturbations as drawn
it stays there (``plan_update``, docs/agents/mppi-kinematic.md)."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.agents.mpc.config import MPPIConfig
from tests.agents.mpc.support import agent_for, nav_env


@pytest.mark.parametrize("plan_update", ["clipped", "drawn"])
def test_a_plan_at_full_speed_where_full_speed_is_best(plan_update: str) -> None:
    agent = agent_for(nav_env(), samples=256, horizon=20, plan_update=plan_update)
    planner, limit = agent.planner, agent.robot.wheel_speed
    commands = []
    for _ in range(5):
        planner.plan[...] = limit  # full speed ahead on both wheels
        controls, perturbation, _ = planner.sample()
        planner.draw_costs[...] = -controls.sum(axis=(1, 2))  # the faster, the cheaper
        commands.append(planner.update(perturbation))
    commanded = np.array(commands)
    if plan_update == "drawn":  # the draws beyond the limit cost what the limit costs
        assert np.array_equal(commanded, np.full_like(commanded, limit))
    else:  # only the inward half of the clipped draws is non-zero
        assert commanded.max() < limit and commanded.mean() < 0.98 * limit


def test_plan_update_is_checked() -> None:
    with pytest.raises(ValueError, match="expected plan_update in"):
        MPPIConfig(plan_update="raw")
    with pytest.raises(ValueError, match="expected plan_update 'clipped' with precision 'float32'"):
        MPPIConfig(plan_update="drawn", precision="float32")
