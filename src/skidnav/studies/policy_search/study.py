"""``STUDY``: the CMA-ES policy search as a study of ``skidnav run`` (``kind =
"policy-search"``, :mod:`skidnav.studies.kind`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import RunLayout
from skidnav.extras import require
from skidnav.studies.kind import STUDY_BACKENDS, Study
from skidnav.studies.policy_search.grid import KIND, LAYOUT, PolicySearchGrid, grid_from_document
from skidnav.studies.policy_search.report import report_section
from skidnav.studies.policy_search.trial import SearchTrial


class PolicySearchStudy:
    """Slip presets × seeds (:class:`~skidnav.studies.policy_search.grid.PolicySearchGrid`),
    one CMA-ES search per run, the learning curves and final scores as the report section."""

    kind: str = KIND
    layout: RunLayout = LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> PolicySearchGrid:
        """The study of the config ``document`` read from ``path`` (UserError if invalid, or
        when the search extra is missing)."""
        grid = grid_from_document(document, path)
        require("search", "a policy search")
        return grid

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """A :class:`~skidnav.studies.policy_search.trial.SearchTrial` checkpointing each search
        in ``out/checkpoints``: a search cut short continues from its last generation."""
        return SearchTrial(out / "checkpoints")

    def report(self, run_dir: Path) -> str:
        """:func:`~skidnav.studies.policy_search.report.report_section`."""
        return report_section(run_dir)


STUDY: Study = PolicySearchStudy()
