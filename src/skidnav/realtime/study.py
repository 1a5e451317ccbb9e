"""Hardware-in-the-loop study: agents × floor/slip presets × seeds against the sim server.

Every (agent, preset, seed) is one real-time run (:class:`skidnav.realtime.loop.RealtimeLoop`
on the ``sim`` driver, which starts its own server on a free loopback port) written to
``OUT/runs/AGENT/PRESET/seed-N/`` with the run's usual files plus ``result.json``. A run whose
``result.json`` exists is skipped, so an interrupted study resumes where it stopped (an unfinished
run starts over). ``OUT/study.csv`` holds one row per run and ``OUT/study.md`` the tables of
docs/realtime.md ("Hardware-in-the-loop study"): success rate and mean episode length per agent
× preset, the rough/slippery success ratio, and model-based minus Q-learning success per floor.
The comparison mirrors the thesis's real-robot results (SPEC §5, "Thesis results to reproduce":
model-based ≈ +12 % success; the rough floor about doubles the success of the slippery one).
"""

from __future__ import annotations

import csv
import io
import json
import logging
import math
import shutil
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from skidnav.atomicfile import remove_stale_temporaries, write_user_file
from skidnav.errors import UserError, first_line, shown
from skidnav.realtime.arena import build_map, seed_streams
from skidnav.realtime.config import (
    RealtimeConfig,
    config_from_mapping,
    read_tables,
    with_overrides,
)
from skidnav.realtime.drivers import make_driver
from skidnav.realtime.loop import EXIT_INTERRUPTED, RealtimeLoop
from skidnav.realtime.run import agent_context, interrupt_handlers, warm_up_agent
from skidnav.realtime.study_report import CSV_FIELDS, markdown_report
from skidnav.robot.kinematics import N_ACTIONS
from skidnav.robot.params import RobotParams
from skidnav.savedfile import read_json
from skidnav.world.discretization import Discretization

log = logging.getLogger(__name__)

__all__ = ["CSV_FIELDS", "RunRecord", "StudySettings", "load_study", "run_study"]

MAX_RECORD_BYTES = 2**16
"""Largest ``result.json`` read [bytes] (one is about 300)."""


@dataclass(frozen=True)
class StudySettings:
    """What a study runs, validated on construction.

    Attributes:
        agents: agent names (registry). presets: ``[presets.NAME]`` tables of the config.
        seeds: runs per (agent, preset), with root seeds ``seed``, ``seed + 1``, …
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
        if not self.agents or not self.presets:
            raise ValueError(
                f"expected agents and presets, got {shown(self.agents)}, {shown(self.presets)}"
            )
        if not (isinstance(self.seeds, int) and self.seeds >= 1):
            raise ValueError(f"expected seeds to be an integer >= 1, got {shown(self.seeds)}")
        if self.episodes is not None and not (
            isinstance(self.episodes, int) and self.episodes >= 1
        ):
            raise ValueError(f"expected episodes to be an integer >= 1, got {shown(self.episodes)}")
        if self.time_scale is not None and not self.time_scale > 0:
            raise ValueError(f"expected time_scale > 0, got {shown(self.time_scale)}")


@dataclass(frozen=True)
class RunRecord:
    """Outcome of one run (a row of ``study.csv``); ``mean_episode_actions`` is over all its
    episodes (goal, truncated at ``max_actions`` or aborted alike); ``late_episodes`` and
    ``late_successes`` count the last half of the episodes (the odd middle one included), where
    the agent has learned the most. Validated on construction, so a ``result.json`` read back
    with wrong fields is refused."""

    agent: str
    preset: str
    seed: int
    episodes: int
    successes: int
    success_rate: float
    mean_episode_actions: float
    aborted: int
    late_episodes: int
    late_successes: int

    def __post_init__(self) -> None:
        counts = ("seed", "episodes", "successes", "aborted", "late_episodes", "late_successes")
        rates = (self.success_rate, self.mean_episode_actions)
        if not (isinstance(self.agent, str) and isinstance(self.preset, str)):
            raise ValueError("expected agent and preset to be strings")
        for name in counts:
            value = getattr(self, name)
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
                raise ValueError(f"expected {name} to be an integer >= 0, got {shown(value)}")
        if not all(isinstance(v, int | float) and 0 <= v < math.inf for v in rates):
            raise ValueError(f"expected finite rates >= 0, got {shown(rates)}")


def load_study(path: Path, overrides: Mapping[str, Any]) -> tuple[dict[str, Any], StudySettings]:
    """(TOML tables without ``[study]``, settings from ``[study]`` with ``overrides`` — keys of
    :class:`StudySettings`, None values ignored — on top); UserError if unreadable or invalid."""
    data = read_tables(path)
    study = data.pop("study", {})
    if not isinstance(study, dict):
        raise UserError(f"{path}: [study]: expected a table, got {shown(study)}")
    table = dict(study)
    table.update({key: value for key, value in overrides.items() if value is not None})
    for key in ("agents", "presets"):
        if isinstance(table.get(key), str):
            table[key] = [name.strip() for name in table[key].split(",") if name.strip()]
        if key in table:
            table[key] = tuple(table[key])
    try:
        settings = StudySettings(**table)
    except (TypeError, ValueError) as error:
        raise UserError(f"[study]: {error}") from None
    return data, settings


def run_config(
    tables: Mapping[str, Any], settings: StudySettings, preset: str, seed: int
) -> RealtimeConfig:
    """The config of one run: ``preset`` merged over the tables, the study's overrides, ``seed``."""
    config = config_from_mapping(tables, preset)
    return with_overrides(
        config,
        episodes=settings.episodes,
        time_scale=settings.time_scale,
        seed=config.run.seed + seed,
    )


