"""What the ``skidnav study`` shortcuts share: their flags become a study config, which runs as
``skidnav run`` runs a config file (:func:`skidnav.studies.loading.run_loaded`): the same grid, the
same runner and backends, a results directory (``--out``) that resumes, and the config's text
saved there as ``config.toml`` (``skidnav run OUT/config.toml --out OUT`` resumes it too)."""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.commands.parsing import path_argument
from skidnav.commands.run import add_backend_arguments, run_with_arguments
from skidnav.experiments.runner import RunOutcome
from skidnav.files.configtables import toml_document
from skidnav.studies.loading import LoadedConfig, parse_grid

FLAGS = Path("<flags>")
"""Where a shortcut's config comes from, as its errors name it."""


def add_run_arguments(parser: argparse.ArgumentParser, name: str) -> None:
    """``--out DIR`` (default ``runs/NAME``), ``--jobs``, ``--backend``, ``--scheduler`` and
    ``--no-progress``, as ``skidnav run`` has them."""
    parser.add_argument(
        "--out",
        type=path_argument,
        default=None,
        help=f"results directory (default: runs/{name}); started again on it, the runs already "
        "finished are kept",
    )
    add_backend_arguments(parser, default=None)
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def run_text(text: str, args: argparse.Namespace) -> tuple[LoadedConfig, RunOutcome]:
    """(the config, what the runner did) of the study config ``text`` run with the arguments of
    :func:`add_run_arguments` into ``args.out`` (default ``runs/<name>``); prints what was run.

    Raises:
        UserError: an invalid setting (naming its key), an output that cannot be written, or
            one holding another config's results.
    """
    loaded = parse_grid(text, FLAGS)
    return loaded, run_with_arguments(loaded, args)


def run_document(document: Mapping[str, Any], args: argparse.Namespace) -> tuple[Any, RunOutcome]:
    """:func:`run_text` of a config ``document`` (its TOML text written by
    :func:`skidnav.files.configtables.toml_document`); returns (the grid, what the runner did)."""
    loaded, outcome = run_text(toml_document(document), args)
    return loaded.grid, outcome
