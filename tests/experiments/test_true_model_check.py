"""A config asking for the true kinematic model of an agent that cannot plan with it is refused
when it is loaded, before any run: one line naming the agent."""

from __future__ import annotations

from pathlib import Path

import pytest

from skidnav.errors import UserError
from skidnav.studies.loading import parse_grid

CONFIG = """
[experiment]
name = "true-check"
episodes = 2
seeds = 1
presets = ["rough-physics"]

[env]
action = "continuous"
observation = "features"

[[maps]]
kind = "free"

[[agents]]
name = "{agent}"
label = "planner"
params = {{ kinematic_model = "{model}" }}
"""


def test_mppi_with_the_true_model_is_refused_at_load() -> None:
    with pytest.raises(UserError) as error:
        parse_grid(CONFIG.format(agent="mppi-kinematic", model="true"), Path("c.toml"))
    message = str(error.value)
    assert "\n" not in message and message.startswith(
        "expected kinematic_model 'learned' or 'prior', got 'true' in c.toml: agent 'planner' ("
    )
    assert message.endswith("which mppi-kinematic cannot take)")


def test_the_learned_and_prior_models_load() -> None:
    for model in ("learned", "prior"):
        loaded = parse_grid(CONFIG.format(agent="mppi-kinematic", model=model), Path("c.toml"))
        assert loaded.study.kind == "experiment"
