"""What each agent of a BARN study sees and answers, from its catalog entry.

Every agent drives the same robot on the same world; what differs is the env's interface:

* an agent answering wheel speeds (``actions = "wheel-speeds"``: ``goal-tracker``,
  ``mppi-kinematic``, …) drives with ``action = "continuous"``; one answering the four discrete
  actions (``q-learning``, ``dyna-full``, the linear and deep agents) with ``action =
  "discrete"`` (full speed ahead, back, or a turn in place), each action lasting the config's
  ``discrete_action_duration`` (:func:`action_duration`; by default the benchmark's 0.1 s);
* a tabular agent observes the discrete state of the world's cells (31 × 101 cells × 20
  heading bins); every other agent the features, with a laser like the benchmark's Hokuyo
  UST-10 (:data:`LIDAR_RANGE`, :data:`LIDAR_FOV`, the config's ``lidar_rays``).

An agent whose parameters describe the observation's laser (``lidar_rays``, ``lidar_range``:
the goal tracker) is given the study's; a config that sets them otherwise is refused.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.agents.catalog import CatalogEntry, entry
from skidnav.errors import UserError, within
from skidnav.experiments.config import AgentSpec
from skidnav.extras import require
from skidnav.studies.agent_grid import read_grid
from skidnav.studies.barn.grid import CONTROL_PERIOD, KIND, BarnGrid

LIDAR_RANGE = 10.0
"""The laser's range [m] (Hokuyo UST-10LX: 10 m)."""
LIDAR_FOV = 1.5 * math.pi
"""The laser's field of view [rad] (270°), centred on the heading."""
OBSERVATION = "features"
"""The observation of every agent that does not learn over the discrete state."""


def env_interface(name: str) -> dict[str, str]:
    """The env's ``action`` and ``observation`` for agent ``name`` (module doc); UserError for
    an unknown agent."""
    described = entry(name)
    action = "discrete" if described.family.actions == "discrete" else "continuous"
    return {"action": action, "observation": described.env_observation(OBSERVATION)}


def action_duration(name: str, grid: BarnGrid) -> float:
    """How long one action of agent ``name`` lasts [s]: the grid's ``discrete_action_duration``
    for an agent answering discrete actions, the benchmark's 0.1 s for one answering wheel
    speeds; UserError for an unknown agent."""
    if env_interface(name)["action"] == "discrete":
        return grid.discrete_action_duration
    return CONTROL_PERIOD


def laser_params(grid: BarnGrid) -> dict[str, Any]:
    """The laser's layout as an agent's parameters: ``lidar_rays``, ``lidar_range`` [m]."""
    return {"lidar_rays": grid.lidar_rays, "lidar_range": LIDAR_RANGE}


def agent_params(agent: AgentSpec, grid: BarnGrid, described: CatalogEntry) -> dict[str, Any]:
    """The parameters ``agent`` is built with: its own, and the study's laser where its config
    describes one (module doc); UserError when it sets another."""
    params = agent.params_dict()
    config: Any = described.config_class  # a frozen dataclass, as every agent config
    fields = {field.name for field in dataclasses.fields(config)}
    for key, value in laser_params(grid).items():
        if key not in fields:
            continue
        if key in params and params[key] != value:
            raise UserError(
                f"agent {agent.label!r}: {key} is the study's laser ({value!r}); "
                f"set lidar_rays in [barn], not {key} = {params[key]!r} in params"
            )
        params[key] = value
    return params


def check_agents(grid: BarnGrid) -> None:
    """Check every agent of ``grid`` before any run: a known name, parameters its config
    accepts; UserError naming the agent otherwise."""
    for agent in grid.agents:
        described = entry(agent.name)
        described.config(agent_params(agent, grid, described))


def grid_from_document(document: Mapping[str, Any], path: Path) -> BarnGrid:
    """The grid of a parsed BARN config read from ``path`` (its ``[barn]`` table and its
    ``[[agents]]``), the agents' names and parameters checked against the catalog.

    Raises:
        UserError: one line naming ``path`` and the key; or the physics extra is missing for
            ``dynamics = "mujoco"``.
    """
    grid = read_grid(BarnGrid, document, path, KIND)
    try:
        check_agents(grid)
    except UserError as error:
        raise within(error, str(path)) from None
    if grid.dynamics == "mujoco":
        require("physics", "dynamics 'mujoco'")
    return grid
