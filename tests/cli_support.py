"""Running the command line inside a test."""

from __future__ import annotations

from collections.abc import Callable

from skidnav.cli import main


def exit_code(argv: list[str], entry: Callable[[list[str]], int] = main) -> int:
    """The exit code of ``entry`` (skidnav's ``main`` unless told), argparse's exits included."""
    try:
        return entry(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)
