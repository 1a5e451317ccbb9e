"""``STUDY``: the BARN benchmark as a study of ``skidnav run`` (``kind = "barn"``,
:mod:`skidnav.studies.kind`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import RunLayout
from skidnav.studies.barn.agents import grid_from_document
from skidnav.studies.barn.grid import KIND, LAYOUT, BarnGrid
from skidnav.studies.barn.report import report_section
from skidnav.studies.barn.trial import barn_trial
from skidnav.studies.kind import STUDY_BACKENDS, Study


class BarnStudy:
    """Agents × BARN worlds × floors × seeds (:class:`~skidnav.studies.barn.grid.BarnGrid`),
    each run scored by the benchmark's rules (:mod:`skidnav.studies.barn.trial`), the scores
    with their intervals as the report section (:mod:`skidnav.studies.barn.report`)."""

    kind: str = KIND
    layout: RunLayout = LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> BarnGrid:
        """The grid of the config ``document`` read from ``path`` (UserError if invalid)."""
        return grid_from_document(document, path)

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """:func:`~skidnav.studies.barn.trial.barn_trial`."""
        return barn_trial

    def report(self, run_dir: Path) -> str:
        """:func:`~skidnav.studies.barn.report.report_section`."""
        return report_section(run_dir)


STUDY: Study = BarnStudy()
"""The BARN study, as :data:`skidnav.studies.kind.STUDY_MODULES` finds it."""
