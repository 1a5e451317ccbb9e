"""``skidnav report RUN_DIR``: write the self-contained HTML report of a results directory, the
report of its kind (``config.json``): an experiment's with the sections studies add to it, or a
study's section in the same page (:func:`write_results_report`; ``skidnav run --report`` too).
For an experiment it then prints the report's one-line verdict
(:mod:`skidnav.experiments.report.verdict`), as ``skidnav run`` does."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, NamedTuple

from skidnav.commands.parsing import path_argument
from skidnav.commands.verbs import HELP
from skidnav.errors import UserError
from skidnav.files.outputs import check_output_file


def add_parser(subparsers: Any) -> None:
    """Add the ``report`` subcommand."""
    parser = subparsers.add_parser(
        "report",
        help=HELP["report"],
        description="Aggregate a results directory written by 'skidnav run' (an experiment or "
        "a study, by the kind its config.json names) into one HTML file (tables, embedded "
        "figures, the config), written atomically: an interrupted report leaves the previous "
        "one or none.",
    )
    parser.add_argument("run_dir", type=path_argument, help="results directory")
    parser.add_argument(
        "-o",
        "--output",
        type=path_argument,
        default=None,
        help="output file (default: RUN_DIR/report.html)",
    )
    parser.add_argument(
        "--study",
        action="store_true",
        help="instead: RUN_DIR/study.md, the real-robot study's tables (success per agent and "
        "floor, rough vs slippery, minus the baseline), e.g. of configs/physics-study.toml",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=report_command)


class ResultsReport(NamedTuple):
    """A results directory's report written: where, and (for an experiment) its verdict
    line."""

    path: Path
    verdict: str | None


def print_report(written: ResultsReport) -> None:
    """Print the verdict line (an experiment's) and where the report is."""
    if written.verdict is not None:
        print(written.verdict)
    print(f"report: {written.path}")


def report_command(args: argparse.Namespace) -> int:
    """Write the report; print its verdict (an experiment's) and its path."""
    if not args.run_dir.is_dir():
        raise UserError(f"{args.run_dir}: no such results directory")
    if args.output is not None:
        check_output_file(args.output, "--output")
    if args.study:
        return study_command(args.run_dir, args.output or args.run_dir / "study.md")
    print_report(write_results_report(args.run_dir, args.output, progress=not args.no_progress))
    return 0


def write_results_report(
    run_dir: Path, output: Path | None = None, *, progress: bool = False
) -> ResultsReport:
    """Write the report of ``run_dir`` by its kind (its study, :func:`~skidnav.studies.kind.
    study_of_results`) to ``output`` (default ``RUN_DIR/report.html``), atomically, an
    experiment's with a progress bar on stderr when ``progress``; returns its path and verdict
    line (None for a study without one, :class:`~skidnav.studies.kind.VerdictStudy`).

    Raises:
        UserError: the results are missing, damaged or of no known kind, or the report cannot
            be written there.
    """
    from skidnav.experiments.store import results_kind
    from skidnav.studies.kind import VerdictStudy, study_of_results

    chosen = study_of_results(results_kind(run_dir), run_dir)
    if isinstance(chosen, VerdictStudy):
        return ResultsReport(*chosen.write_report(run_dir, output, progress=progress))
    from skidnav.experiments.report.page import report_path, study_report, write_page

    text = study_report(run_dir, chosen.layout, chosen.report(run_dir))
    return ResultsReport(write_page(report_path(run_dir, output), text), None)


def study_command(run_dir: Path, output: Path) -> int:
    """Write the study's tables of ``run_dir`` to ``output``; print its path."""
    from skidnav.files.atomic import write_user_file
    from skidnav.studies.hardware.experiment_tables import experiment_study_report

    write_user_file(output, experiment_study_report(run_dir).encode("utf-8"), "study tables")
    print(f"study tables: {output}")
    return 0
