"""The grid of a hardware-in-the-loop study (docs/realtime.md, "Hardware-in-the-loop study"): what
it runs (:class:`StudySettings`, the ``[study]`` table) over a real-time config's presets, as the
runner's grid (:class:`StudyGrid`, a :class:`~skidnav.experiments.runs.Grid`): agents × the
config's ``[run] map`` × presets × seeds from the ``[run] seed``.

With ``sim_episodes`` every agent runs once per value: from scratch (0, labelled by its name) or
pre-trained for N episodes in the kinematic simulator first (``NAME+simN``,
:mod:`skidnav.studies.hardware.pretraining`); every arm of a (preset, seed) meets the same world.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from skidnav.errors import ConfigError, UserError, shown
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
from skidnav.robot.params import RobotParams
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
        sim_episodes: episodes of pre-training in the kinematic simulator, one arm per value
            (0: from scratch on the robot).
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
    sim_episodes: tuple[int, ...] = (0,)

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
        _check_sim_episodes(self.sim_episodes)


def _check_sim_episodes(values: object) -> None:
    """ValueError unless ``values`` is a tuple of distinct integers in [0, MAX_EPISODES]."""
    counts = isinstance(values, tuple) and all(
        isinstance(n, int) and not isinstance(n, bool) and 0 <= n <= MAX_EPISODES for n in values
    )
    if not (counts and isinstance(values, tuple) and values and len(set(values)) == len(values)):
        raise ValueError(
            f"expected sim_episodes to be one or more distinct integers in [0, "
            f"{MAX_EPISODES:,}], got {shown(values)}"
        )


def arm_label(agent: str, sim_episodes: int) -> str:
    """The label of agent ``agent`` pre-trained for ``sim_episodes`` simulator episodes: its
    name from scratch (0), ``NAME+simN`` otherwise."""
    return agent if sim_episodes == 0 else f"{agent}+sim{sim_episodes}"


def agent_specs(names: Sequence[str], sim_episodes: Sequence[int]) -> tuple[AgentSpec, ...]:
    """The grid's agents: every name × every pre-training, name-major."""
    return tuple(AgentSpec(name, arm_label(name, n)) for name in names for n in sim_episodes)


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
    comma-separated string); a one-line UserError naming the key and ``where`` if invalid."""
    study = dict(values)
    for key in ("agents", "presets"):
        if isinstance(study.get(key), str):
            study[key] = [name.strip() for name in study[key].split(",") if name.strip()]
    for key in ("agents", "presets", "sim_episodes"):
        if key in study and isinstance(study[key], list | tuple):
            study[key] = tuple(study[key])
    return build_dataclass(StudySettings, study, where)


@dataclass(frozen=True)
class StudyGrid:
    """A study as the runner's grid (:class:`~skidnav.experiments.runs.Grid`) and as the
    statistics' settings (:class:`~skidnav.experiments.report.analysis.StatsSettings`).

    Attributes:
        agents: one per agent name and pre-training (:func:`agent_specs`; hyperparameters:
            ``configs``' ``agents``).
        maps: the one map of every run, the config's ``[run] map``.
        presets: preset names; ``configs``: the config of each, with the study's episodes and
            time scale (its ``[run] map`` and ``seed`` are the study's; a run's seed comes from
            its world stream).
        seeds: runs per (agent, preset). root_seed: the config's ``[run] seed``.
        bootstrap_samples, confidence: of every interval of the tables.
        sim_episodes: the pre-trainings of every agent (``(0,)``: none).
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
    sim_episodes: tuple[int, ...] = (0,)

    def __post_init__(self) -> None:
        if not (self.agents and len(self.maps) == 1 and len(self.configs) == len(self.presets)):
            raise ValueError("expected agents, one map and one config per preset")
        _check_count("seeds", self.seeds, MAX_SEEDS)
        _check_root_seed("root_seed", self.root_seed)
        _check_sim_episodes(self.sim_episodes)
        if self.agents != agent_specs(self.agent_names, self.sim_episodes):
            raise ValueError("expected the agents of agent_specs(names, sim_episodes)")

    @property
    def agent_names(self) -> list[str]:
        """The distinct agent names, in grid order."""
        return list(dict.fromkeys(agent.name for agent in self.agents))

    def pretraining(self, label: str) -> int:
        """Simulator episodes of the arm labelled ``label`` before it drives (KeyError if none
        is)."""
        arms = {arm_label(name, n): n for name in self.agent_names for n in self.sim_episodes}
        return arms[label]

    def references(self) -> dict[str, str]:
        """Arm → the arm it is compared with: a pre-trained arm with its agent from scratch
        (when the grid has that arm), any other arm but the baseline with the baseline."""
        pairs = {}
        for agent in self.agents:
            scratch = agent.name if 0 in self.sim_episodes else self.baseline
            reference = scratch if self.pretraining(agent.label) else self.baseline
            if reference != agent.label:
                pairs[agent.label] = reference
        return pairs

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
    """The grid as a JSON-ready dict (inverse of :func:`grid_from_dict`); ``sim_episodes`` only
    when the grid pre-trains (a study without keeps its fingerprint)."""
    pretraining = {} if grid.sim_episodes == (0,) else {"sim_episodes": list(grid.sim_episodes)}
    return pretraining | {
        "name": grid.name,
        "agents": grid.agent_names,
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
    sim_episodes = tuple(data.get("sim_episodes", (0,)))
    return StudyGrid(
        agents=agent_specs(data["agents"], sim_episodes),
        maps=(MapSpec(**data["map"]),),
        presets=tuple(str(p["name"]) for p in presets),
        configs=configs,
        seeds=data["seeds"],
        root_seed=data["root_seed"],
        name=data["name"],
        bootstrap_samples=data["bootstrap_samples"],
        confidence=data["confidence"],
        sim_episodes=sim_episodes,
    )


def build_grid(tables: Mapping[str, Any], settings: StudySettings) -> StudyGrid:
    """The grid of ``settings`` over the config ``tables``, checked before anything runs.

    Raises:
        UserError: an unknown agent or preset, invalid hyperparameters, an unreadable map, a
            negative root seed, a preset that sets ``[run] map``, ``seed`` or manual reset, or
            pre-training with a preset whose actions are not the simulator's.
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
    if any(settings.sim_episodes):
        for preset, config in zip(settings.presets, configs, strict=True):
            _check_simulator_actions(preset, config)
    return StudyGrid(
        agents=agent_specs(settings.agents, settings.sim_episodes),
        maps=(_map_spec(base.map),),
        presets=settings.presets,
        configs=configs,
        seeds=settings.seeds,
        root_seed=seed,
        sim_episodes=settings.sim_episodes,
    )


def _check_simulator_actions(preset: str, config: RealtimeConfig) -> None:
    """UserError unless an action of ``preset`` (``[run] period × substeps``) lasts as long as
    the simulator's (the robot's ``dt × substeps``), which pre-training teaches."""
    simulated = RobotParams().action_duration
    robot = config.run.period * config.run.substeps
    if abs(robot - simulated) > 1e-9:
        raise ConfigError(
            f"expected [run] period × substeps to be {simulated:g} s, got {robot:g} s",
            (f"[presets.{preset}]",),
            f"sim_episodes pre-trains on the simulator's actions of {simulated:g} s",
        )


def _preset_config(
    tables: Mapping[str, Any], settings: StudySettings, preset: str, base: RunSettings
) -> RealtimeConfig:
    """The config of ``preset`` with the study's episodes and time scale, without the tables of
    other drivers than ``sim``."""
    config = config_from_mapping(tables, preset)
    run = config.run
    if (run.map, run.seed, run.reset) != (base.map, base.seed, "auto"):
        raise ConfigError(
            "expected no [run] map, seed or reset",
            (f"[presets.{preset}]",),
            "a study runs every preset on the [run] map from the [run] seed, resetting "
            "automatically",
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
