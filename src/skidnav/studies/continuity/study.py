"""The continuity comparison as a study of the one runner: ``kind = "continuity"``
(docs/continuity.md, "A study config").

A config (``configs/continuity.toml``)::

    kind = "continuity"

    [continuity]        # the fields of ComparisonConfig, each optional
    name = "continuity"
    map_kind = "obstacles"
    learners = ["q-learning", "dyna-full", "cmaes", "ppo", "sac", "goal-tracker"]
    seeds = 3
    ...

``skidnav run CONFIG`` executes its runs, every learner × seed index
(:class:`~skidnav.studies.continuity.comparison.ComparisonConfig` is the grid), on any backend,
one run file per finished run (:mod:`skidnav.studies.continuity.runfile`), so a comparison
killed by Ctrl-C or SIGKILL resumes with nothing finished lost. Run k of every learner trains
from :func:`~skidnav.studies.continuity.comparison.run_seed` (the runner's world stream k), so a
run's numbers do not depend on the backend, the order or a resume. ``skidnav study continuity``
writes the config of its flags (:func:`config_text`) and runs it the same way. The report
section and the shortcut's files come from the results directory
(:mod:`skidnav.studies.continuity.results`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import Grid, RunSpec
from skidnav.experiments.store import TrialResult
from skidnav.files.configtables import build_dataclass, check_keys, table, toml_value
from skidnav.studies.continuity.comparison import (
    ComparisonConfig,
    comparison_to_dict,
    require_learner_extras,
    run_seed,
    train_learner,
)
from skidnav.studies.continuity.runfile import CONTINUITY_LAYOUT, run_result
from skidnav.studies.kind import STUDY_BACKENDS, Study

KIND = "continuity"
TOP_KEYS = ("kind", KIND)
"""The top-level keys of a continuity config."""


def comparison_from_document(document: Mapping[str, Any], path: Path | str) -> ComparisonConfig:
    """The comparison of a parsed config (its ``[continuity]`` table; lists as tuples).

    Raises:
        UserError: one line naming ``path``, the table or key and what was expected.
    """
    check_keys(document, TOP_KEYS, f"{path}: top level")
    values = dict(table(document.get(KIND, {}), f"{path}: [{KIND}]"))
    if isinstance(values.get("learners"), list):
        values["learners"] = tuple(values["learners"])
    return build_dataclass(ComparisonConfig, values, f"{path}: [{KIND}]")


def config_text(config: ComparisonConfig, comment: str = "") -> str:
    """The TOML config of ``config`` (every field spelled out), after the ``comment`` line."""
    lines = [f"# {comment}"] if comment else []
    lines += [f'kind = "{KIND}"', "", f"[{KIND}]"]
    lines += [f"{key} = {toml_value(value)}" for key, value in comparison_to_dict(config).items()]
    return "\n".join(lines) + "\n"


def continuity_trial(spec: RunSpec[ComparisonConfig]) -> TrialResult:
    """One run: learner ``spec.agent.name`` trained from the seed of its index, then its final
    policy's rollouts (:func:`~skidnav.studies.continuity.runfile.run_result`)."""
    config = spec.config
    run = train_learner(config, spec.agent.name, run_seed(config, spec.seed))
    return run_result(spec, run)


class ContinuityStudy:
    """The continuity study (:class:`~skidnav.studies.kind.Study`)."""

    kind = KIND
    layout = CONTINUITY_LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> Grid:
        """The comparison of the config ``document`` read from ``path``; refused when a
        learner's extra is missing (:func:`~skidnav.studies.continuity.comparison.
        require_learner_extras`)."""
        comparison = comparison_from_document(document, path)
        require_learner_extras(comparison)
        return comparison

    def trial(self, grid: Grid, out: Path) -> TrialFunction:
        """:func:`continuity_trial` (importable by worker processes)."""
        return continuity_trial

    def report(self, run_dir: Path) -> str:
        """The comparison table, the trajectory picture and the runs of ``run_dir``."""
        from skidnav.studies.continuity.results import report_section

        return report_section(run_dir)


STUDY: Study = ContinuityStudy()
"""The continuity study, as :data:`skidnav.studies.kind.STUDY_MODULES` finds it."""
