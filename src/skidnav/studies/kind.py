"""What a study is to ``skidnav run``: a kind of config the one runner executes.

A config is a TOML file whose top-level ``kind`` names its study; a config without one is a plain
experiment (agents × maps × presets × seeds), ``kind = "experiment"``, a study like the others
(:mod:`skidnav.studies.experiment`). The study turns the parsed document into a
:class:`~skidnav.experiments.runs.Grid` (its runs are the grid's agent × map × preset × seed
points, each with its own seeds), gives the function that executes one run and the
:class:`~skidnav.experiments.store.RunLayout` of its results, and writes its section of the
report. :func:`skidnav.experiments.runner.run_experiment` does the rest, the same for every
study: the process and Dask backends, one atomic file per finished run (a study killed by
Ctrl-C or SIGKILL resumes with nothing finished lost), the tidy Parquet tables, provenance and
the sessions in ``metadata.json``.

:data:`STUDY_MODULES` lists the studies; each module defines ``STUDY``, an object of the
:class:`Study` protocol. Only the named study's module is imported. A study whose report is a page
of its own with a one-line verdict (the experiment's) is also a :class:`VerdictStudy`.

An experiment's report draws the sections some studies add to it (the discretization-gap
table): :data:`EXPERIMENT_SECTIONS` lists them, the one place the commands take them from
(:func:`experiment_sections`), so the experiment report imports no study. docs/experiments.md,
"A study is a config".
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from skidnav.errors import ConfigError, UserError
from skidnav.experiments.runner import BACKENDS, TrialFunction
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import RunLayout

if TYPE_CHECKING:
    from skidnav.experiments.report.html import ExperimentSection

STUDY_BACKENDS: tuple[str, ...] = BACKENDS
"""Every backend of the runner: what a study runs on unless it says otherwise."""
EXPERIMENT_KIND = "experiment"
"""The ``kind`` of a plain experiment config (agents × maps × presets × seeds)."""


class Study(Protocol):
    """One kind of study: how its config becomes runs, how a run is executed, how it reports.

    Attributes:
        kind: the config's ``kind`` value, e.g. ``"continuity"``.
        layout: what its results directory holds (``layout.kind`` equals :attr:`kind`).
        backends: the runner backends it runs on (:data:`STUDY_BACKENDS` unless its runs keep
            wall-clock pace one at a time, as the hardware-in-the-loop study's).
    """

    kind: str
    layout: RunLayout
    backends: tuple[str, ...]

    def grid(self, document: Mapping[str, Any], path: Path) -> Grid:
        """The validated grid of the parsed TOML ``document`` read from ``path``.

        Raises:
            UserError: one line naming ``path``, the key and what was expected.
        """
        ...

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """The function executing one run of ``grid`` whose results go to the directory ``out``
        (importable by worker processes). Most runs write nothing themselves; a run that does
        (the hardware-in-the-loop study's real-time logs, a policy search's checkpoint) writes
        under ``out``."""
        ...

    def report(self, run_dir: Path) -> str:
        """The study's section of the HTML report of ``run_dir`` (an HTML fragment; a
        :class:`VerdictStudy`'s whole report page)."""
        ...


@runtime_checkable
class VerdictStudy(Protocol):
    """A study whose report is a page of its own, led by a one-line verdict (the experiment's:
    :mod:`skidnav.experiments.report.html`), rather than a section in the page every other study's
    report shares (:func:`skidnav.experiments.report.page.study_report`)."""

    def write_report(
        self, run_dir: Path, output: Path | None = None, *, progress: bool = False
    ) -> tuple[Path, str]:
        """Write the report of ``run_dir`` to ``output`` (default ``RUN_DIR/report.html``),
        atomically, with a progress bar on stderr when ``progress``; (its path, its verdict).

        Raises:
            UserError: the results are missing or damaged, or the report cannot be written.
        """
        ...

    def verdict(self, run_dir: Path) -> str:
        """The one line the report of ``run_dir`` opens with (``skidnav run`` prints it)."""
        ...


STUDY_MODULES: dict[str, str] = {
    EXPERIMENT_KIND: "skidnav.studies.experiment.study",
    "barn": "skidnav.studies.barn.study",
    "continuity": "skidnav.studies.continuity.study",
    "generalisation": "skidnav.studies.generalisation.study",
    "kinematic-curve": "skidnav.studies.kinematic_models.curve_study",
    "kinematic-models": "skidnav.studies.kinematic_models.study",
    "policy-search": "skidnav.studies.policy_search.study",
    "robot-study": "skidnav.studies.hardware.study",
    "sutton-barto-checks": "skidnav.studies.sutton_barto.study",
    "transfer": "skidnav.studies.transfer.study",
}
"""Study kind → the module defining its ``STUDY``: the plain experiment first, then the studies
alphabetically, the order errors list them in."""

EXPERIMENT_SECTIONS: tuple[str, ...] = ("skidnav.studies.gap:gap_section",)
"""The sections studies add to an experiment report, ``"module:function"``, in page order; each
function takes the summaries and the config and returns an HTML fragment
(:data:`skidnav.experiments.report.html.ExperimentSection`)."""


def study_kind(document: Mapping[str, Any], path: Path | str) -> str:
    """The ``kind`` of a parsed config (:data:`EXPERIMENT_KIND` when it names none).

    Raises:
        UserError: ``kind`` is not a string naming a study.
    """
    kind = document.get("kind", EXPERIMENT_KIND)
    if not isinstance(kind, str) or kind not in STUDY_MODULES:
        problem = f"expected kind to be one of {', '.join(STUDY_MODULES)}, got {kind!r}"
        raise ConfigError(problem, (str(path),))
    return kind


def study(kind: str) -> Study:
    """The study of ``kind`` (a key of :data:`STUDY_MODULES`)."""
    found: Study = importlib.import_module(STUDY_MODULES[kind]).STUDY
    return found


def study_of_results(kind: str, where: Path | str) -> Study:
    """The study whose results are of ``kind`` (``config.json``'s, a study's ``layout.kind``).

    Raises:
        UserError: no study writes results of that kind.
    """
    if kind not in STUDY_MODULES:
        known = ", ".join(STUDY_MODULES)
        raise UserError(f"{where}: holds {kind!r} results; known kinds: {known}")
    return study(kind)


def experiment_sections() -> tuple[ExperimentSection, ...]:
    """The functions of :data:`EXPERIMENT_SECTIONS` (their modules imported now)."""
    sections: list[ExperimentSection] = []
    for entry in EXPERIMENT_SECTIONS:
        module, name = entry.split(":")
        sections.append(getattr(importlib.import_module(module), name))
    return tuple(sections)
