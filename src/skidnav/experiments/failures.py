"""Runs that raise: one line each, and the sweep goes on.

A run that raises (a numerical failure, a bug: anything but a :class:`~skidnav.errors.UserError`,
which is about the whole grid, or a ``KeyboardInterrupt``) does not end the sweep:
:func:`skidnav.experiments.runner.execute` gives its :class:`RunFailure` instead of its results,
and :func:`~skidnav.experiments.runner.run_experiment` logs the failure's one line naming the
run, its place in the grid and the error (:attr:`RunFailure.message`), writes every run that
finishes, and at the end raises :class:`~skidnav.errors.RunsFailedError` (the CLI prints one line
and exits with code 1). Nothing of a failed run is written, so the same command
on the same results directory runs only the failed runs again (the resume of
:mod:`skidnav.experiments.runner`).

>>> from types import SimpleNamespace
>>> spec = SimpleNamespace(run_id="run-000004", agent=SimpleNamespace(label="dyna-full"),
...                        preset="thesis", map=SimpleNamespace(label="obstacles"), seed=4)
>>> run_failure(spec, ZeroDivisionError("float division by zero")).message.split(" failed: ")
['run-000004 (agent dyna-full, preset thesis, map obstacles, seed 4)', 'ZeroDivisionError: float \
division by zero']
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple, TypeVar

from skidnav.errors import UserError, first_line

logger = logging.getLogger(__name__)
Result = TypeVar("Result")


class RunFailure(NamedTuple):
    """A run of the grid that raised instead of returning its results.

    Attributes:
        spec: the run (a :class:`~skidnav.experiments.runs.RunSpec`).
        error: the error as one line, ``"TypeName: first line of its message"``.
    """

    spec: Any
    error: str

    @property
    def message(self) -> str:
        """One line: the run, its place in the grid and the error."""
        return f"{describe_run(self.spec)} failed: {self.error}"


def describe_run(spec: Any) -> str:
    """``"run-000004 (agent dyna-full, preset thesis, map obstacles, seed 4)"``."""
    return (
        f"{spec.run_id} (agent {spec.agent.label}, preset {spec.preset}, map {spec.map.label}, "
        f"seed {spec.seed})"
    )


def run_failure(spec: Any, error: BaseException) -> RunFailure:
    """The failure of ``spec`` by ``error`` (its traceback, if any, is logged at DEBUG level)."""
    name = type(error).__name__
    text = f"{name}: {first_line(error)}" if str(error) else name
    logger.debug("%s raised", spec.run_id, exc_info=error)
    return RunFailure(spec, text)


def attempt(spec: Any, result: Callable[[], Result]) -> Result | RunFailure:
    """``result()`` (a run's results), or the failure of ``spec`` if it raises; a UserError,
    about the whole grid, and a KeyboardInterrupt go on."""
    try:
        return result()
    except UserError:
        raise
    except Exception as error:
        return run_failure(spec, error)


def failed_runs_message(failures: Sequence[RunFailure], total: int, out_dir: object) -> str:
    """The one line that ends a sweep with ``failures`` among ``total`` runs."""
    others = f"; {len(failures) - 1} more logged above" if len(failures) > 1 else ""
    return (
        f"{len(failures)} of {total} runs failed: {failures[0].message}{others}; the "
        f"finished runs are kept in {out_dir}, and the same command runs the failed ones again"
    )
