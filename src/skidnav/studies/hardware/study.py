"""Hardware-in-the-loop study: agents × floor/slip presets × seeds on the sim server, run by the
experiment runner as a study kind, ``kind = "robot-study"`` (docs/realtime.md,
"Hardware-in-the-loop study").

A study config names its kind, the ``[study]`` table (:class:`~skidnav.studies.hardware.grid.
StudySettings`) and the real-time tables it runs: its own (``[run]``, ``[sim]``, ``[agents.*]``,
``[presets.*]``, as in ``configs/realtime.toml``), or those of the real-time config that
``[study] config`` names, whose own ``[study]`` table the study's keys then override::

    kind = "robot-study"

    [study]
    config = "realtime.toml"      # relative to this file
    seeds = 2

``skidnav run CONFIG`` runs it (serially: a run keeps wall-clock pace); ``skidnav robot study
--config REALTIME [--agents …]`` writes such a config of its flags (:func:`study_config_text`) and
runs it with the same grid, runner, trial and files (:func:`run_study`), then writes the tables
``OUT/study.md``. Everything a run needs lives in the config: each run starts its own sim server
on a free loopback port, so there is no address to give.

The grid (:class:`~skidnav.studies.hardware.grid.StudyGrid`) is agents × the config's ``[run]
map`` × presets × seeds. :func:`skidnav.experiments.runner.run_experiment` expands, seeds,
stores, locks and resumes it as it does an experiment's, with the study's results layout
(:data:`STUDY_LAYOUT`) and its trial function,
:class:`~skidnav.studies.hardware.trial.RealtimeTrial`: one real-time run on the ``sim`` driver.
Seeds as in an experiment (:mod:`skidnav.experiments.runs`): every agent of a (preset, seed)
meets the same world, and each run has its own stream for the agent. A run without a run file
starts over. The tables (:mod:`skidnav.studies.hardware.report`) come from the store's summaries
through :mod:`skidnav.experiments.report.analysis`. The comparison mirrors the thesis's
real-robot results (model-based ≈ +12 % success; the rough floor about doubles the success of
the slippery one).
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, NamedTuple

import pandas as pd

from skidnav.errors import ConfigError, UserError, first_line, shown, within
from skidnav.experiments.configfile import parse_tables
from skidnav.experiments.report.page import markdown_html
from skidnav.experiments.runner import TrialFunction, run_experiment
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import ResultStore, RunLayout
from skidnav.files.atomic import write_user_file
from skidnav.files.configtables import resolve_path, table, toml_value
from skidnav.files.saved import ArraySpec, read_config_text, up_to
from skidnav.realtime.config import read_tables, resolve_map_paths
from skidnav.realtime.control.loop import EXIT_INTERRUPTED
from skidnav.studies.hardware.grid import (
    StudyGrid,
    build_grid,
    grid_from_dict,
    grid_to_dict,
    study_settings,
)
from skidnav.studies.hardware.report import markdown_report
from skidnav.studies.hardware.speed import speed_report
from skidnav.studies.hardware.trial import EPISODE_COLUMNS, RealtimeTrial, ignore
from skidnav.studies.kind import Study

__all__ = [
    "STUDY",
    "STUDY_LAYOUT",
    "StudyGrid",
    "StudyOutcome",
    "build_grid",
    "grid_from_dict",
    "grid_to_dict",
    "load_study",
    "run_study",
    "study_config_text",
    "study_grid",
]

KIND = "robot-study"
"""The study's kind, in its configs and its results' ``config.json``."""


def study_grid(document: Mapping[str, Any], path: Path) -> StudyGrid:
    """The grid of a parsed study config ``document`` read from ``path`` (module doc).

    Raises:
        UserError: one line naming the file, the table or key and what was expected.
    """
    data = copy.deepcopy(dict(document))
    data.pop("kind", None)
    where = f"{path}: [study]"
    study = dict(table(data.pop("study", {}), where))
    source = study.pop("config", None)
    tables_path = path
    if source is None:
        resolve_map_paths(data, path.parent)
    elif not isinstance(source, str) or data:
        raise ConfigError(
            "expected config to be the name of a real-time config and no other table here, "
            f"got {shown(source)} and {', '.join(data) or 'none'}",
            (where,),
        )
    else:
        tables_path = resolve_path(source, path.parent)
        data = read_tables(tables_path)
        study = {**table(data.pop("study", {}), f"{tables_path}: [study]"), **study}
    settings = study_settings(study, where)
    try:
        return build_grid(data, settings)
    except UserError as error:
        raise within(error, str(tables_path)) from None


def study_config_text(config: Path, overrides: Mapping[str, Any]) -> str:
    """The study config of ``skidnav robot study --config CONFIG``: the real-time ``config`` by
    its absolute path and the ``[study]`` keys given as ``overrides`` (None values left out;
    agents and presets as comma-separated strings or lists)."""
    lines = [
        "# the config of `skidnav robot study`: skidnav run it to resume",
        f'kind = "{KIND}"',
        "",
        "[study]",
        f"config = {toml_value(str(config.resolve()))}",
    ]
    for key, value in overrides.items():
        if value is not None:
            lines.append(f"{key} = {toml_value(value)}")
    return "\n".join(lines) + "\n"


def load_study(config: Path, overrides: Mapping[str, Any]) -> tuple[StudyGrid, str]:
    """(grid, config text) of the study ``skidnav robot study --config CONFIG`` with the
    ``overrides`` of :func:`study_config_text` runs.

    Raises:
        UserError: ``config`` or the overrides are unreadable or invalid (one line).
    """
    read_config_text(config)  # an unreadable config named as itself, before the study's text
    text = study_config_text(config, overrides)
    return study_grid(parse_tables(text, config), config), text


def study_file_specs(grid: StudyGrid) -> dict[str, ArraySpec]:
    """What a study run file may hold besides its document: the :data:`EPISODE_COLUMNS`, each at
    most the longest preset's episodes long."""
    episodes = up_to(max(config.run.episodes for config in grid.configs))
    return {f"episode.{key}": ArraySpec((episodes,), kinds="fiub") for key in EPISODE_COLUMNS}


