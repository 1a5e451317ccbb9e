"""``STUDY``: the kinematic-model comparison as a study of ``skidnav run``
(``kind = "kinematic-models"``, :mod:`skidnav.studies.kind`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import RunLayout
from skidnav.studies.kind import STUDY_BACKENDS, Study
from skidnav.studies.kinematic_models.grid import (
    KIND,
    LAYOUT,
    ModelComparison,
    comparison_from_document,
    require_model_extras,
)
from skidnav.studies.kinematic_models.table import report_section
from skidnav.studies.kinematic_models.trial import comparison_trial


class KinematicModelsStudy:
    """Models × seeds (:class:`~skidnav.studies.kinematic_models.grid.ModelComparison`), one
    model fitted and scored on one seed's drive per run, the table of means over seeds as the
    report section."""

    kind: str = KIND
    layout: RunLayout = LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> ModelComparison:
        """The comparison of the config ``document`` read from ``path`` (UserError if invalid,
        or when a model's extra is missing)."""
        comparison = comparison_from_document(document, path)
        require_model_extras(comparison)
        return comparison

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """:func:`~skidnav.studies.kinematic_models.trial.comparison_trial`."""
        return comparison_trial

    def report(self, run_dir: Path) -> str:
        """:func:`~skidnav.studies.kinematic_models.table.report_section`."""
        return report_section(run_dir)


STUDY: Study = KinematicModelsStudy()
