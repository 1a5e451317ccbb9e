"""``skidnav run CONFIG``: run (or resume) an experiment grid or a study (a config with a
``kind``, :mod:`skidnav.studies.kind`) on the one runner, loaded and run by
:mod:`skidnav.studies.loading`; here only the flags and what is printed.

The study shortcuts (``skidnav study …``, ``skidnav robot study``; :mod:`skidnav.commands.shortcut`)
write the config of their flags and run it through the same
:func:`~skidnav.studies.loading.parse_grid` and :func:`~skidnav.studies.loading.run_loaded`: the
same grid, runs, files and resume."""

from __future__ import annotations

import argparse
import contextlib
import signal
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import Any

from skidnav.commands.parsing import path_argument
from skidnav.commands.verbs import HELP
from skidnav.envs.registration import allow_env_modules
from skidnav.experiments.runner import BACKENDS, RunOutcome
from skidnav.experiments.tensorboard_log import TensorBoardLog
from skidnav.extras import require
from skidnav.files.outputs import check_output_dir
from skidnav.statistics.formatting import plural
from skidnav.studies.kind import VerdictStudy
from skidnav.studies.loading import LoadedConfig, load_grid, run_loaded


def add_parser(subparsers: Any) -> None:
    """Add the ``run`` subcommand."""
    parser = subparsers.add_parser(
        "run",
        help=HELP["run"],
        description="Run every run of an experiment config, or of a study config (its top-level "
        "'kind' names the study), or the part of its grid that --runs names. Started again on "
        "the same --out directory it skips the runs already finished; a second run on a "
        "directory in use is refused.",
    )
    parser.add_argument("config", type=path_argument, help="experiment or study config (TOML)")
    parser.add_argument(
        "--out",
        type=path_argument,
        default=None,
        help="results directory (default: runs/<config name>)",
    )
    add_backend_arguments(parser, default=None)
    add_env_module_argument(parser)
    parser.add_argument(
        "--runs",
        default=None,
        metavar="SELECTION",
        help="run only these runs of the grid, by index (the NNNNNN of run-NNNNNN): N, A:B "
        "(A to B-1) and A: or :B, comma-separated, e.g. 0:60,120:180; each run keeps its "
        "streams, so parts run into one --out give the whole grid's results",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--report", action="store_true", help="write report.html when done")
    parser.add_argument(
        "--tensorboard",
        type=path_argument,
        default=None,
        metavar="DIR",
        help="also log every run's episodes to TensorBoard in DIR (the logging extra)",
    )
    parser.set_defaults(func=run_command)


def add_backend_arguments(parser: argparse.ArgumentParser, default: str | None = "process") -> None:
    """``--jobs``, ``--backend`` and ``--scheduler``: how runs are executed (``run``, ``tune``,
    the study shortcuts). A ``default`` of None leaves the backend to
    :func:`skidnav.studies.loading.choose_backend`."""
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
        help="Dask scheduler address (with --backend dask): tls://host:port, with the TLS "
        "credentials of Dask's config (distributed.comm.tls.*), or tcp://host:port, "
        "unauthenticated (warned); default: a local TLS-only cluster of --jobs workers",
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


def outcome_line(outcome: RunOutcome) -> str:
    """What a run of a config did, in one line: runs (of the grid's, when a part was asked
    for), where, how many now and before, time."""
    runs = plural(outcome.n_runs, "run")
    if outcome.n_runs < outcome.grid_runs:
        runs = f"{outcome.n_runs} of the grid's {outcome.grid_runs} runs"
    return (
        f"{runs} in {outcome.out_dir} ({outcome.executed} run now, "
        f"{outcome.skipped} already done) in {outcome.wall_time:.1f} s"
    )


def tensorboard_log(directory: Path | None) -> TensorBoardLog | None:
    """The TensorBoard log of ``--tensorboard DIR`` (None without it), checked before any work:
    UserError (one line) without the ``logging`` extra or when ``DIR`` cannot be written."""
    if directory is None:
        return None
    require("logging", "--tensorboard")
    return TensorBoardLog(check_output_dir(directory, "--tensorboard"))


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """SIGTERM stops the sweep as Ctrl-C does (a KeyboardInterrupt: the workers stopped, what
    was saved said), instead of ending the process at once, which would leave the pool's
    semaphores to the resource tracker's "leaked semaphore" warning."""

    def interrupt(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def run_with_arguments(
    loaded: LoadedConfig,
    args: argparse.Namespace,
    on_run: TensorBoardLog | None = None,
    only: str | None = None,
) -> RunOutcome:
    """Run a loaded config as the command-line ``args`` ask (``--out``, default
    ``runs/<name>``, checked first; ``--backend``, ``--jobs``, ``--scheduler``,
    ``--no-progress``), SIGTERM stopping it as Ctrl-C does; prints what was run. ``only``: a
    part of the grid (``--runs``, :func:`~skidnav.experiments.runs.select_runs`)."""
    out = check_output_dir(args.out if args.out is not None else Path("runs") / loaded.grid.name)
    with terminate_as_interrupt():
        outcome = run_loaded(
            loaded,
            out,
            backend=args.backend,
            jobs=args.jobs,
            scheduler=args.scheduler,
            progress=not args.no_progress,
            on_run=on_run,
            only=only,
        )
    print(outcome_line(outcome))
    return outcome


def run_command(args: argparse.Namespace) -> int:
    """Run the experiment or study; print where the results are and, for a study with a verdict
    (:class:`~skidnav.studies.kind.VerdictStudy`: an experiment), its verdict line, with the
    report when asked."""
    allow_env_modules(args.env_module)
    log = tensorboard_log(args.tensorboard)
    loaded = load_grid(args.config)
    outcome = run_with_arguments(loaded, args, on_run=log, only=args.runs)
    if log is not None:
        print(f"TensorBoard logs: {log.root} (tensorboard --logdir {log.root})")
    if args.report:
        from skidnav.commands.report import print_report, write_results_report

        print_report(write_results_report(outcome.out_dir, progress=not args.no_progress))
    elif isinstance(loaded.study, VerdictStudy):
        print(loaded.study.verdict(outcome.out_dir))
    return 0