STUDY_LAYOUT = RunLayout(KIND, EPISODE_COLUMNS, grid_to_dict, grid_from_dict, study_file_specs)
"""The results directory of a study (:class:`~skidnav.experiments.store.RunLayout`)."""


class StudyOutcome(NamedTuple):
    """What :func:`run_study` did: exit code (0, or 130 interrupted), runs of the grid, runs
    finished (before or now), runs executed now."""

    code: int
    n_runs: int
    finished: int
    executed: int


def run_study(
    grid: StudyGrid,
    out: Path,
    *,
    source_text: str = "",
    progress: Callable[[str], None] = ignore,
    announce: Callable[[str], None] = ignore,
) -> StudyOutcome:
    """Run (or resume) every run of ``grid`` in ``out`` through the experiment runner, as
    ``skidnav run`` does with the study's config ``source_text`` (saved as ``config.toml``), then
    write ``study.md`` (also after an interruption, from the runs finished by then); ``progress``
    gets the real-time loop's status lines, ``announce`` one line per finished run.

    Raises:
        UserError: ``out`` holds other results or is in use, a run's robot cannot be reached, a
            file cannot be written.
    """
    if (out / "study.csv").exists() and not (out / "config.json").exists():
        raise UserError(f"{out}: holds a study in an earlier format; choose another --out")
    store = ResultStore(out, STUDY_LAYOUT)
    before = len(store.finished()) if store.check(grid) else 0
    trial = RealtimeTrial(out, progress, announce)
    try:
        try:
            outcome = run_experiment(
                grid, out, backend="serial", trial=trial, source_text=source_text,
                layout=STUDY_LAYOUT,
            )  # fmt: skip
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
    text = study_markdown(summaries, grid)
    write_user_file(store.root / "study.md", text.encode("utf-8"), "report")
    return len(summaries)


def study_markdown(summaries: pd.DataFrame, grid: StudyGrid) -> str:
    """The study's tables (``study.md``): success and episode length
    (:func:`~skidnav.studies.hardware.report.markdown_report`), then the robot episodes to
    success (:func:`~skidnav.studies.hardware.speed.speed_report`)."""
    return markdown_report(summaries, grid, grid.conditions()) + speed_report(summaries, grid)


class HardwareStudy:
    """The hardware-in-the-loop study (:class:`~skidnav.studies.kind.Study`): serial only, its
    runs writing their real-time files into the results directory."""

    kind = KIND
    layout = STUDY_LAYOUT
    backends: tuple[str, ...] = ("serial",)

    def grid(self, document: Mapping[str, Any], path: Path) -> Grid:
        """:func:`study_grid`."""
        return study_grid(document, path)

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """One real-time run per call, its files in ``out/runs/AGENT/PRESET/seed-N``."""
        return RealtimeTrial(out)

    def report(self, run_dir: Path) -> str:
        """The study's tables of ``run_dir`` (:func:`~skidnav.studies.hardware.report.
        markdown_report`) as HTML."""
        store = ResultStore(run_dir, STUDY_LAYOUT)
        grid: StudyGrid = store.config()
        summaries = store.load_tables()[1]
        text = study_markdown(summaries, grid)
        return "<h2>Hardware-in-the-loop study</h2>" + markdown_html(text)


STUDY: Study = HardwareStudy()
"""The hardware-in-the-loop study, as :data:`skidnav.studies.kind.STUDY_MODULES` finds it."""
