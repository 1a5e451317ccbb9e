"""What every command-line parser of skidnav shares (the ``skidnav`` command's and the reference
robot's): no option taken by a prefix of its name (``--secret X`` is not ``--secret-file X``),
the words after an unknown option not printed (they may be a secret), and the number types of
arguments whose errors are one line.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from typing import Any

from skidnav.errors import unknown_arguments


class StrictParser(argparse.ArgumentParser):
    """An argument parser that takes an option only by its whole name and names unknown
    arguments by :func:`~skidnav.errors.unknown_arguments` (their values left out)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs["allow_abbrev"] = False
        super().__init__(*args, **kwargs)

    def parse_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> argparse.Namespace:
        """argparse's, the unknown arguments named by :func:`~skidnav.errors.unknown_arguments`."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            self.error(f"unrecognized arguments: {unknown_arguments(extras)}")
        return parsed


def positive_number(text: str) -> float:
    """A finite number > 0, for an argument's ``type`` (``nan``, ``inf``, 0 refused in one line).

    >>> positive_number("2.5")
    2.5
    >>> positive_number("nan")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a finite number > 0, got 'nan'
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value
