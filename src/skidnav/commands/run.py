"""``skidnav run CONFIG``: run (or resume) an experiment grid or a study (a config with a
``kind``, :mod:`skidnav.studies.kind`) on the one runner.

The study shortcuts (``skidnav study …``, ``skidnav robot study``; :mod:`skidnav.commands.shortcut`)
write the config of their flags and run it through :func:`parse_grid` and :func:`run_loaded`, the
path of ``skidnav run``: the same grid, runs, files and resume."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, NamedTuple

from skidnav.envs.registration import allow_env_modules
from skidnav.errors import UserError
from skidnav.experiments.configfile import config_from_tables, parse_tables
from skidnav.experiments.runner import (
    BACKENDS,
    RunObserver,
    RunOutcome,
    TrialFunction,
    run_experiment,
)
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import EXPERIMENT_LAYOUT, RunLayout
from skidnav.experiments.tensorboard_log import TensorBoardLog
from skidnav.extras import require
from skidnav.files.outputs import check_output_dir
from skidnav.files.saved import read_config_text
from skidnav.statistics.formatting import plural
from skidnav.studies.kind import EXPERIMENT_KIND, Study, study, study_kind


def add_parser(subparsers: Any) -> None:
    """Add the ``run`` subcommand."""
    parser = subparsers.add_parser(
        "run",
        help="run an experiment or study config (agents × maps × presets × seeds); resumable",
        description="Run every run of an experiment config, or of a study config (its top-level "
        "'kind' names the study). Started again on the same --out directory it skips the runs "
        "already finished; a second run on a directory in use is refused.",
    )
    parser.add_argument("config", type=Path, help="experiment or study config (TOML)")
    parser.add_argument(
        "--out", type=Path, default=None, help="results directory (default: runs/<config name>)"
    )
    add_backend_arguments(parser, default=None)
    add_env_module_argument(parser)
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--report", action="store_true", help="write report.html when done")
    parser.add_argument(
        "--tensorboard",
        type=Path,
        default=None,
        metavar="DIR",
        help="also log every run's episodes to TensorBoard in DIR (the logging extra)",
    )
    parser.set_defaults(func=run_command)


def add_backend_arguments(parser: argparse.ArgumentParser, default: str | None = "process") -> None:
    """``--jobs``, ``--backend`` and ``--scheduler``: how runs are executed (``run``, ``tune``,
    the study shortcuts). A ``default`` of None leaves the backend to :func:`choose_backend`."""
    parser.add_argument(
        "--jobs", type=int, default=None, help="worker processes (default: local cores)"
    )
    parser.add_argument(
        "--backend",
        choices=BACKENDS,
        default=default,
        help="serial, local process pool, or Dask (default: process"
        + (", or serial for a study that runs only serially)" if default is None else ")"),
    )
    parser.add_argument(
        "--scheduler",
        default=None,
        help="Dask scheduler address, e.g. tcp://127.0.0.1:8786 (with --backend dask)",
    )


def add_env_module_argument(parser: argparse.ArgumentParser) -> None:
    """``--env-module MODULE`` (repeatable): the modules a config's ``env_id`` may name
    (``run``, ``tune``)."""
    parser.add_argument(
        "--env-module",
        action="append",
        default=[],
        metavar="MODULE",
        help="import MODULE for its Gymnasium environments and allow env_id = "
        '"MODULE:Env-v0" (repeatable; a config alone can name only registered ids)',
    )


class LoadedConfig(NamedTuple):
    """A config ready to run.

    Attributes:
        grid: its runs (an experiment config, or the study's grid).
        study: the study of its ``kind``; None for an experiment.
        text: the config's text (saved as ``config.toml`` beside the results).
        path: the file it was read from (named in errors).
    """

    grid: Grid
    study: Study | None
    text: str
    path: Path

    @property
    def layout(self) -> RunLayout:
        """What its results directory holds."""
        return EXPERIMENT_LAYOUT if self.study is None else self.study.layout


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
    kind = study_kind(document, path)
    if kind == EXPERIMENT_KIND:
        return LoadedConfig(config_from_tables(document, path), None, text, path)
    chosen = study(kind)
    return LoadedConfig(chosen.grid(document, path), chosen, text, path)


def choose_backend(loaded: LoadedConfig, backend: str | None) -> str:
    """``backend``, or when None ``process`` (``serial`` for a study that runs only serially,
    :attr:`~skidnav.studies.kind.Study.backends`).

    Raises:
        UserError: the study does not run on ``backend``.
    """
    if loaded.study is None:
        return backend or "process"
    allowed = loaded.study.backends
    if backend is None:
        return "process" if "process" in allowed else allowed[0]
    if backend not in allowed:
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
) -> RunOutcome:
    """Run (or resume) every run of ``loaded`` into ``out`` on the runner
    (:func:`~skidnav.experiments.runner.run_experiment`), with the study's run function
    (:meth:`~skidnav.studies.kind.Study.trial`) unless ``trial`` is given (the same function with
    other progress callbacks: ``skidnav robot study``); ``on_run`` is told of every finished run
    (the TensorBoard log).

    Raises:
        UserError: bad backend options, ``out`` holds other results or is in use.
        RunsFailedError: runs raised (the finished ones are kept).
    """
    backend = choose_backend(loaded, backend)
    if trial is None and loaded.study is not None:
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
    )


def outcome_line(outcome: RunOutcome) -> str:
    """What a run of a config did, in one line: runs, where, how many now and before, time."""
    return (
        f"{plural(outcome.n_runs, 'run')} in {outcome.out_dir} ({outcome.executed} run now, "
        f"{outcome.skipped} already done) in {outcome.wall_time:.1f} s"
    )


def tensorboard_log(directory: Path | None) -> TensorBoardLog | None:
    """The TensorBoard log of ``--tensorboard DIR`` (None without it), checked before any work:
    UserError (one line) without the ``logging`` extra or when ``DIR`` cannot be written."""
    if directory is None:
        return None
    require("logging", "--tensorboard")
    return TensorBoardLog(check_output_dir(directory, "--tensorboard"))


def run_command(args: argparse.Namespace) -> int:
    """Run the experiment or study; print where the results are and, for an experiment, its
    verdict line (:mod:`skidnav.experiments.report.verdict`), with the report when asked."""
    allow_env_modules(args.env_module)
    log = tensorboard_log(args.tensorboard)
    loaded = load_grid(args.config)
    out = check_output_dir(args.out if args.out is not None else Path("runs") / loaded.grid.name)
    outcome = run_loaded(
        loaded,
        out,
        backend=args.backend,
        jobs=args.jobs,
        scheduler=args.scheduler,
        progress=not args.no_progress,
        on_run=log,
    )
    print(outcome_line(outcome))
    if log is not None:
        print(f"TensorBoard logs: {log.root} (tensorboard --logdir {log.root})")
    if args.report:
        from skidnav.commands.report import print_report, write_results_report

        print_report(write_results_report(outcome.out_dir, progress=not args.no_progress))
    elif loaded.study is None:
        from skidnav.experiments.report.verdict import experiment_verdict

        print(experiment_verdict(outcome.out_dir))
    return 0
