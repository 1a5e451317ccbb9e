"""The sim-to-sim gap (docs/physics.md, "The sim-to-sim gap"): policies learned on the kinematic
simulator, run on the MuJoCo robot.

* :mod:`~skidnav.studies.transfer.evaluation` — one seed's training and its evaluation on both
  dynamics.
* :mod:`~skidnav.studies.transfer.grid` — the config (``kind = "transfer"``), the grid of runs
  (agents × seeds) the runner executes, and its results layout.
* :mod:`~skidnav.studies.transfer.study` — the run function and ``STUDY`` for ``skidnav run``
  (:mod:`skidnav.studies.kind`).
* :mod:`~skidnav.studies.transfer.report` — the table, from a results directory.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["TransferResult", "TransferRun", "transfer_run"]


def __getattr__(name: str) -> Any:
    """The names of :data:`__all__`, from :mod:`~skidnav.studies.transfer.evaluation`, imported
    when first asked for: the config and grid modules stay light."""
    if name in __all__:
        return getattr(importlib.import_module(f"{__name__}.evaluation"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
