"""Reading a saved ``mppi-kinematic`` agent (``.npz`` + ``.json``, never pickle) and its frozen
policy.

As every saved agent (:func:`skidnav.agents.linear.registry.load_linear_agent`): the JSON is
read within a size and nesting limit and every field checked before a fresh agent of it is
built (the model's size checked before anything is allocated); the archive's member names,
dtypes and shapes are checked against that agent's arrays before any is read; the values
(finite numbers, counts ≥ 0, wheel speeds within the bound, the model's sample counts
consistent) before they are used. Anything wrong is one :class:`~skidnav.errors.CorruptFileError`
line naming the file.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.geometry import geometry_from_json
from skidnav.agents.mpc.agent import (
    AGENT_NAME,
    SAVE_FORMAT,
    SAVE_VERSION,
    MPPIKinematicAgent,
)
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.dynamics import SampledDynamics
from skidnav.agents.mpc.policy import MPPIPolicy
from skidnav.agents.saving import generator_from_state, save_paths
from skidnav.errors import UserError, shown
from skidnav.files.saved import ArraySpec, SavedArchive, loading, read_json
from skidnav.models.kinematic_files import check_model_size
from skidnav.models.kinematic_regression import N_COEFFICIENTS
from skidnav.sim.lidar import FULL_TURN

MAX_AGENT_JSON_BYTES = 2**20
"""Largest ``.json`` of a saved agent [bytes]."""
MAX_STATES = 4_000_000
"""Most discrete states a saved agent's discretization may have (its lattice holds about 85
bytes per state and duration, its reverse graph included)."""


READ_VERSIONS = (2, 3, SAVE_VERSION)
"""The saved versions read: 2 held ``temperature`` in control steps (converted on reading); 2
and 3 no ``lidar_fov`` (their lidar spanned a full turn)."""


def load_mppi_agent(path: str | Path) -> MPPIKinematicAgent:
    """The agent saved at ``path`` (:meth:`MPPIKinematicAgent.save`); CorruptFileError in one
    line naming the file when either file is missing, damaged or inconsistent (module doc)."""
    npz_path, json_path = save_paths(path)
    meta = read_json(json_path, max_bytes=MAX_AGENT_JSON_BYTES, what="agent file")
    with loading(json_path, "agent", (ValueError, TypeError, OverflowError, UserError)):
        agent = _fresh_agent(meta)
    specs = {
        name: ArraySpec(tuple(array.shape), array.dtype.str)
        for name, array in agent.state_arrays().items()
    }
    with loading(npz_path, "agent"):
        with SavedArchive(npz_path) as archive:
            arrays = archive.read_all(specs)
        restore_arrays(agent, arrays)
    return agent


def _fresh_agent(meta: Mapping[str, Any]) -> MPPIKinematicAgent:
    """A new agent of the saved config, geometry, goal and observation layout, its counters
    and Generator restored (its arrays not yet)."""
    version = meta.get("version")
    if meta.get("format") != SAVE_FORMAT or version not in READ_VERSIONS:
        raise ValueError(f"not a skidnav {AGENT_NAME} agent file of version {SAVE_VERSION}")
    if meta["agent"] != AGENT_NAME:
        raise ValueError(f"expected agent {AGENT_NAME!r}, got {shown(meta['agent'])}")
    config_values = meta["config"]
    if not isinstance(config_values, Mapping):
        raise ValueError("expected config to be a JSON object")
    robot, grid = geometry_from_json(meta["geometry"])
    if version == 2 and "temperature" in config_values:  # then in control steps, now seconds
        steps = config_values["temperature"]
        if type(steps) not in (int, float):
            raise ValueError(f"expected temperature to be a number, got {shown(steps)}")
        config_values = {**config_values, "temperature": steps * robot.action_duration}
    config = MPPIConfig.from_mapping(config_values)
    if grid is None or grid.n_states > MAX_STATES:
        raise ValueError(f"expected a discretization of at most {MAX_STATES:,} states")
    check_model_size(grid, config.kinematic_config())
    placeholder = np.zeros((grid.n_regions, N_COEFFICIENTS))
    agent = MPPIKinematicAgent(
        robot, grid, meta["goal"], config,
        true_coefficients=placeholder if config.kinematic_model == "true" else None,
        lidar_rays=meta["lidar_rays"], lidar_range=meta["lidar_range"],
        lidar_fov=_field_of_view(meta, version),
    )  # fmt: skip
    counters, rng_state = meta["counters"], meta["rng"]
    if not isinstance(counters, Mapping) or not isinstance(rng_state, Mapping):
        raise ValueError("expected counters and rng to be JSON objects")
    for name in ("steps", "episodes", "rollouts", "episode_steps"):
        value = counters[name]
        if type(value) is not int or value < 0:
            raise ValueError(f"expected counter {name} to be an integer >= 0, got {shown(value)}")
        setattr(agent, name, value)
    agent.rng = generator_from_state(rng_state)
    agent.planner.rng = agent.rng
    return agent


def _field_of_view(meta: Mapping[str, Any], version: Any) -> float:
    """The saved lidar's field of view [rad]: a full turn for the versions before it was
    saved; ValueError unless a number (the agent checks its range)."""
    if version != SAVE_VERSION:
        return FULL_TURN
    fov = meta["lidar_fov"]
    if type(fov) not in (int, float):
        raise ValueError(f"expected lidar_fov to be a number, got {shown(fov)}")
    return float(fov)


def restore_arrays(agent: MPPIKinematicAgent, arrays: Mapping[str, np.ndarray]) -> None:
    """Fill ``agent`` (built by :func:`_fresh_agent`) with the saved arrays, each checked; then
    its cost map is recomputed from the evidence and the model. ValueError (or
    CorruptFileError) for a value the agent cannot hold."""
    agent.model.load_arrays(dict(arrays))
    dynamics = SampledDynamics(
        *(np.asarray(arrays[f"dynamics_{name}"]) for name in SampledDynamics._fields)
    )
    if not all(np.isfinite(array).all() for array in dynamics) or (dynamics.noise_std < 0).any():
        raise ValueError("saved dynamics are not finite (or a noise is negative)")
    for saved, own in zip(dynamics, agent.dynamics, strict=True):
        own[...] = saved
    for name in ("hits", "passes", "ray_ends", "ray_crossings"):
        counts = np.asarray(arrays[name])
        if (counts < 0).any():
            raise ValueError(f"saved {name} are not counts")
        getattr(agent.evidence, name)[...] = counts
    plan = np.asarray(arrays["plan"])
    if not (np.abs(plan) <= agent.robot.wheel_speed).all():  # NaN fails too
        raise ValueError("saved plan holds wheel speeds beyond the bound")
    agent.planner.plan[...] = plan
    agent.refresh_costs()


def policy_from_file(json_path: Path, meta: Mapping[str, Any]) -> MPPIPolicy:
    """The frozen planner of the agent saved at ``json_path`` (``meta``: its parsed JSON, read
    again by the agent's loader), its Generator seeded 0: a loader for
    the mpc family (:mod:`skidnav.agents.mpc.family`, format ``"skidnav-mppi-agent"``)."""
    del meta  # the agent's own loader reads and checks the file
    return load_mppi_agent(json_path).policy(seed=0)