def _check_agents(agents: Sequence[str]) -> None:
    from skidnav.agents.registry import agent_class

    for name in agents:
        agent_class(name)  # UserError if unknown


def _run_one(
    config: RealtimeConfig, agent_name: str, out: Path, progress: Callable[[str], None]
) -> tuple[int, list[Any]]:
    """One real-time run of a new agent on the ``sim`` driver; (exit code, episode results)."""
    from skidnav.agents.registry import make_agent

    robot, grid = RobotParams(), Discretization()
    grid_map = build_map(config.run.map, config.run.seed, grid)
    context = agent_context(agent_name, robot, grid)
    rng = seed_streams(config.run.seed)["agent"]
    table = config.agents.get(agent_name)
    agent = make_agent(agent_name, grid.n_states, N_ACTIONS, table, rng, **context)
    warm_up_agent(agent_name, config, context, grid.n_states)
    driver = make_driver("sim", config, server_log=out / "sim-server.jsonl")
    try:
        driver.connect()
    except ConnectionError as error:
        getattr(driver, "shutdown", driver.close)()
        raise UserError(f"cannot start the sim server: {error}") from None
    loop = RealtimeLoop(
        driver, agent, grid_map, config, out, robot=robot, grid=grid, progress=progress
    )
    try:
        with interrupt_handlers(loop):
            code = loop.run(0)
    finally:
        getattr(driver, "shutdown", driver.close)()
    return code, loop.results


