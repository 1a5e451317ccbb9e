"""``skidnav study kinematic compare``: the Bayesian-ridge and the Gaussian-process kinematic
models on held-out sub-steps of the fast simulator (docs/gp-kinematic.md).

A shortcut: the flags make a ``kind = "kinematic-models"`` config
(:mod:`skidnav.studies.kinematic_models`), which the runner runs into ``--out`` as
``skidnav run`` does (the config saved there as ``config.toml``; the same command, or ``skidnav
run OUT/config.toml --out OUT``, resumes it); then the table of means over seeds is printed.
"""

from __future__ import annotations

import argparse

from skidnav.commands.shortcut import add_run_arguments, run_text
from skidnav.errors import UserError
from skidnav.experiments.store import ResultStore
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.studies.kinematic_models.grid import MODELS, ModelComparison, comparison_toml
from skidnav.studies.kinematic_models.table import describe, table_rows, text_table

FLAGS = ("seeds", "samples", "slip", "drift", "drift_period", "train_fraction", "window")
"""The flags, each a :class:`ModelComparison` field of the same name (and ``--models``)."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``kinematic`` with its ``compare`` subcommand."""
    parser = subparsers.add_parser("kinematic", help="learned kinematic models")
    actions = parser.add_subparsers(dest="kinematic_command", required=True)
    compare = actions.add_parser(
        "compare",
        help="Bayesian ridge vs Gaussian process on held-out simulated sub-steps (resumable)",
        description="Run a kinematic-models study from its flags into --out and print its table; "
        "started again on the same --out it skips the runs already finished.",
    )
    compare.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1 (worlds and drives)")
    compare.add_argument("--samples", type=int, default=20_000, help="sub-steps logged per seed")
    compare.add_argument("--slip", choices=SLIP_PRESETS, default="slippery", help="slip preset")
    compare.add_argument("--drift", type=float, default=0.0, help="drift amplitude A (0: none)")
    compare.add_argument(
        "--drift-period", type=float, help="drift period [s] (default: the logged time)"
    )
    compare.add_argument(
        "--train-fraction", type=float, default=0.5, help="first part of the log fitted on"
    )
    compare.add_argument("--window", type=int, default=500, help="samples kept per region")
    compare.add_argument(
        "--models",
        default=",".join(MODELS),
        help=f"comma-separated, of {', '.join(MODELS)} (default: both; gp needs the gp extra)",
    )
    add_run_arguments(compare, "kinematic-models")
    compare.set_defaults(func=_compare)


def comparison_from_flags(args: argparse.Namespace) -> ModelComparison:
    """The config of the flags; UserError naming the flag of a bad value."""
    models = tuple(name.strip() for name in args.models.split(",") if name.strip())
    try:
        return ModelComparison(models=models, **{key: getattr(args, key) for key in FLAGS})
    except ValueError as error:
        message = str(error)
        for key in (*FLAGS, "models"):
            message = message.replace(f" {key} ", f" --{key.replace('_', '-')} ")
        raise UserError(message) from None


def _compare(args: argparse.Namespace) -> int:
    comparison = comparison_from_flags(args)
    loaded, outcome = run_text(comparison_toml(comparison), args)
    summaries = ResultStore(outcome.out_dir, loaded.layout).load_tables()[1]
    print(describe(comparison))
    for line in text_table(table_rows(comparison, summaries)):
        print(line)
    return 0
