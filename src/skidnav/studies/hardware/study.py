"""Hardware-in-the-loop study: agents × floor/slip presets × seeds on the sim server, run by the
experiment runner (docs/realtime.md, "Hardware-in-the-loop study").

The study is a grid (:class:`StudyGrid`, a :class:`~skidnav.experiments.runs.Grid`): agents ×
the config's ``[run] map`` × presets × seeds. :func:`skidnav.experiments.runner.run_experiment`
expands, seeds, stores, locks and resumes it as it does an experiment's, with the study's
results layout (:data:`STUDY_LAYOUT`) and its trial function,
:class:`~skidnav.studies.hardware.trial.RealtimeTrial`: one real-time run on the ``sim`` driver.
Seeds as in an experiment (:mod:`skidnav.experiments.runs`): every agent of a (preset, seed)
meets the same world, and each run has its own stream for the agent. A run without a run file
starts over. The tables of ``OUT/study.md`` (:mod:`skidnav.studies.hardware.report`) come from the
store's summaries through :mod:`skidnav.experiments.report.analysis`. The comparison mirrors the
thesis's real-robot results (SPEC §5: model-based ≈ +12 % success; the rough floor about
doubles the success of the slippery one).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, NamedTuple

from skidnav.atomicfile import write_user_file
from skidnav.configtables import build_dataclass, table
from skidnav.errors import UserError, first_line, shown
from skidnav.experiments.config import MAX_EPISODES, MAX_SEEDS, AgentSpec, MapSpec
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import ResultStore, RunLayout
from skidnav.realtime.arena import arena_map
from skidnav.realtime.config import (
    RealtimeConfig,
    RunSettings,
    SimSettings,
    config_from_mapping,
    read_tables,
    with_overrides,
)
from skidnav.realtime.control.loop import EXIT_INTERRUPTED
from skidnav.savedfile import ArraySpec, up_to
from skidnav.studies.hardware.report import markdown_report
from skidnav.studies.hardware.trial import EPISODE_COLUMNS, RealtimeTrial, ignore
from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAP_KINDS

__all__ = [
    "STUDY_LAYOUT",
    "StudyGrid",
    "StudyOutcome",
    "StudySettings",
    "build_grid",
    "load_study",
    "run_study",
]


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


def load_study(path: Path, overrides: Mapping[str, Any]) -> tuple[dict[str, Any], StudySettings]:
    """(TOML tables without ``[study]``, settings from ``[study]`` with ``overrides`` — keys of
    :class:`StudySettings`, None values ignored — on top); UserError if unreadable or invalid."""
    data = read_tables(path)
    study = dict(table(data.pop("study", {}), f"{path}: [study]"))
    study.update({key: value for key, value in overrides.items() if value is not None})
    for key in ("agents", "presets"):
        if isinstance(study.get(key), str):
            study[key] = [name.strip() for name in study[key].split(",") if name.strip()]
        if key in study and isinstance(study[key], list | tuple):
            study[key] = tuple(study[key])
    return data, build_dataclass(StudySettings, study, "[study]")


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


def study_file_specs(grid: StudyGrid) -> dict[str, ArraySpec]:
    """What a study run file may hold besides its document: the :data:`EPISODE_COLUMNS`, each at
    most the longest preset's episodes long."""
    episodes = up_to(max(config.run.episodes for config in grid.configs))
    return {f"episode.{key}": ArraySpec((episodes,), kinds="fiub") for key in EPISODE_COLUMNS}


STUDY_LAYOUT = RunLayout(
    "robot-study", EPISODE_COLUMNS, grid_to_dict, grid_from_dict, study_file_specs
)
"""The results directory of a study (:class:`~skidnav.experiments.store.RunLayout`)."""


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
    config = dataclasses.replace(config, drivers={})  # the sim driver needs none
    return with_overrides(config, episodes=settings.episodes, time_scale=settings.time_scale)


def _map_spec(spec: str) -> MapSpec:
    """A ``[run] map`` (a kind, or a map file's absolute path) as the grid's map."""
    if spec in MAP_KINDS:
        return MapSpec(spec, kind=spec)
    return MapSpec(Path(spec).stem, file=spec)


class StudyOutcome(NamedTuple):
    """What :func:`run_study` did: exit code (0, or 130 interrupted), runs of the grid, runs
    finished (before or now), runs executed now."""

    code: int
    n_runs: int
    finished: int
    executed: int


def run_study(
    tables: Mapping[str, Any],
    settings: StudySettings,
    out: Path,
    *,
    progress: Callable[[str], None] = ignore,
    announce: Callable[[str], None] = ignore,
) -> StudyOutcome:
    """Run (or resume) every run of the study in ``out`` through the experiment runner, then
    write ``study.md`` (also after an interruption, from the runs finished by then).

    Raises:
        UserError: bad settings or config (before anything is written), ``out`` holds other
            results or is in use, a run's robot cannot be reached, a file cannot be written.
    """
    grid = build_grid(tables, settings)
    if (out / "study.csv").exists() and not (out / "config.json").exists():
        raise UserError(f"{out}: holds a study in an earlier format; choose another --out")
    store = ResultStore(out, STUDY_LAYOUT)
    before = len(store.finished()) if store.check(grid) else 0
    trial = RealtimeTrial(out, progress, announce)
    try:
        try:
            outcome = run_experiment(grid, out, backend="serial", trial=trial, layout=STUDY_LAYOUT)
        except KeyboardInterrupt:
            finished = write_report(store, grid, consolidate=True)
            return StudyOutcome(EXIT_INTERRUPTED, grid.n_runs, finished, finished - before)
        write_report(store, grid)
    except OSError as error:  # a full disk, a folder that cannot be written
        reason = error.strerror or first_line(error)
        raise UserError(f"{error.filename or out}: cannot write the study ({reason})") from None
    return StudyOutcome(0, outcome.n_runs, outcome.n_runs, outcome.executed)


def write_report(store: ResultStore, grid: StudyGrid, *, consolidate: bool = False) -> int:
    """Write ``study.md`` from the store's summaries (consolidated first when asked, e.g. after
    an interruption); returns the runs it covers (0 without any finished run: nothing written)."""
    if not store.finished():
        return 0
    summaries = store.consolidate()[1] if consolidate else store.load_tables()[1]
    text = markdown_report(summaries, grid, grid.conditions())
    write_user_file(store.root / "study.md", text.encode("utf-8"), "report")
    return len(summaries)
