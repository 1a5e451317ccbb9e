"""A config file, or the text a study shortcut writes, made ready to run on the one runner, and
run: the path every door takes (``skidnav run``, the study shortcuts, ``skidnav.run_config``).

The config's ``kind`` names its study (:mod:`skidnav.studies.kind`; none: the plain experiment);
the study turns the parsed document into a grid, chooses the runs' function and the layout of the
results, and says which backends it runs on. The runner
(:func:`~skidnav.experiments.runner.run_experiment`) does the rest and saves the config's text as
``config.toml`` beside the results, so ``skidnav run OUT/config.toml --out OUT`` resumes any run.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from skidnav.errors import UserError
from skidnav.experiments.configfile import parse_tables
from skidnav.experiments.runner import (
    BACKENDS,
    RunObserver,
    RunOutcome,
    TrialFunction,
    run_experiment,
)
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import RunLayout
from skidnav.files.saved import read_config_text
from skidnav.studies.kind import Study, study, study_kind


class LoadedConfig(NamedTuple):
    """A config ready to run.

    Attributes:
        grid: its runs (the study's grid of the config).
        study: the study of its ``kind`` (the plain experiment when it names none).
        text: the config's text (saved as ``config.toml`` beside the results).
        path: the file it was read from (named in errors).
    """

    grid: Grid
    study: Study
    text: str
    path: Path

    @property
    def layout(self) -> RunLayout:
        """What its results directory holds (the study's layout)."""
        return self.study.layout


def load_grid(path: Path) -> LoadedConfig:
    """The config at ``path``, ready to run.

    Raises:
        UserError: the file cannot be read, or its TOML, kind or content is invalid.
    """
    return parse_grid(read_config_text(path), path)


def parse_grid(text: str, path: Path) -> LoadedConfig:
    """The config of ``text`` (read from ``path``, or written by a study shortcut), ready to run.

    Raises:
        UserError: its TOML, kind or content is invalid (one line naming ``path``).
    """
    document = parse_tables(text, path)
    chosen = study(study_kind(document, path))
    return LoadedConfig(chosen.grid(document, path), chosen, text, path)


def choose_backend(loaded: LoadedConfig, backend: str | None) -> str:
    """``backend``, or when None ``process`` (``serial`` for a study that runs only serially,
    :attr:`~skidnav.studies.kind.Study.backends`); a name the runner does not know is left for
    the runner to refuse.

    Raises:
        UserError: the study does not run on ``backend``.
    """
    allowed = loaded.study.backends
    if backend is None:
        return "process" if "process" in allowed else allowed[0]
    if backend in BACKENDS and backend not in allowed:
        raise UserError(
            f"{loaded.path}: a {loaded.study.kind} study runs only with --backend "
            f"{' or '.join(allowed)}, not {backend}"
        )
    return backend


def run_loaded(
    loaded: LoadedConfig,
    out: Path,
    *,
    backend: str | None = None,
    jobs: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    trial: TrialFunction | None = None,
    on_run: RunObserver | None = None,
    only: str | None = None,
) -> RunOutcome:
    """Run (or resume) every run of ``loaded`` into ``out`` on the runner
    (:func:`~skidnav.experiments.runner.run_experiment`), with the study's run function
    (:meth:`~skidnav.studies.kind.Study.trial`) unless ``trial`` is given (the same function with
    other progress callbacks: ``skidnav robot study``); ``on_run`` is told of every finished run
    (the TensorBoard log); ``only`` runs a part of the grid
    (:func:`~skidnav.experiments.runs.select_runs`).

    Raises:
        UserError: bad backend options, ``out`` holds other results or is in use.
        RunsFailedError: runs raised (the finished ones are kept).
    """
    backend = choose_backend(loaded, backend)
    if trial is None:
        trial = loaded.study.trial(loaded.grid, out)
    return run_experiment(
        loaded.grid,
        out,
        backend=backend,
        jobs=jobs,
        scheduler=scheduler,
        trial=trial,
        source_text=loaded.text,
        config_path=loaded.path,
        progress=progress,
        layout=loaded.layout,
        on_run=on_run,
        only=only,
    )
