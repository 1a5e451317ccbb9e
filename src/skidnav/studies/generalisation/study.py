"""The generalisation study as ``skidnav run`` executes it (``kind = "generalisation"``,
:mod:`skidnav.studies.kind`): its config becomes a
:class:`~skidnav.studies.generalisation.grid.GeneralisationGrid`, whose runs (agent × seed) the
runner executes with :func:`generalisation_trial`, one run file each; ``skidnav study generalise``
writes the same config from its flags and runs it the same way.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any

from skidnav.agents.catalog import entry
from skidnav.errors import UserError, within
from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import RunLayout, TrialResult
from skidnav.studies.agent_grid import read_grid, training_episodes
from skidnav.studies.generalisation.evaluation import generalisation_run, grid_split
from skidnav.studies.generalisation.grid import KIND, LAYOUT, GeneralisationGrid
from skidnav.studies.generalisation.report import report_section
from skidnav.studies.kind import STUDY_BACKENDS


def generalisation_trial(spec: RunSpec[GeneralisationGrid]) -> TrialResult:
    """Run ``spec``: its agent trained on the split's training worlds from the streams of run
    ``spec.seed``, evaluated on both sides; the training episodes, and the
    :class:`~skidnav.studies.generalisation.evaluation.GeneralisationResult` but agent and seed
    (the run's coordinates) as the summary."""
    grid = spec.config
    result, log = generalisation_run(
        spec.agent.name, spec.seed, grid_split(grid), grid.episodes, root_seed=grid.root_seed,
        params=spec.agent.params_dict(), env_options=grid.env_options, max_steps=grid.max_steps,
        eval_epsilon=grid.eval_epsilon,
    )  # fmt: skip
    summary = {key: value for key, value in asdict(result).items() if key not in ("agent", "seed")}
    return TrialResult(spec.run_id, spec.coordinates, training_episodes(log), summary, {})


class GeneralisationStudy:
    """The :class:`~skidnav.studies.kind.Study` of ``kind = "generalisation"``."""

    kind: str = KIND
    layout: RunLayout = LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> GeneralisationGrid:
        """The validated grid of a parsed config; every agent's name and params checked as a
        new agent would check them.

        Raises:
            UserError: one line naming ``path`` and the key or agent.
        """
        grid = read_grid(GeneralisationGrid, document, path, KIND)
        for agent in grid.agents:
            try:
                entry(agent.name).config(agent.params_dict())
            except UserError as error:
                raise within(within(error, "[[agents]]"), str(path)) from None
        return grid

    def trial(self, grid: GeneralisationGrid, out: Path) -> TrialFunction:
        """:func:`generalisation_trial`."""
        return generalisation_trial

    def report(self, run_dir: Path) -> str:
        """The study's tables (:func:`~skidnav.studies.generalisation.report.report_section`)."""
        return report_section(run_dir)


STUDY = GeneralisationStudy()
"""The generalisation study (:data:`skidnav.studies.kind.STUDY_MODULES`)."""
