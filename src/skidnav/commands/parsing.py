"""The argument parser of every ``skidnav`` command: its errors are one line.

argparse prints a usage block and then ``prog: error: …``; skidnav's rule for bad input is one
line naming the problem and exit code 2, so every parser and subparser of the command line is an
:class:`OneLineParser` (subparsers inherit their parent's class).
"""

from __future__ import annotations

import argparse
from typing import NoReturn


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are the one line ``skidnav: error: …`` (exit code 2).

    The subcommand's path is named in the line (``skidnav: error: robot run: …``), except for the
    top-level parser.
    """

    def error(self, message: str) -> NoReturn:
        command = self.prog.removeprefix("skidnav").strip()
        where = f"{command}: " if command else ""
        self.exit(2, f"skidnav: error: {where}{message}\n")
