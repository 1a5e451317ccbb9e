"""Running the command line inside a test."""

from __future__ import annotations

from skidnav.cli import main


def exit_code(argv: list[str]) -> int:
    """``main``'s exit code, argparse's exits included."""
    try:
        return main(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)
