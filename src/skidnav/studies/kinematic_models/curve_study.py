"""``STUDY``: the learned kinematic model's data curve as a study of ``skidnav run``
(``kind = "kinematic-curve"``, :mod:`skidnav.studies.kind`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import RunLayout
from skidnav.studies.kind import STUDY_BACKENDS, Study
from skidnav.studies.kinematic_models.curve_grid import (
    KIND,
    LAYOUT,
    KinematicCurve,
    curve_from_document,
    require_dynamics_extras,
)
from skidnav.studies.kinematic_models.curve_table import report_section
from skidnav.studies.kinematic_models.curve_trial import curve_trial


class KinematicCurveStudy:
    """Dynamics × floors × seeds
    (:class:`~skidnav.studies.kinematic_models.curve_grid.KinematicCurve`), one drive per run,
    the table of the curve as the report section."""

    kind: str = KIND
    layout: RunLayout = LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> KinematicCurve:
        """The curve of the config ``document`` read from ``path`` (UserError if invalid, or
        when the MuJoCo robot is asked for without the physics extra)."""
        curve = curve_from_document(document, path)
        require_dynamics_extras(curve)
        return curve

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """:func:`~skidnav.studies.kinematic_models.curve_trial.curve_trial`."""
        return curve_trial

    def report(self, run_dir: Path) -> str:
        """:func:`~skidnav.studies.kinematic_models.curve_table.report_section`."""
        return report_section(run_dir)


STUDY: Study = KinematicCurveStudy()
"""The data curve, as :data:`skidnav.studies.kind.STUDY_MODULES` finds it."""
