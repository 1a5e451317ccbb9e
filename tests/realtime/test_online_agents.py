"""``skidnav robot run --agent`` takes the agents that learn online: the tabular family's, read
from the catalog; any other name is refused in one line before the robot is contacted."""

from __future__ import annotations

import pytest

from skidnav.agents.catalog import family
from skidnav.errors import UserError
from skidnav.realtime.control.run import online_agent_class


def test_every_tabular_agent_and_mppi_learns_online_on_the_robot() -> None:
    for name in (*family("tabular").agents, "mppi-kinematic"):
        assert online_agent_class(name).name == name


@pytest.mark.parametrize("name", ["linear-q", "goal-tracker"])
def test_other_families_are_refused_naming_the_online_agents(name: str) -> None:
    with pytest.raises(UserError, match="does not learn online on the robot: expected one of q-"):
        online_agent_class(name)
    with pytest.raises(UserError, match="unknown agent 'nope'"):
        online_agent_class("nope")
