"""What the ``skidnav study`` shortcuts share: their flags become a study config, which runs as
``skidnav run`` runs a config file (:func:`skidnav.commands.run.run_grid`): the same grid, the
same runner and backends, a results directory (``--out``) that resumes, and the config's text
saved there as ``config.toml`` (``skidnav run OUT/config.toml --out OUT`` resumes it too)."""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.commands.run import add_backend_arguments, grid_of_text, run_grid
from skidnav.configtables import toml_document
from skidnav.experiments.runner import RunOutcome

FLAGS = Path("<flags>")
"""Where a shortcut's config comes from, as its errors name it."""


def add_run_arguments(parser: argparse.ArgumentParser, name: str) -> None:
    """``--out DIR`` (default ``runs/NAME``), ``--jobs``, ``--backend``, ``--scheduler`` and
    ``--no-progress``, as ``skidnav run`` has them."""
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help=f"results directory (default: runs/{name}); started again on it, the runs already "
        "finished are kept",
    )
    add_backend_arguments(parser)
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def run_document(document: Mapping[str, Any], args: argparse.Namespace) -> tuple[Any, RunOutcome]:
    """(the grid, what the runner did) of the study config ``document`` run with the arguments
    of :func:`add_run_arguments`.

    Raises:
        UserError: an invalid setting (naming its key), an output that cannot be written, or
            one holding another config's results.
    """
    text = toml_document(document)
    loaded = grid_of_text(text, FLAGS)
    return loaded[0], run_grid(loaded, text, args)
