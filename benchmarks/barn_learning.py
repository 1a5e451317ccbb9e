"""The learning table of docs/barn.md ("dyna-full against q-learning"), read from the results
of ``configs/barn-dyna-full-learning.toml`` (a BARN study, learning protocol: one scored run
after each training episode) with the project's statistics.

Per agent, over the worlds (one seed each): the worlds whose last ``WINDOW`` scored runs hold at
least ``NEED`` successes; the Kaplan–Meier median episodes and seconds of driving to the first
success and to sustained success (the first episode ending ``WINDOW`` consecutive scored runs
with at least ``NEED`` successes; a world that never gets there is censored at its last
episode); the mean success share and metric of the last ``WINDOW`` scored runs with 95 %
bootstrap intervals; and, for two agents, their paired differences and the ratio of their
median episodes to a first success.

    python benchmarks/barn_learning.py runs/barn-dyna-full-learning [--agents dyna-full q-learning]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.metrics import window_success_episode
from skidnav.experiments.store import ResultStore
from skidnav.statistics.intervals import bootstrap_interval, difference_interval
from skidnav.statistics.survival import median_interval, speedup_interval
from skidnav.studies.barn.grid import LAYOUT

WINDOW, NEED = 10, 9
"""Sustained success: at least NEED successes in WINDOW consecutive scored runs
(:func:`~skidnav.experiments.metrics.window_success_episode`: 90 % of the window)."""
SEED = 2020
"""Root of the bootstrap streams (one child per statistic: the table is the same every run)."""


def per_world(episodes: pd.DataFrame) -> pd.DataFrame:
    """One row per (agent, world): episodes and driving seconds [s] to the first and the
    sustained success (NaN: never), the success share and mean metric of the last WINDOW scored
    runs, and the run's total driving [s]."""
    rows = {}
    for (agent, world), runs in episodes.sort_values("episode").groupby(["agent", "world"]):
        success = runs["success"].to_numpy(dtype=float)
        driving = runs["driving_seconds"].to_numpy(dtype=float)
        first = np.flatnonzero(success)
        sustained = window_success_episode(success, WINDOW)  # 1-based; NaN: never
        rows[(agent, world)] = {
            "first_episode": first[0] + 1 if first.size else np.nan,
            "first_seconds": driving[first[0]] if first.size else np.nan,
            "sustained_episode": sustained,
            "sustained_seconds": driving[int(sustained) - 1] if sustained == sustained else np.nan,
            "last_success": success[-WINDOW:].mean(),
            "last_metric": runs["metric"].to_numpy(dtype=float)[-WINDOW:].mean(),
            "episodes": float(len(runs)),
            "driving": driving[-1],
        }
    table = pd.DataFrame(rows).T.astype(float)
    table.index.names = ["agent", "world"]
    return table


def _censored(values: pd.Series, limit: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """(times, observed): ``values`` where reached, else ``limit`` (censored)."""
    observed = values.notna().to_numpy(dtype=float)
    return np.where(observed > 0, values.fillna(0).to_numpy(), limit.to_numpy()), observed


def shown(interval: object, scale: float = 1.0) -> str:
    """``estimate [low, high]`` of an interval, divided by ``scale``."""
    low, high = interval.low / scale, interval.high / scale  # type: ignore[attr-defined]
    return f"{interval.estimate / scale:.3g} [{low:.3g}, {high:.3g}]"  # type: ignore[attr-defined]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run_dir", type=Path)
    parser.add_argument("--agents", nargs=2, default=["dyna-full", "q-learning"])
    args = parser.parse_args()
    episodes, _ = ResultStore(args.run_dir, LAYOUT).load_tables()
    table = per_world(episodes)
    streams = iter(np.random.SeedSequence(SEED).spawn(64))
    rng = lambda: np.random.default_rng(next(streams))  # noqa: E731
    print(f"window: last {WINDOW} scored runs; sustained: {NEED} of {WINDOW} consecutive")
    for agent, rows in table.groupby(level="agent"):
        held = (rows["last_success"] >= NEED / WINDOW).sum()
        print(f"\n{agent}: {held} / {len(rows)} worlds with >= {NEED} of the last {WINDOW}")
        for what in ("first", "sustained"):
            for unit, limit, scale in (("episode", "episodes", 1), ("seconds", "driving", 3600)):
                times, seen = _censored(rows[f"{what}_{unit}"], rows[limit])
                median = shown(median_interval(times, seen, rng()), scale)
                name = "episodes" if scale == 1 else "hours of driving"
                print(f"  KM median {name} to {what} success: {median} ({int(seen.sum())} seen)")
        for column in ("last_success", "last_metric"):
            mean = shown(bootstrap_interval(rows[column].to_numpy(), rng()))
            print(f"  {column}, mean over worlds: {mean}")
    a, b = (table.loc[agent] for agent in args.agents)
    print(f"\npaired {args.agents[0]} - {args.agents[1]} ({len(a)} worlds):")
    for column in ("last_success", "last_metric"):
        difference = difference_interval(
            a[column].to_numpy(), b[column].to_numpy(), rng(), paired=True
        )
        print(f"  {column}: {shown(difference)}")
    slow, fast = (_censored(t["first_episode"], t["episodes"]) for t in (b, a))
    ratio = speedup_interval(slow[0], slow[1], fast[0], fast[1], rng())
    print(f"  episodes to a first success, {args.agents[1]} / {args.agents[0]}: {ratio.words()}")


if __name__ == "__main__":
    main()
