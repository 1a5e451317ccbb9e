"""`make bench`: run every benchmarks/bench_*.py in turn (each prints its own figures), then
record the key figures and the time to learn for the current commit (:mod:`history`, airspeed
velocity) and write them as the speed table of docs/speed.md
(:mod:`speed_table`)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import history
import speed_table

HERE = Path(__file__).parent


def main() -> int:
    failures = 0
    for script in sorted(HERE.glob("bench_*.py")):
        print(f"== {script.stem}", flush=True)
        result = subprocess.run([sys.executable, str(script)], cwd=HERE)
        failures += result.returncode != 0
    print("== recorded per commit: the key ratios and the time to learn", flush=True)
    text = speed_table.table(history.recorded(history.record()))
    print(text)
    speed_table.write(text)
    print(f"written to {', '.join(str(path) for path in speed_table.TARGETS)}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
