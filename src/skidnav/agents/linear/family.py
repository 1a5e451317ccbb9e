"""The linear family: tile-coded features of a ``Box`` observation, learned step by step.

Semi-gradient Q-learning and SARSA, Linear Dyna with its linear model, and Linear Dyna planning
through the learned kinematic model (``linear-dyna-kinematic``), trained by the plain loop
(:func:`~skidnav.agents.training.train_agent`). A saved agent over the feature observation drives
the robot frozen, by the wheel speeds of its greedy actions
(:mod:`skidnav.agents.discrete_policy`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from numpy.random import SeedSequence

from skidnav.agents.discrete_policy import discrete_policy
from skidnav.agents.family import (
    Env,
    Family,
    Params,
    constructor_context,
    discrete_actions,
    observation_space,
)
from skidnav.agents.interface import AgentConfig
from skidnav.agents.linear.agent import SAVE_FORMAT, LinearAgent
from skidnav.agents.linear.config import LinearDynaConfig
from skidnav.agents.linear.registry import (
    CONTINUOUS_AGENT_MODULES,
    linear_agent_class,
    load_linear_agent,
    make_linear_agent,
)
from skidnav.agents.training import train_agent
from skidnav.agents.wheel_policy import WheelSpeedPolicy

GOAL_DIMENSIONS = 3
"""How many of the steering features (:meth:`~skidnav.sim.features.PoseFeatures.
steering_dimensions`: the goal's distance and bearing first) an agent with a linear model of
its features tiles by default: the model holds n_features² weights per action, so the goal's
three alone (5³ × 8 = 1,000 features with the default tiles and tilings: a 32 MB model)."""


def _config_class(name: str) -> type[AgentConfig]:
    return linear_agent_class(name).config_class


def _make(name: str, env: Env, params: Params, seed: SeedSequence, max_steps: int) -> LinearAgent:
    space = observation_space(name, env, gymnasium.spaces.Box)
    cls = linear_agent_class(name)
    context = constructor_context(cls, env, params)
    rng = np.random.default_rng(seed)
    chosen = tiled_by_default(cls, env, params)
    return make_linear_agent(name, space, discrete_actions(name, env), chosen, rng, **context)


def tiled_by_default(cls: type[LinearAgent], env: Env, params: Params) -> dict[str, Any]:
    """``params``, with the features a tile coder takes by default on the skid-steer env's
    feature observation when they name no ``dimensions``: the steering features
    (:meth:`~skidnav.sim.features.PoseFeatures.steering_dimensions`: all 15 default features
    would need ~10^11 tiles), the goal's alone for an agent with a linear model of its features
    (:data:`GOAL_DIMENSIONS`); unchanged on any other observation."""
    nav = env.unwrapped
    features: Any = getattr(nav, "features", None)
    tiled = "dimensions" in params or getattr(nav, "observation_kind", None) != "features"
    if tiled or features is None:
        return dict(params)
    dimensions = list(features.steering_dimensions())
    if issubclass(cls.config_class, LinearDynaConfig):
        dimensions = dimensions[:GOAL_DIMENSIONS]
    return {**params, "dimensions": dimensions}


def _load(json_path: Path, meta: Mapping[str, Any], env: Env | None) -> LinearAgent:
    return load_linear_agent(json_path)


def _policy(json_path: Path, meta: Mapping[str, Any]) -> WheelSpeedPolicy:
    """The saved agent, frozen, driving by the wheel speeds of its greedy actions
    (:func:`~skidnav.agents.discrete_policy.discrete_policy`)."""
    agent = load_linear_agent(json_path)  # its loader bounds the file's sizes
    bounds = (agent.low, agent.high)
    return discrete_policy(lambda: agent, json_path, agent.name, bounds, agent.n_actions)


FAMILY: Family[LinearAgent] = Family(
    name="linear",
    summary="tile-coded features of the continuous pose or of the goal and laser features, "
    "learned step by step; Linear Dyna plans with a linear or the kinematic model",
    agents=tuple(CONTINUOUS_AGENT_MODULES),
    observation="box",
    actions="discrete",
    agent_class=linear_agent_class,
    config_class=_config_class,
    make=_make,
    train=train_agent,
    save_formats=(SAVE_FORMAT,),
    load=_load,
    policy=_policy,
    documentation={"linear-sarsa": "linear-q", "linear-dyna-kinematic": "linear-dyna"},
)
"""The linear family (:class:`~skidnav.agents.family.Family`)."""
