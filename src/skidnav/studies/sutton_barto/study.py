"""``STUDY``: the textbook checks of Sutton & Barto (2018) ch. 8 as a study of ``skidnav run``
(``kind = "sutton-barto-checks"``, :mod:`skidnav.studies.kind`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import RunLayout
from skidnav.studies.kind import STUDY_BACKENDS, Study
from skidnav.studies.sutton_barto.grid import KIND, LAYOUT, TextbookChecks, checks_from_document


class SuttonBartoStudy:
    """Checks × runs (:class:`~skidnav.studies.sutton_barto.grid.TextbookChecks`), one agent
    trained on one maze per run, the tables and plots of every example as the report section."""

    kind: str = KIND
    layout: RunLayout = LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> TextbookChecks:
        """The checks of the config ``document`` read from ``path`` (UserError if invalid)."""
        return checks_from_document(document, path)

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """:func:`~skidnav.studies.sutton_barto.trial.checks_trial` (importable by workers)."""
        from skidnav.studies.sutton_barto.trial import checks_trial

        return checks_trial

    def report(self, run_dir: Path) -> str:
        """:func:`~skidnav.studies.sutton_barto.report.report_section`."""
        from skidnav.studies.sutton_barto.report import report_section

        return report_section(run_dir)


STUDY: Study = SuttonBartoStudy()
"""The textbook checks, as :data:`skidnav.studies.kind.STUDY_MODULES` finds them."""
