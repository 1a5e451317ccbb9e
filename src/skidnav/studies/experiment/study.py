"""``STUDY``: the plain experiment as ``skidnav run`` executes it (``kind = "experiment"``, or no
``kind``; :mod:`skidnav.studies.kind`).

Its grid is the :class:`~skidnav.experiments.config.ExperimentConfig` of the config's tables,
checked against the agents, envs and map files before any run starts; its runs are
:func:`skidnav.experiments.trial.run_trial`'s, its results the runner's experiment layout
(:data:`~skidnav.experiments.store.EXPERIMENT_LAYOUT`). Its report is a page of its own, led by
its one-line verdict (:class:`~skidnav.studies.kind.VerdictStudy`), with the sections studies add
to an experiment report (:func:`~skidnav.studies.kind.experiment_sections`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.configfile import config_from_tables
from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import EXPERIMENT_LAYOUT, RunLayout
from skidnav.studies.kind import EXPERIMENT_KIND, STUDY_BACKENDS, Study, experiment_sections


class ExperimentStudy:
    """Agents × maps × presets × seeds on the navigation env (:class:`~skidnav.studies.kind.
    Study` and :class:`~skidnav.studies.kind.VerdictStudy`)."""

    kind: str = EXPERIMENT_KIND
    layout: RunLayout = EXPERIMENT_LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> ExperimentConfig:
        """The experiment of the config ``document`` read from ``path``, its agents,
        environment options and map files checked
        (:func:`~skidnav.experiments.config_checks.check_config`).

        Raises:
            UserError: one line naming ``path`` and what is wrong.
        """
        from skidnav.experiments.config_checks import check_config

        config = config_from_tables(dict(document), path)
        check_config(config, path)
        return config

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """:func:`~skidnav.experiments.trial.run_trial`, importing in each worker the
        environment modules allowed here (:func:`~skidnav.experiments.trial.default_trial`)."""
        from skidnav.experiments.trial import default_trial

        return default_trial()

    def report(self, run_dir: Path) -> str:
        """The whole experiment report page of ``run_dir`` (HTML), with the studies' sections."""
        from skidnav.experiments.report.html import build_report

        return build_report(run_dir, experiment_sections())

    def write_report(
        self, run_dir: Path, output: Path | None = None, *, progress: bool = False
    ) -> tuple[Path, str]:
        """Write the report of ``run_dir`` to ``output`` (default ``RUN_DIR/report.html``)
        atomically, a progress bar on stderr when ``progress``; (its path, its verdict line).

        Raises:
            UserError: the results are missing or damaged, or the report cannot be written.
        """
        from skidnav.experiments.report.html import write_report

        written = write_report(run_dir, output, experiment_sections(), progress=progress)
        return written.path, written.verdict

    def verdict(self, run_dir: Path) -> str:
        """The verdict line of ``run_dir`` (:func:`~skidnav.experiments.report.verdict.
        experiment_verdict`), what its report opens with."""
        from skidnav.experiments.report.verdict import experiment_verdict

        return experiment_verdict(run_dir)


STUDY: Study = ExperimentStudy()
"""The plain experiment, as :data:`skidnav.studies.kind.STUDY_MODULES` finds it."""
