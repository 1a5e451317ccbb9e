"""Benchmark of the experiment runner: wall time and runs/s of configs/quick.toml (the demo).

Usage (from the repository root)::

    PYTHONPATH=src python benchmarks/bench_experiments.py [CONFIG] [--jobs N] [--backend B]

Prints the wall time of the whole sweep (compilation included: the first run of each algorithm
compiles or loads the numba kernels), runs per second, and per algorithm the mean training time
of one run (compilation excluded: each process warms the kernels up before a run's clock starts,
see ``skidnav.experiments.trial.warm_up``) and its ratio to Q-learning's, all measured in this
one run. The target for
configs/quick.toml is at most 2 minutes on 2 cores (``make demo``); configs/thesis.toml (30 seeds
× 5000 episodes) takes about 30 minutes and is not part of ``make bench``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import pandas as pd

from skidnav.experiments.configfile import load_config
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import ResultStore

ROOT = Path(__file__).resolve().parents[1]
BUDGET_S = 120.0


def main() -> None:
    """Run the sweep in a temporary directory and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", type=Path, default=ROOT / "configs" / "quick.toml")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--backend", default="process")
    args = parser.parse_args()
    config = load_config(args.config)
    with tempfile.TemporaryDirectory() as out:
        started = time.perf_counter()
        outcome = run_experiment(config, out, backend=args.backend, jobs=args.jobs)
        elapsed = time.perf_counter() - started
        _, summaries = ResultStore(out).load_tables()
    print(
        f"config            {args.config.name} ({outcome.n_runs} runs, {config.episodes} episodes)"
    )
    print(f"backend           {args.backend}, {args.jobs} jobs")
    print(f"wall time         {elapsed:.1f} s (budget {BUDGET_S:.0f} s: {elapsed / BUDGET_S:.2f}×)")
    print(f"throughput        {outcome.n_runs / elapsed:.3f} runs/s")
    per_algorithm = summaries.groupby("algorithm", sort=False)["wall_time"].mean()
    reference = float(per_algorithm.get("q-learning", per_algorithm.iloc[0]))
    table = pd.DataFrame(
        {"mean run training time [s]": per_algorithm, "× q-learning": per_algorithm / reference}
    )
    print(table.round(2).to_string())


if __name__ == "__main__":
    main()
