"""What only the library knows of an experiment config, checked before any run starts: agent
names and hyperparameters, the observation each agent learns over, environment options, map
files and grids (:func:`check_config`)."""

from __future__ import annotations

from pathlib import Path

import gymnasium
import numpy as np

from skidnav.agents.catalog import CatalogEntry, entry
from skidnav.envs.registration import creation_error, registered_env_id
from skidnav.errors import ConfigError, UserError, within
from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.reference.finegrid import check_grids
from skidnav.experiments.runs import expand_runs
from skidnav.experiments.trial import SKID_ENV_ID, config_map, trial_env
from skidnav.world.mapfile import load_map


def check_config(config: ExperimentConfig, path: Path | str | None = None) -> None:
    """Check what only the library knows before any run starts: agent names and hyperparameters,
    environment options, map files. Raises UserError naming the problem (and the config file
    ``path`` when given)."""
    try:
        _check_config(config)
    except UserError as error:
        if path is None:
            raise
        raise within(error, str(path)) from None


def _check_config(config: ExperimentConfig) -> None:
    registered_env_id(config.env_id)
    entries = _check_agents(config)
    for map_spec in config.maps:
        if map_spec.file:
            load_map(map_spec.file)
    first = expand_runs(config)[0]
    try:
        for map_spec in config.maps:
            grid_map = config_map(map_spec, np.random.default_rng(0))
            check_grids(config, grid_map, map_spec.label, entries)
        trial_env(first, grid_map, 0).close()
    except ConfigError:  # a grid the map refuses, named already
        raise
    except gymnasium.error.Error as error:
        raise UserError(f"environment {config.env_id!r}: {error}") from None
    except (TypeError, ValueError) as error:
        raise UserError(f"environment or map options: {creation_error(error)}") from None


def _check_agents(config: ExperimentConfig) -> dict[str, CatalogEntry]:
    """The catalog entry of each agent name of ``config``, asked once, its parameters (a true
    kinematic model only for an agent that takes the simulator's) and (on the skid-steer env)
    the observation it would learn over checked; UserError otherwise."""
    entries: dict[str, CatalogEntry] = {}
    requested = dict(config.env_options).get("observation")
    for agent in config.agents:
        described = entries.setdefault(agent.name, entry(agent.name))
        params = agent.params_dict()
        described.config(params)
        if params.get("kinematic_model") == "true" and not described.asks_for("true_kinematics"):
            raise ConfigError(
                "expected kinematic_model 'learned' or 'prior', got 'true'",
                (f"agent {agent.label!r}",),
                "'true' plans with the simulator's expected velocities of the discrete actions, "
                f"which {agent.name} cannot take",
            )
        if config.env_id == SKID_ENV_ID:
            described.env_observation(requested)
    return entries
