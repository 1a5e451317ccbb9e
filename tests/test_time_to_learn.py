"""make bench's time to learn (``benchmarks/time_to_learn.py``): what it counts, from the runner's
tables, and how the speed table shows it."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from skidnav.experiments.configfile import load_config
from tests.benchmark_scripts import benchmark

time_to_learn = benchmark("time_to_learn")


def _tables() -> tuple[pd.DataFrame, pd.DataFrame]:
    """Three runs of 6 episodes, 0.5 s each: converged at 2 and 4 (their first good windows at
    1), the third censored at 5."""
    runs = ["a", "b", "c"]
    episodes = pd.DataFrame({
        "run_id": np.repeat(runs, 6), "agent": "x", "episode": np.tile(np.arange(1, 7), 3),
        "wall_time": 0.5, "planning_updates": 10, "length": 20,
    })  # fmt: skip
    summaries = pd.DataFrame({
        "run_id": runs, "agent": "x", "convergence_episode": [2.0, 4.0, 5.0],
        "converged": [1.0, 1.0, 0.0], "first_window_episode": [1.0, 1.0, 1.0],
    })  # fmt: skip
    return episodes, summaries


def test_learned_counts_the_reports_convergence_episode_with_intervals() -> None:
    config = load_config(time_to_learn.CONFIG)
    learned = time_to_learn.learned(*_tables(), config)
    assert (learned.runs, learned.converged) == (3, 2)
    # The reports' convergence episode (not the first good window, 1 for every run): KM median
    # of 2, 4 and 5 censored is 4; training up to it 0.5 s per episode.
    assert learned.episode.estimate == 4.0
    assert learned.seconds.estimate == 2.0
    assert learned.episode.low == 2.0  # the smallest median a resample can have
    assert math.isinf(learned.episode.high)  # resamples with two censored runs of three
    assert learned.updates_per_second == 20.0 and learned.steps_per_second == 40.0


def test_interval_text() -> None:
    interval = time_to_learn.Interval(0.481, 0.31, math.inf)
    assert time_to_learn.with_interval(interval, " s") == "0.481 s [0.31 s, ∞]"
    assert time_to_learn.with_interval(time_to_learn.Interval(3.0, math.nan, math.nan)) == "3"


def test_speed_table_shows_an_unmeasured_end_as_infinite() -> None:
    speed_table = benchmark("speed_table")
    figures = {}
    for agent in time_to_learn.agent_labels():
        for name, value in (("seconds", 0.5), ("seconds_low", 0.25), ("seconds_high", math.nan),
                            ("episodes", 120.0), ("episodes_low", 80.0), ("episodes_high", 300.0),
                            ("unconverged_runs", 1.0), ("time_per_update", 100.0),
                            ("time_per_step", 10.0)):  # fmt: skip
            figures[speed_table.LEARNING.format(name), agent] = value
    rows = speed_table.learning_table(figures)
    runs, _ = time_to_learn.budget()
    assert rows[2].split(" | ")[1:4] == [
        f"{runs - 1}/{runs}",
        "120 [80, 300]",
        "**0.5 s [0.25 s, ∞]**",
    ]
