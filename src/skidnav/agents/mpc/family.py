"""The model-predictive family: ``mppi-kinematic``, MPPI through the learned kinematic model.

It drives the two wheel speeds (the env's ``action="continuous"``) over a ``Box`` observation
(the features by default: the pose, the goal and the lidar ranges, whose readings build its
map; over the pose alone it maps from collisions only), learning its model and its map step by
step in the plain loop (:func:`~skidnav.agents.mpc.training.train_mppi`); its saved file also
runs on the robot as the frozen planner.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.random import SeedSequence

from skidnav.agents.family import Env, Family, Params, require_wheel_speed_env
from skidnav.agents.interface import AgentConfig
from skidnav.agents.mpc.agent import AGENT_NAME, SAVE_FORMAT, MPPIKinematicAgent, make_mppi_agent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.loading import load_mppi_agent, policy_from_file
from skidnav.agents.mpc.training import train_mppi


def _agent_class(name: str) -> type[MPPIKinematicAgent]:
    return MPPIKinematicAgent


def _config_class(name: str) -> type[AgentConfig]:
    return MPPIConfig


def _make(
    name: str, env: Env, params: Params, seed: SeedSequence, max_steps: int
) -> MPPIKinematicAgent:
    """The controller for the navigation env ``env``: it reads the env's robot, discretization,
    goal cell and lidar layout (never its walls or floor), draws from ``seed``. UserError for an
    env of other spaces or bad ``params`` (``kinematic_model = "true"`` among them: the
    simulator offers no coefficients of the model to plan with)."""
    require_wheel_speed_env(name, env)
    return make_mppi_agent(env, dict(params), np.random.default_rng(seed))


def _load(json_path: Path, meta: Mapping[str, Any], env: Env | None) -> MPPIKinematicAgent:
    return load_mppi_agent(json_path)


FAMILY: Family[MPPIKinematicAgent] = Family(
    name="mpc",
    summary="model predictive control of the two wheel speeds (MPPI) through the learned "
    "kinematic model, with a map built from its lidar and its collisions",
    agents=(AGENT_NAME,),
    observation="box",
    actions="wheel-speeds",
    agent_class=_agent_class,
    config_class=_config_class,
    make=_make,
    train=train_mppi,
    save_formats=(SAVE_FORMAT,),
    load=_load,
    policy=policy_from_file,
    box_observation="features",
)
"""The model-predictive family (:class:`~skidnav.agents.family.Family`)."""
