"""The grid of a hardware-in-the-loop study (docs/realtime.md, "Hardware-in-the-loop study"): what
it runs (:class:`StudySettings`, the ``[study]`` table) over a real-time config's presets, as the
runner's grid (:class:`StudyGrid`, a :class:`~skidnav.experiments.runs.Grid`): agents × the
config's ``[run] map`` × presets × seeds from the ``[run] seed``.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from skidnav.errors import UserError, shown
from skidnav.experiments.config import AgentSpec, MapSpec
from skidnav.experiments.limits import MAX_EPISODES, MAX_SEEDS
from skidnav.files.configtables import build_dataclass
from skidnav.realtime.arena import arena_map
from skidnav.realtime.config import (
    RealtimeConfig,
    RunSettings,
    SimSettings,
    config_from_mapping,
    with_overrides,
)
from skidnav.realtime.drivers import require_driver_extras
from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAP_KINDS


@dataclass(frozen=True)
class StudySettings:
    """What a study runs, validated on construction.

    Attributes:
        agents: agent names (registry). presets: ``[presets.NAME]`` tables of the config.
        seeds: runs per (agent, preset).
        episodes: episodes per run (None: the preset's ``[run] episodes``).
        time_scale: robot s per wall s (None: the preset's ``[run] time_scale``).
    """

    agents: tuple[str, ...] = ("q-learning", "dyna-kinematic")
    presets: tuple[str, ...] = (
        "rough-stationary",
        "slippery-stationary",
        "rough-drifting",
        "slippery-drifting",
    )
    seeds: int = 1
    episodes: int | None = None
    time_scale: float | None = None

    def __post_init__(self) -> None:
        for name in ("agents", "presets"):
            names = getattr(self, name)
            named = isinstance(names, tuple) and all(isinstance(n, str) and n for n in names)
            if not (named and names and len(set(names)) == len(names)):
                raise ValueError(
                    f"expected one or more distinct {name[:-1]} names, got {shown(names)}"
                )
        _check_count("seeds", self.seeds, MAX_SEEDS)
        if self.episodes is not None:
            _check_count("episodes", self.episodes, MAX_EPISODES)
        scale = self.time_scale
        if scale is not None and not (isinstance(scale, int | float) and 0 < scale < math.inf):
            raise ValueError(f"expected a finite time_scale > 0, got {shown(scale)}")


def _check_root_seed(name: str, value: object) -> None:
    """ValueError unless ``value`` is an integer >= 0 (a ``SeedSequence`` entropy)."""
    if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
        raise ValueError(f"expected {name} to be an integer >= 0, got {shown(value)}")


def _check_count(name: str, value: object, most: int) -> None:
    """ValueError unless ``value`` is an integer in [1, ``most``]."""
    if not (isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= most):
        raise ValueError(f"expected {name} to be an integer in [1, {most:,}], got {shown(value)}")


def study_settings(values: Mapping[str, Any], where: str) -> StudySettings:
    """The settings of a ``[study]`` table's ``values`` (agents and presets as lists, or as one
    comma-separated string); UserError ``"{where}: …"`` if invalid."""
    study = dict(values)
    for key in ("agents", "presets"):
        if isinstance(study.get(key), str):
            study[key] = [name.strip() for name in study[key].split(",") if name.strip()]
        if key in study and isinstance(study[key], list | tuple):
            study[key] = tuple(study[key])
    return build_dataclass(StudySettings, study, where)


@dataclass(frozen=True)
class StudyGrid:
    """A study as the runner's grid (:class:`~skidnav.experiments.runs.Grid`) and as the
    statistics' settings (:class:`~skidnav.experiments.report.analysis.StatsSettings`).

    Attributes:
        agents: one per agent name (label = name; hyperparameters: ``configs``' ``agents``).
        maps: the one map of every run, the config's ``[run] map``.
        presets: preset names; ``configs``: the config of each, with the study's episodes and
            time scale (its ``[run] map`` and ``seed`` are the study's; a run's seed comes from
            its world stream).
        seeds: runs per (agent, preset). root_seed: the config's ``[run] seed``.
        bootstrap_samples, confidence: of every interval of the tables.
    """

    agents: tuple[AgentSpec, ...]
    maps: tuple[MapSpec, ...]
    presets: tuple[str, ...]
    configs: tuple[RealtimeConfig, ...]
    seeds: int
    root_seed: int
    name: str = "robot-study"
    bootstrap_samples: int = 2000
    confidence: float = 0.95

    def __post_init__(self) -> None:
        if not (self.agents and len(self.maps) == 1 and len(self.configs) == len(self.presets)):
            raise ValueError("expected agents, one map and one config per preset")
        _check_count("seeds", self.seeds, MAX_SEEDS)
        _check_root_seed("root_seed", self.root_seed)

    @property
    def agent_labels(self) -> list[str]:
        """Agent labels in grid order."""
        return [agent.label for agent in self.agents]

    @property
    def baseline(self) -> str:
        """The agent the others are compared to: Q-learning if in the study, else the first."""
        return "q-learning" if "q-learning" in self.agent_labels else self.agent_labels[0]

    @property
    def n_runs(self) -> int:
        """Runs of the grid."""
        return len(self.agents) * len(self.presets) * self.seeds

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of :func:`grid_to_dict` (names a study directory)."""
        text = json.dumps(grid_to_dict(self), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def conditions(self) -> dict[str, tuple[str, bool]]:
        """Preset → (slip preset of its floor, drifting slip?)."""
        return {
            p: (c.sim.slip, c.sim.drift > 0)
            for p, c in zip(self.presets, self.configs, strict=True)
        }


def grid_to_dict(grid: StudyGrid) -> dict[str, Any]:
    """The grid as a JSON-ready dict (inverse of :func:`grid_from_dict`)."""
    return {
        "name": grid.name,
        "agents": [agent.name for agent in grid.agents],
        "map": {"label": grid.maps[0].label, "kind": grid.maps[0].kind, "file": grid.maps[0].file},
        "presets": [
            {"name": preset, "run": asdict(c.run), "sim": asdict(c.sim), "agents": dict(c.agents)}
            for preset, c in zip(grid.presets, grid.configs, strict=True)
        ],
        "seeds": grid.seeds,
        "root_seed": grid.root_seed,
        "bootstrap_samples": grid.bootstrap_samples,
        "confidence": grid.confidence,
    }


def grid_from_dict(data: dict[str, Any]) -> StudyGrid:
    """The grid saved by :func:`grid_to_dict` (KeyError, TypeError or ValueError if invalid)."""
    presets = data["presets"]
    configs = tuple(
        RealtimeConfig(
            run=RunSettings(**p["run"]), sim=SimSettings(**p["sim"]), agents=dict(p["agents"])
        )
        for p in presets
    )
    return StudyGrid(
        agents=tuple(AgentSpec(name, name) for name in data["agents"]),
        maps=(MapSpec(**data["map"]),),
        presets=tuple(str(p["name"]) for p in presets),
        configs=configs,
        seeds=data["seeds"],
        root_seed=data["root_seed"],
        name=data["name"],
        bootstrap_samples=data["bootstrap_samples"],
        confidence=data["confidence"],
    )


def build_grid(tables: Mapping[str, Any], settings: StudySettings) -> StudyGrid:
    """The grid of ``settings`` over the config ``tables``, checked before anything runs.

    Raises:
        UserError: an unknown agent or preset, invalid hyperparameters, an unreadable map, a
            negative root seed, or a preset that sets ``[run] map``, ``seed`` or manual reset.
    """
    from skidnav.agents.tabular.registry import make_config

    base = config_from_mapping(tables).run
    seed = base.seed
    try:
        _check_root_seed("[run] seed", seed)
    except ValueError as error:
        raise UserError(str(error)) from None
    configs = tuple(_preset_config(tables, settings, preset, base) for preset in settings.presets)
    for config in configs:
        require_driver_extras("sim", config)  # the study's runs drive the sim server
        for agent in settings.agents:
            make_config(agent, config.agents.get(agent))  # UserError if unknown or invalid
    arena_map(base.map, seed, Discretization())  # UserError if unreadable
    return StudyGrid(
        agents=tuple(AgentSpec(name, name) for name in settings.agents),
        maps=(_map_spec(base.map),),
        presets=settings.presets,
        configs=configs,
        seeds=settings.seeds,
        root_seed=seed,
    )


def _preset_config(
    tables: Mapping[str, Any], settings: StudySettings, preset: str, base: RunSettings
) -> RealtimeConfig:
    """The config of ``preset`` with the study's episodes and time scale, without the tables of
    other drivers than ``sim``."""
    config = config_from_mapping(tables, preset)
    run = config.run
    if (run.map, run.seed, run.reset) != (base.map, base.seed, "auto"):
        raise UserError(
            f"[presets.{preset}]: a study runs every preset on the [run] map from the [run] "
            "seed, resetting automatically; this preset sets [run] map, seed or reset"
        )
    # the sim driver reads no driver table: theirs stay at the defaults
    config = RealtimeConfig(
        run=config.run, sim=config.sim, agents=config.agents, policies=config.policies
    )
    return with_overrides(config, episodes=settings.episodes, time_scale=settings.time_scale)


def _map_spec(spec: str) -> MapSpec:
    """A ``[run] map`` (a kind, or a map file's absolute path) as the grid's map."""
    if spec in MAP_KINDS:
        return MapSpec(spec, kind=spec)
    return MapSpec(Path(spec).stem, file=spec)
