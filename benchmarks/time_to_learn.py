"""The figure a user feels: how long each agent takes to learn, in wall time.

The runs of :data:`CONFIG` (its comment states the world and the budget) are trained by the
experiment runner (:func:`skidnav.experiments.runner.run_experiment`), one after another on one
core, and per agent:

* **convergence episode**: each run's ``convergence_episode``, the rule every report uses
  (``skidnav.experiments.metrics.convergence_episode``: the first passing episode from which the
  pass share stays at least ``convergence_level`` to the end; not the retired first good
  window, ``first_window_episode``), the Kaplan–Meier median over the runs with its 95 %
  percentile-bootstrap interval (:func:`skidnav.statistics.survival.median_interval`; a run that
  did not converge is censored at its censoring episode; more than half censored: ∞);
* **seconds to learn**: each run's training time [s] of its episodes up to and including its
  convergence episode (neither the evaluation rollouts after each episode, which measure and do
  not learn, nor numba's compilation, done by the runner's warm-up before a run's clock starts,
  are timed), the Kaplan–Meier median and its interval likewise (a run that did not converge
  is censored at its training time up to its censoring episode);
* **planning updates/s** and **real steps/s** over all its training, for comparison with the
  update rates of ``bench_agents.py`` and ``bench_training.py``.

Usage (from the repository root): ``PYTHONPATH=src python benchmarks/time_to_learn.py [CONFIG]``
(default :data:`CONFIG`).
``make bench`` records these figures per commit (``benchmarks/history.py``).
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

import pandas as pd

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.configfile import load_config
from skidnav.experiments.report.analysis import stats_rng
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import ResultStore
from skidnav.statistics.intervals import Interval
from skidnav.statistics.survival import median_interval

CONFIG = Path(__file__).with_name("time_to_learn.toml")


class Learned(NamedTuple):
    """How long one agent took to learn (module doc).

    Attributes:
        runs: runs trained. converged: runs that converged.
        episode: median convergence episode with its interval (∞: most runs did not converge).
        seconds: median training time to convergence [s] with its interval (∞ likewise).
        updates_per_second: planning updates per second of training (0 without planning).
        steps_per_second: real steps per second of training.
    """

    runs: int
    converged: int
    episode: Interval
    seconds: Interval
    updates_per_second: float
    steps_per_second: float


def agent_labels(config_path: Path = CONFIG) -> list[str]:
    """The agents of ``config_path``, in its order."""
    return [agent.label for agent in load_config(config_path).agents]


def budget(config_path: Path = CONFIG) -> tuple[int, str]:
    """(runs per agent, what each run was given) of ``config_path``, e.g. (10, "2000 episodes of
    ≤ 300 actions")."""
    config = load_config(config_path)
    limit = f" of ≤ {config.max_steps} actions" if config.max_steps else ""
    runs = config.seeds * len(config.maps) * len(config.presets)
    return runs, f"{config.episodes} episodes{limit}"


def confidence(config_path: Path = CONFIG) -> float:
    """The level of the intervals of ``config_path``, e.g. 0.95."""
    return load_config(config_path).confidence


def time_to_learn(config_path: Path = CONFIG) -> dict[str, Learned]:
    """Train every run of ``config_path`` (serially, in a temporary folder) and measure how long
    each agent took to learn, by agent label."""
    config = load_config(config_path)
    with tempfile.TemporaryDirectory() as out:
        run_experiment(config, out, backend="serial", jobs=1)
        episodes, summaries = ResultStore(out).load_tables()
    return {
        label: learned(
            episodes[episodes["agent"] == label], summaries[summaries["agent"] == label], config
        )
        for label in agent_labels(config_path)
    }


def learned(episodes: pd.DataFrame, summaries: pd.DataFrame, config: ExperimentConfig) -> Learned:
    """:class:`Learned` of one agent from its runs' tables (``ResultStore.load_tables``); the
    intervals at ``config.confidence`` from ``config.bootstrap_samples`` resamples, seeded by
    the root seed and the agent's label (as the report's cells are)."""
    until = summaries.set_index("run_id")["convergence_episode"]
    learning = episodes[episodes["episode"] <= episodes["run_id"].map(until)]
    seconds = learning.groupby("run_id")["wall_time"].sum().reindex(until.index)
    converged = summaries.set_index("run_id")["converged"].astype(bool).to_numpy()
    training = float(episodes["wall_time"].sum())
    label = str(summaries["agent"].iloc[0]) if len(summaries) else ""

    def median(times: pd.Series, what: str) -> Interval:
        rng = stats_rng(config, "time-to-learn", label, what)
        return median_interval(
            times.to_numpy(), converged, rng,
            n_resamples=config.bootstrap_samples, confidence=config.confidence,
        )  # fmt: skip

    return Learned(
        runs=len(summaries),
        converged=int(converged.sum()),
        episode=median(until, "episode"),
        seconds=median(seconds, "seconds"),
        updates_per_second=float(episodes["planning_updates"].sum()) / training,
        steps_per_second=float(episodes["length"].sum()) / training,
    )


def describe(value: float, unit: str = "") -> str:
    """``value`` for a table: whole from 100 on, else 3 significant digits; "∞" for ∞, "–" for
    NaN."""
    if math.isnan(value):
        return "–"
    if math.isinf(value):
        return "∞"
    return (f"{value:,.0f}" if abs(value) >= 100 else f"{value:.3g}") + unit


def with_interval(interval: Interval, unit: str = "") -> str:
    """``estimate [low, high]`` of :func:`describe`, e.g. "0.48 s [0.31 s, ∞]"; the estimate
    alone when the interval is NaN (one run)."""
    shown = describe(interval.estimate, unit)
    if math.isnan(interval.low) or math.isnan(interval.high):
        return shown
    return f"{shown} [{describe(interval.low, unit)}, {describe(interval.high, unit)}]"


def main() -> None:
    config_path = Path(sys.argv[1]) if len(sys.argv) > 1 else CONFIG
    print(f"time to learn ({config_path.name}):")
    for label, figures in time_to_learn(config_path).items():
        print(
            f"  {label:22s} converged {figures.converged}/{figures.runs}, median episode "
            f"{with_interval(figures.episode)}, {with_interval(figures.seconds, ' s')} of "
            "training; "
            f"{figures.updates_per_second / 1e6:6.2f} M planning updates/s, "
            f"{figures.steps_per_second / 1e3:6.1f} k real steps/s",
            flush=True,
        )


if __name__ == "__main__":
    main()
