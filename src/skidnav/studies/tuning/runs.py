"""The runs of a tuning trial: the experiment of one trial, its runs on the tuning streams
(seed-major) and the check that no tuning map is an evaluation map (docs/tuning.md).

A tuning run's world and run streams are those of the evaluation grid with the spawn key
prefixed by :data:`TUNE_STREAM`, so every trial of every agent meets the same tuning worlds.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np

from skidnav.errors import UserError
from skidnav.experiments.config import (
    DEFAULT_ENV_ID,
    AgentSpec,
    ExperimentConfig,
    freeze_params,
)
from skidnav.experiments.runs import expand_runs
from skidnav.seeding import ROOT_ROLES, WORLD_ROLES, SeedKey, child_sequences
from skidnav.studies.tuning.config import TuneConfig
from skidnav.world.grid import GridMap

if TYPE_CHECKING:
    from skidnav.experiments.trial import ExperimentRun

TUNE_STREAM = ROOT_ROLES.index("tuning")
"""Child of ``SeedSequence(root_seed)`` that roots every tuning stream (0, 1: evaluation)."""


def tuning_key(key: SeedKey) -> SeedKey:
    """The tuning counterpart of an evaluation seed key: the same key under :data:`TUNE_STREAM`."""
    assert key.spawn_key[:1] in ((0,), (1,)), "expected an evaluation world or run key"
    return SeedKey(key.entropy, (TUNE_STREAM, *key.spawn_key))


def trial_config(
    config: ExperimentConfig, tune: TuneConfig, agent: AgentSpec, params: dict[str, Any], label: str
) -> ExperimentConfig:
    """The experiment of one trial: ``agent`` with ``params`` over its own params, on the tuning
    maps with the tuning seeds; ``label`` (e.g. the trial number) goes into the description, so
    every trial has its own fingerprint (the Dask keys of its runs)."""
    tuned = AgentSpec(agent.name, agent.label, freeze_params({**agent.params_dict(), **params}))
    return dataclasses.replace(
        config,
        agents=(tuned,),
        maps=tune.maps,
        seeds=tune.seeds,
        baseline=agent.label,
        description=f"tuning {agent.label} {label}".rstrip(),
    )


def tuning_runs(config: ExperimentConfig) -> list[ExperimentRun]:
    """The runs of a :func:`trial_config`, on the tuning streams, seed-major."""
    runs = [
        dataclasses.replace(
            spec, world_seed=tuning_key(spec.world_seed), run_seed=tuning_key(spec.run_seed)
        )
        for spec in expand_runs(config)
    ]
    return sorted(runs, key=lambda spec: (spec.seed, spec.index))


def run_map(spec: ExperimentRun) -> GridMap:
    """The map run ``spec`` trains on (drawn as :func:`skidnav.experiments.trial.measure_trial`
    draws it: from the first child of the world stream)."""
    from skidnav.experiments.trial import config_map

    map_seed = child_sequences(spec.world_seed.sequence(), WORLD_ROLES)["map"]
    return config_map(spec.map, np.random.default_rng(map_seed))


def _map_key(grid_map: GridMap) -> tuple[Any, ...]:
    return (grid_map.occupancy.shape, grid_map.occupancy.tobytes(), grid_map.start, grid_map.goal)


def check_separation(config: ExperimentConfig, tune: TuneConfig) -> int:
    """Check that no tuning map equals an evaluation map of ``config`` (its ``[[maps]]`` ×
    presets × seeds); returns the number of evaluation maps compared (0 for an environment that
    brings its own world, where there is nothing to separate).

    Raises:
        UserError: a tuning map equals an evaluation map (e.g. the same map file).
    """
    if config.env_id != DEFAULT_ENV_ID:
        return 0
    first = config.agents[0]
    evaluation = dataclasses.replace(config, agents=(first,), baseline=first.label)
    seen = {_map_key(run_map(spec)): spec for spec in expand_runs(evaluation)}
    template = trial_config(config, tune, first, {}, "")
    for spec in tuning_runs(template):
        twin = seen.get(_map_key(run_map(spec)))
        if twin is not None:
            raise UserError(
                f"tuning map {spec.map.label!r} (seed {spec.seed}) equals evaluation map "
                f"{twin.map.label!r} (seed {twin.seed}); give [[tune.maps]] maps of their own"
            )
    return len(seen)
