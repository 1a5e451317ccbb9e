"""``skidnav study reproduce sutton-barto``: the textbook checks of Sutton & Barto (2018) ch. 8, a
shortcut for the ``kind = "sutton-barto-checks"`` config (:mod:`skidnav.studies.sutton_barto`;
``configs/sutton-barto-checks.toml`` holds its defaults).

It writes the config of its flags (saved as ``--out DIR/config.toml``) and runs it as ``skidnav
run`` does (:mod:`skidnav.commands.shortcut`): the same runs and files, resumed when started again
on the same ``--out``. Then, from the results directory, it prints one table per example and
writes to ``--out``, each file atomically:

* ``dyna_maze.csv/.png`` — Example 8.1: actions per episode of Dyna-Q with n = 0, 5, 50 planning
  steps (γ = 0.95, α = 0.1, ε = 0.1), ``--runs`` runs of 50 episodes;
* ``blocking_maze.*``, ``shortcut_maze.*`` — Examples 8.2/8.3: mean cumulative reward of Dyna-Q
  and Dyna-Q+ per time step;
* ``prioritized_sweeping.csv/.png`` — Example 8.4: value updates until the greedy path is
  near-optimal, Dyna-Q and prioritized sweeping on Dyna Mazes scaled ×1, ×2, ×3.
"""

from __future__ import annotations

import argparse
from typing import Any

from skidnav.commands.shortcut import add_run_arguments, run_text
from skidnav.errors import UserError
from skidnav.studies.sutton_barto.grid import KIND, TextbookChecks, checks_toml

FLAGS = ("runs", "root_seed")
"""The flags, each a :class:`TextbookChecks` field of the same name."""
COMMENT = "the config of `skidnav study reproduce sutton-barto`: skidnav run it to resume"


def add_parser(subparsers: Any) -> None:
    """Register ``skidnav study reproduce`` and its targets (``sutton-barto``), each with its
    own help."""
    parser = subparsers.add_parser(
        "reproduce",
        help="reproduce reference results (resumable)",
        description="Reproduce reference results as a study config written from the flags "
        "(resumable on the same --out). Targets: sutton-barto.",
    )
    targets = parser.add_subparsers(dest="target", required=True, metavar="TARGET")
    _add_sutton_barto(targets)


def _add_sutton_barto(targets: Any) -> None:
    """``skidnav study reproduce sutton-barto``."""
    defaults = TextbookChecks()
    parser = targets.add_parser(
        "sutton-barto",
        help="the Dyna-Q checks of Sutton & Barto (2018) ch. 8, Examples 8.1–8.4",
        description="Run the Sutton & Barto (2018) ch. 8 checks (Examples 8.1 Dyna Maze, 8.2 "
        "Blocking Maze, 8.3 Shortcut Maze, 8.4 prioritized sweeping) as a study config written "
        "from these flags (resumable on the same --out), print their tables and write their CSV "
        "and PNG files to --out.",
    )
    parser.add_argument(
        "--runs", type=int, default=defaults.runs, help="independent runs of every check"
    )
    parser.add_argument(
        "--root-seed", type=int, default=defaults.root_seed, help="root of every run's streams"
    )
    add_run_arguments(parser, KIND)
    parser.set_defaults(func=reproduce_command)


def checks_from_flags(args: argparse.Namespace) -> TextbookChecks:
    """The checks of the flags (the other settings the config's defaults); UserError naming the
    flag of a bad value."""
    try:
        return TextbookChecks(**{key: getattr(args, key) for key in FLAGS})
    except ValueError as error:
        message = str(error)
        for key in FLAGS:
            message = message.replace(f" {key} ", f" --{key.replace('_', '-')} ")
        raise UserError(message) from None


def reproduce_command(args: argparse.Namespace) -> int:
    """Run (or resume) the checks; print their tables; write their CSV and PNG files."""
    from skidnav.studies.sutton_barto.report import summary_text, write_outputs
    from skidnav.studies.sutton_barto.results import read_results

    out = run_text(checks_toml(checks_from_flags(args), COMMENT), args)[1].out_dir
    results = read_results(out)
    print(summary_text(results))
    write_outputs(out, results)
    print(f"wrote CSV and PNG files to {out}")
    return 0
