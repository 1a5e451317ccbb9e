"""The classical family: ``classical``, the navigation stack a roboticist would use instead of a
learner, as a baseline.

A family of its own rather than a member of the policy family: the policies there are
stateless maps from an observation to wheel speeds (a tanh network, the goal tracker), while
this navigator owns a map, a route planner and a controller, each a compiled kernel of its own
package (the house rule: a family owns its planning kernels). Like them it drives the two wheel
speeds over the features and learns nothing; its episodes run in the plain loop, its saved file
runs on the robot as a frozen policy (``skidnav robot run --agent-file``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from numpy.random import SeedSequence

from skidnav.agents.classical.agent import (
    AGENT_NAME,
    SAVE_FORMAT,
    ClassicalAgent,
    load_classical_agent,
    make_classical_agent,
)
from skidnav.agents.classical.config import ClassicalConfig
from skidnav.agents.family import Env, Family, Params, require_wheel_speed_env
from skidnav.agents.interface import AgentConfig
from skidnav.agents.training import train_plain
from skidnav.agents.wheel_policy import WheelSpeedPolicy


def _agent_class(name: str) -> type[ClassicalAgent]:
    return ClassicalAgent


def _config_class(name: str) -> type[AgentConfig]:
    return ClassicalConfig


def _make(
    name: str, env: Env, params: Params, seed: SeedSequence, max_steps: int
) -> ClassicalAgent:
    """The navigator for the navigation env ``env`` (it draws no random number: ``seed`` is
    unused); UserError for an env of other spaces or bad ``params``."""
    require_wheel_speed_env(name, env)
    return make_classical_agent(env, params)


def _load(json_path: Path, meta: Mapping[str, Any], env: Env | None) -> ClassicalAgent:
    return load_classical_agent(json_path, meta)


def _policy(json_path: Path, meta: Mapping[str, Any]) -> WheelSpeedPolicy:
    return load_classical_agent(json_path, meta).policy()


FAMILY: Family[ClassicalAgent] = Family(
    name="classical",
    summary="the classical navigation stack as a baseline: an occupancy grid from the laser, "
    "a Dijkstra route on it inflated by the footprint, a dynamic-window controller",
    agents=(AGENT_NAME,),
    observation="box",
    actions="wheel-speeds",
    agent_class=_agent_class,
    config_class=_config_class,
    make=_make,
    train=train_plain,
    save_formats=(SAVE_FORMAT,),
    load=_load,
    policy=_policy,
    box_observation="features",
)
"""The classical family (:class:`~skidnav.agents.family.Family`)."""
