"""Generalisation to maps never seen (docs/generalisation.md): agents trained on a seeded set of
maps, their frozen policies run on those maps and on maps never seen.

* :mod:`~skidnav.studies.generalisation.evaluation` — the split of worlds, one run's training and
  evaluation, the reference policies.
* :mod:`~skidnav.studies.generalisation.grid` — the config (``kind = "generalisation"``) and the
  grid of runs (agents × seeds) the runner executes, and its results layout.
* :mod:`~skidnav.studies.generalisation.study` — the run function and ``STUDY`` for
  ``skidnav run`` (:mod:`skidnav.studies.kind`).
* :mod:`~skidnav.studies.generalisation.report` — the tables, from a results directory.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = [
    "EpsilonGreedy",
    "GeneralisationResult",
    "GeneralisationRun",
    "GoalSeeker",
    "Reference",
    "Split",
    "evaluate_on",
    "generalisation_run",
    "references",
    "split_worlds",
]


def __getattr__(name: str) -> Any:
    """The names of :data:`__all__`, from :mod:`~skidnav.studies.generalisation.evaluation`,
    imported when first asked for: the config and grid modules stay light (a command's
    ``--help`` does not load the agents and environments)."""
    if name in __all__:
        return getattr(importlib.import_module(f"{__name__}.evaluation"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
