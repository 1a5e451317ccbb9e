"""The speed history: ``make bench``'s recorded figures per commit, kept by airspeed velocity
(asv) in ``.asv/results/<machine>/`` (not in git: figures of one machine compare with that
machine's only).

``benchmarks/tracked`` says what is recorded (:mod:`key_figures` and :mod:`time_to_learn`),
measured in this Python environment (``asv run --python=same``) and filed under the current
commit, whatever the state of the work tree: commit first.

Usage (from the repository root)::

    python benchmarks/history.py record             # measure and record the current commit
    python benchmarks/history.py compare [--factor 2] [--recorded]

``compare`` records the current commit (unless ``--recorded``: its record is taken as it is),
then names every figure that moved by more than ``--factor`` since the last commit recorded
before it on this machine (``asv compare --only-changed``; less is better for every figure).
``make bench`` records; ``make bench-compare`` compares.
"""

from __future__ import annotations

import argparse
import ast
import os
import platform
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

from asv import results as asv_results

HERE = Path(__file__).resolve().parent
CONFIG = HERE / "asv.conf.json"
RESULTS = HERE.parent / ".asv" / "results"
MACHINE = platform.node()
"""asv's machine name: its default, the host name."""
FACTOR = 2.0
"""How far a figure must move for ``compare`` to name it (×). Measured twice on the same code on
the loaded 2-core CI machine, figures moved by up to 1.85× (the plain-Python baselines measured
in a subprocess move most)."""

Figures = dict[tuple[str, str], float]
"""(benchmark, parameter) → recorded value, e.g. ``("figures.KeyFigures.track_relative_time",
"vector-discrete")``."""


class Record(NamedTuple):
    """The figures recorded for one commit on this machine."""

    commit: str
    measured_at: float  # [ms since the epoch] when the last figure was measured
    figures: Figures


def asv(*arguments: str, quiet: bool = False) -> None:
    """Run ``asv`` with :data:`CONFIG`. asv drops ``PYTHONPATH`` for the benchmarks; a path given
    to this process (e.g. ``PYTHONPATH=src``) is passed on as asv's ``ASV_PYTHONPATH``, so the
    code measured is the code this process imports. ``quiet``: its output is not shown."""
    environment = dict(os.environ)
    if "PYTHONPATH" in environment:  # made absolute: asv runs the benchmarks elsewhere
        paths = [str(Path(path).resolve()) for path in environment["PYTHONPATH"].split(os.pathsep)]
        environment.setdefault("ASV_PYTHONPATH", os.pathsep.join(paths))
    command = [sys.executable, "-m", "asv", "--config", str(CONFIG), *arguments]
    subprocess.run(command, check=True, env=environment, cwd=HERE.parent, capture_output=quiet)


def head() -> str:
    """The current commit's hash."""
    return subprocess.run(
        ["git", "rev-parse", "HEAD"], capture_output=True, text=True, check=True, cwd=HERE
    ).stdout.strip()


def record() -> str:
    """Measure and record the figures of the current commit on this machine; its hash.
    CalledProcessError when a figure could not be measured (asv exits with 2)."""
    commit = head()
    asv("machine", "--yes", "--machine", MACHINE, quiet=True)  # asv's description of this machine
    asv("run", "--python=same", f"--set-commit-hash={commit}", "--machine", MACHINE,
        "--show-stderr")  # fmt: skip
    return commit


def records() -> list[Record]:
    """Every commit recorded on this machine, the most recently measured last."""
    found = []
    for result in asv_results.iter_results_for_machine(str(RESULTS), MACHINE):
        figures: Figures = {}
        for key in result.get_all_result_keys():
            params = result.get_result_params(key)
            values = result.get_result_value(key, params)
            for param, value in zip(params[0], values, strict=True):
                figures[key, ast.literal_eval(param)] = float("nan") if value is None else value
        found.append(Record(result.commit_hash, max(result.started_at.values()), figures))
    return sorted(found, key=lambda found_record: found_record.measured_at)


def recorded(commit: str) -> Record:
    """The record of ``commit``; LookupError when it has none on this machine."""
    for found in records():
        if found.commit == commit:
            return found
    raise LookupError(f"no figures recorded for {commit[:8]} on {MACHINE} in {RESULTS}")


def compare(factor: float, measure: bool) -> None:
    """Name the figures that moved by more than ``factor`` from the last commit recorded before
    the current one to the current one (recorded first when ``measure``)."""
    commit = record() if measure else recorded(head()).commit
    earlier = [found for found in records() if found.commit != commit]
    if not earlier:
        print(f"no other commit recorded on {MACHINE}: nothing to compare {commit[:8]} with")
        return
    print(f"figures that moved by more than {factor:g}× from {earlier[-1].commit[:8]} to "
          f"{commit[:8]} (less is better for every figure: + worse, - better):")  # fmt: skip
    asv("compare", "--machine", MACHINE, "--factor", str(factor), "--only-changed",
        "--split", earlier[-1].commit, commit)  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=("record", "compare"))
    parser.add_argument("--factor", type=float, default=FACTOR)
    parser.add_argument("--recorded", action="store_true", help="compare without measuring")
    args = parser.parse_args()
    if args.command == "record":
        record()
    else:
        compare(args.factor, not args.recorded)


if __name__ == "__main__":
    main()
