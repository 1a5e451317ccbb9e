"""``skidnav tune CONFIG``: hyperparameter search with Optuna on tuning maps; resumable."""

from __future__ import annotations

import argparse
import dataclasses
import logging
from pathlib import Path
from typing import Any

from skidnav.commands.parsing import path_argument
from skidnav.commands.run import add_backend_arguments, add_env_module_argument
from skidnav.commands.verbs import HELP
from skidnav.envs.registration import allow_env_modules
from skidnav.errors import UserError
from skidnav.extras import require
from skidnav.files.outputs import check_output_dir
from skidnav.studies.tuning.config import load_tune_config_and_text


def add_parser(subparsers: Any) -> None:
    """Add the ``tune`` subcommand."""
    parser = subparsers.add_parser(
        "tune",
        help=HELP["tune"],
        description="Search the hyperparameters of every agent with a [tune.space.<label>] "
        "table of CONFIG, on tuning maps kept apart from the evaluation maps, and write the "
        "best ones to DIR/tuned.toml (an experiment config). Started again on the same --out "
        "directory it continues each study up to its trial count (docs/tuning.md); a second "
        "search on a directory in use is refused.",
    )
    parser.add_argument(
        "config", type=path_argument, help="experiment config with a [tune] table (TOML)"
    )
    parser.add_argument(
        "--out",
        type=path_argument,
        default=None,
        help="study directory (default: runs/<config name>)",
    )
    parser.add_argument(
        "--trials",
        type=int,
        default=None,
        help="finished trials per agent, instead of [tune] trials (e.g. a small budget)",
    )
    add_backend_arguments(parser)
    add_env_module_argument(parser)
    parser.set_defaults(func=tune_command)


def _print_trial(label: str, trial: Any, finished: int, target: int) -> None:
    value = "" if trial.value is None else f" {trial.value:.1f}"
    params = ", ".join(
        f"{key}={value:.4g}" if isinstance(value, float) else f"{key}={value}"
        for key, value in trial.params.items()
    )
    state = trial.state.name.lower()
    print(f"{label}: trial {trial.number} {state}{value} ({params}) [{finished}/{target}]")


def tune_command(args: argparse.Namespace) -> int:
    """Run the search; print each trial and where tuned.toml is."""
    require("tuning", "skidnav tune")
    import optuna

    from skidnav.studies.tuning.search import tune_experiment

    if not args.verbose:
        optuna.logging.set_verbosity(logging.WARNING)
    allow_env_modules(args.env_module)
    config, tune, text = load_tune_config_and_text(args.config)
    if args.trials is not None:
        try:
            tune = dataclasses.replace(tune, trials=args.trials)
        except ValueError as error:
            raise UserError(f"--trials: {error}") from None
    out = check_output_dir(args.out if args.out is not None else Path("runs") / config.name)
    outcome = tune_experiment(
        config,
        tune,
        out,
        backend=args.backend,
        jobs=args.jobs,
        scheduler=args.scheduler,
        source_text=text,
        config_path=args.config,
        on_trial=_print_trial,
    )
    counts = ", ".join(f"{label} {count}" for label, count in outcome.finished.items())
    print(
        f"tuned hyperparameters: {outcome.tuned} ({outcome.executed} trials run now; finished: "
        f"{counts}) in {outcome.wall_time:.1f} s"
    )
    return 0