def record_of(agent: str, preset: str, seed: int, results: Sequence[Any]) -> RunRecord:
    """The :class:`RunRecord` of a run's episode results (``EpisodeResult`` objects)."""
    episodes = len(results)
    reached = [bool(r.reached_goal) and not r.aborted for r in results]
    late = reached[episodes // 2 :]
    successes = sum(reached)
    return RunRecord(
        agent=agent,
        preset=preset,
        seed=seed,
        episodes=episodes,
        successes=successes,
        success_rate=successes / episodes if episodes else 0.0,
        mean_episode_actions=sum(r.actions for r in results) / episodes if episodes else 0.0,
        aborted=sum(bool(r.aborted) for r in results),
        late_episodes=len(late),
        late_successes=sum(late),
    )


def _read_record(path: Path) -> RunRecord | None:
    """The record of a finished run, or None (logged) when it is absent or unreadable (too
    large, not JSON, nested too deeply, wrong fields): the run is then repeated."""
    if not path.is_file():
        return None
    try:
        data = read_json(path, max_bytes=MAX_RECORD_BYTES, what="run record")
        unknown = sorted(set(data) - set(RunRecord.__dataclass_fields__))
        if unknown:
            raise ValueError(f"unexpected field {shown(unknown[0])}")
        return RunRecord(**data)
    except UserError as error:  # names the file
        problem = first_line(error, len(str(path)) + 120)
    except (ValueError, TypeError) as error:
        problem = f"{path}: {first_line(error, 120)}"
    log.warning("%s; the run is repeated", problem)
    return None


def _write_record(path: Path, record: RunRecord) -> None:
    """Write ``result.json`` atomically: a run killed while writing it is repeated, never half
    recorded."""
    write_user_file(path, json.dumps(asdict(record), indent=1).encode("utf-8"), "run record")


def run_study(
    tables: Mapping[str, Any],
    settings: StudySettings,
    out: Path,
    *,
    progress: Callable[[str], None] | None = None,
    announce: Callable[[str], None] | None = None,
) -> tuple[int, list[RunRecord]]:
    """Run every unfinished (agent, preset, seed), then write ``study.csv`` and ``study.md``.

    Returns (exit code: 0, or the code of an interrupted run; the records of all finished runs).
    ``announce`` gets one line per run (ran or skipped); ``progress`` the loop's status lines.
    """
    progress = progress or (lambda line: None)
    announce = announce or (lambda line: None)
    _check_agents(settings.agents)
    configs = {
        (preset, seed): run_config(tables, settings, preset, seed)
        for preset in settings.presets
        for seed in range(settings.seeds)
    }
    records: list[RunRecord] = []
    code = 0
    for agent in settings.agents:
        for (preset, seed), config in configs.items():
            run_dir = out / "runs" / agent / preset / f"seed-{seed}"
            record = _read_record(run_dir / "result.json")
            if record is not None:
                announce(f"{agent} {preset} seed {seed}: done before, skipped")
                records.append(record)
                continue
            if run_dir.exists():
                shutil.rmtree(run_dir)  # unfinished: start over
            run_dir.mkdir(parents=True)
            code, results = _run_one(config, agent, run_dir, progress)
            if code == EXIT_INTERRUPTED:
                break
            record = record_of(agent, preset, seed, results)
            _write_record(run_dir / "result.json", record)
            announce(
                f"{agent} {preset} seed {seed}: {record.successes}/{record.episodes} goals, "
                f"{record.mean_episode_actions:.1f} actions/episode, {record.aborted} aborted"
            )
            records.append(record)
        if code == EXIT_INTERRUPTED:
            break
    write_outputs(records, configs, out)
    return (EXIT_INTERRUPTED if code == EXIT_INTERRUPTED else 0), records


def write_outputs(
    records: Sequence[RunRecord], configs: Mapping[tuple[str, int], RealtimeConfig], out: Path
) -> None:
    """``study.csv`` (one row per run) and ``study.md`` (see :func:`markdown_report`), each
    written atomically (:func:`~skidnav.atomicfile.write_atomic`): a kill leaves the old table or
    the new one, and the next call removes its temporary."""
    table = io.StringIO()
    writer = csv.DictWriter(table, fieldnames=CSV_FIELDS)
    writer.writeheader()
    for record in records:
        row = asdict(record)
        row["success_rate"] = f"{record.success_rate:.4f}"
        row["mean_episode_actions"] = f"{record.mean_episode_actions:.2f}"
        writer.writerow(row)
    conditions = {
        preset: (config.sim.slip, config.sim.drift > 0) for (preset, _), config in configs.items()
    }
    rows = [asdict(record) for record in records]
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UserError(f"{out}: cannot create the folder ({error.strerror or error})") from None
    remove_stale_temporaries(out)  # of a study killed while writing its tables
    write_user_file(out / "study.csv", table.getvalue().encode("utf-8"), "study table")
    write_user_file(out / "study.md", markdown_report(rows, conditions).encode("utf-8"), "report")
