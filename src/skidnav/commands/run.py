"""``skidnav run CONFIG``: run (or resume) an experiment grid or a study (a config with a
``kind``, :mod:`skidnav.studies.kind`) on the one runner."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from skidnav.envs.registration import allow_env_modules
from skidnav.experiments.configfile import config_from_tables, parse_tables
from skidnav.experiments.runner import BACKENDS, RunOutcome, TrialFunction, run_experiment
from skidnav.experiments.runs import Grid
from skidnav.experiments.store import EXPERIMENT_LAYOUT, RunLayout
from skidnav.outputs import check_output_dir
from skidnav.savedfile import read_config_text
from skidnav.studies.kind import EXPERIMENT_KIND, study, study_kind


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
    add_backend_arguments(parser)
    add_env_module_argument(parser)
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--report", action="store_true", help="write report.html when done")
    parser.set_defaults(func=run_command)


def add_backend_arguments(parser: argparse.ArgumentParser) -> None:
    """``--jobs``, ``--backend`` and ``--scheduler``: how runs are executed (``run``, ``tune``)."""
    parser.add_argument(
        "--jobs", type=int, default=None, help="worker processes (default: local cores)"
    )
    parser.add_argument(
        "--backend",
        choices=BACKENDS,
        default="process",
        help="serial, local process pool, or Dask (default: process)",
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


def load_grid(path: Path) -> tuple[Grid, TrialFunction | None, RunLayout, str]:
    """The grid of the config at ``path``, its run function (None: the runner's default, for an
    experiment), its results layout and the config's text.

    Raises:
        UserError: the file cannot be read, or its TOML, kind or content is invalid.
    """
    text = read_config_text(path)
    return (*grid_of_text(text, path), text)


def grid_of_text(text: str, path: Path) -> tuple[Grid, TrialFunction | None, RunLayout]:
    """The grid, run function and results layout of config ``text`` (read from ``path``, or
    written by a ``skidnav study`` shortcut from its flags).

    Raises:
        UserError: its TOML, kind or content is invalid (naming ``path``).
    """
    document = parse_tables(text, path)
    kind = study_kind(document, path)
    if kind == EXPERIMENT_KIND:
        return config_from_tables(document, path), None, EXPERIMENT_LAYOUT
    chosen = study(kind)
    grid = chosen.grid(document, path)
    return grid, chosen.trial(grid), chosen.layout


def run_grid(
    loaded: tuple[Grid, TrialFunction | None, RunLayout],
    text: str,
    args: argparse.Namespace,
    config_path: Path | None = None,
) -> RunOutcome:
    """Run (or resume) the ``loaded`` grid of config ``text`` in ``args.out`` (default
    ``runs/<name>``) on the backend of ``args`` (:func:`add_backend_arguments`, ``no_progress``);
    print where the results are."""
    grid, trial, layout = loaded
    out = check_output_dir(args.out if args.out is not None else Path("runs") / grid.name)
    outcome = run_experiment(
        grid,
        out,
        backend=args.backend,
        jobs=args.jobs,
        scheduler=args.scheduler,
        trial=trial,
        source_text=text,
        config_path=config_path,
        progress=not args.no_progress,
        layout=layout,
    )
    print(
        f"{outcome.n_runs} runs in {outcome.out_dir} ({outcome.executed} run now, "
        f"{outcome.skipped} already done) in {outcome.wall_time:.1f} s"
    )
    return outcome


def run_command(args: argparse.Namespace) -> int:
    """Run the experiment or study; print where the results are."""
    allow_env_modules(args.env_module)
    grid, trial, layout, text = load_grid(args.config)
    outcome = run_grid((grid, trial, layout), text, args, args.config)
    if args.report:
        from skidnav.experiments.report.html import write_report

        print(f"report: {write_report(outcome.out_dir)}")
    return 0
