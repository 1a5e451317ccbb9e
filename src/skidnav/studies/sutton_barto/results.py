"""The textbook checks read back from their results directory: per example the runs' curves and
counts, and the files ``skidnav study reproduce sutton-barto`` writes from them (the CSV rows).

Everything here comes from the run files' tables (:class:`~skidnav.experiments.store.ResultStore`),
so a study run by ``skidnav run`` on any backend, resumed or not, gives the numbers of the same
config run in one go. Runs are taken in seed order; an unfinished run is left out of every mean.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd

from skidnav.errors import UserError
from skidnav.experiments.store import ResultStore
from skidnav.studies.sutton_barto.grid import (
    DYNA_MAZE_EPISODES,
    LAYOUT,
    Check,
    TextbookChecks,
)
from skidnav.studies.sutton_barto.trial import cumulative_reward

NEAR_OPTIMAL = 18.0
"""Mean actions per episode counted as near-optimal on the Dyna Maze (shortest path 14: ε = 0.1
keeps the mean 2–4 actions above it, as in Sutton & Barto (2018) Figure 8.2)."""


class ChecksResults(NamedTuple):
    """The checks as their results directory holds them.

    Attributes:
        config: the checks.
        episodes: one row per run and episode (the runner's episode table: ``agent`` the check's
            label, ``seed`` the run index, ``episode`` from 1, ``steps``, ``reward``).
        summaries: one row per finished run (the runner's summaries: the run's summary keys).
    """

    config: TextbookChecks
    episodes: pd.DataFrame
    summaries: pd.DataFrame


def read_results(run_dir: Path | str) -> ChecksResults:
    """The finished runs of the checks in ``run_dir``.

    Raises:
        UserError: not a results directory of the checks, or no finished run.
        CorruptFileError: a damaged file, named.
    """
    store = ResultStore(run_dir, LAYOUT)
    config: TextbookChecks = store.config()
    if not store.finished():
        raise UserError(f"{run_dir}: no finished runs")
    episodes, summaries = store.load_tables()
    return ChecksResults(config, episodes, summaries)


def checks_of(results: ChecksResults, example: str) -> list[Check]:
    """The checks of ``example`` with at least one finished run, in config order."""
    done = set(results.summaries["agent"])
    return [c for c in results.config.checks() if c.example == example and c.label in done]


def _runs(frame: pd.DataFrame, check: Check) -> pd.DataFrame:
    """The rows of ``check`` in ``frame``, in seed (and episode) order."""
    order = ["seed", "episode"] if "episode" in frame.columns else ["seed"]
    return frame[frame["agent"] == check.label].sort_values(order)


def dyna_maze_steps(results: ChecksResults) -> dict[int, np.ndarray]:
    """Example 8.1: Dyna-Q's n → actions per episode, int64 (runs, 50), runs in seed order."""
    steps = {}
    for check in checks_of(results, "dyna-maze"):
        rows = _runs(results.episodes, check)["steps"].to_numpy(np.int64)
        steps[check.planning_steps] = rows.reshape(-1, DYNA_MAZE_EPISODES)
    return steps


def dyna_maze_rows(results: ChecksResults) -> pd.DataFrame:
    """``dyna_maze.csv``: planning_steps, run (index), episode, steps; n by n, run by run."""
    frames = []
    for check in checks_of(results, "dyna-maze"):
        rows = _runs(results.episodes, check)
        frame = pd.DataFrame(
            {"run": rows["seed"], "episode": rows["episode"], "steps": rows["steps"]}
        )
        frame.insert(0, "planning_steps", check.planning_steps)
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


def first_episode_below(mean_steps: np.ndarray, level: float = NEAR_OPTIMAL) -> int:
    """First episode (1-based) whose mean actions are ≤ ``level``; −1 if none.

    >>> first_episode_below(np.array([800.0, 40.0, 17.5, 19.0]))
    3
    """
    below = np.nonzero(mean_steps <= level)[0]
    return int(below[0]) + 1 if below.size else -1


def changing_curves(results: ChecksResults, example: str) -> dict[str, np.ndarray]:
    """Examples 8.2/8.3: agent → cumulative reward after each time step, float64 (runs, steps),
    runs in seed order."""
    curves = {}
    for check in checks_of(results, example):
        rows = _runs(results.episodes, check)
        per_run = [
            cumulative_reward(run["steps"].to_numpy(), run["reward"].to_numpy())
            for _, run in rows.groupby("seed", sort=True)
        ]
        curves[check.agent] = np.array(per_run)
    return curves


def changing_rows(curves: dict[str, np.ndarray]) -> pd.DataFrame:
    """``blocking_maze.csv`` / ``shortcut_maze.csv``: agent, step (from 1), the mean cumulative
    reward over runs."""
    frames = []
    for agent, per_run in curves.items():
        mean = per_run.mean(axis=0)
        steps = np.arange(1, len(mean) + 1)
        frames.append(pd.DataFrame({"agent": agent, "step": steps, "mean_cumulative_reward": mean}))
    return pd.concat(frames, ignore_index=True)


def sweeping_updates(results: ChecksResults) -> dict[Check, pd.DataFrame]:
    """Example 8.4: check → its runs in seed order: ``seed``, ``n_states``, ``updates`` until
    the greedy path is near-optimal (NaN: never)."""
    return {
        check: _runs(results.summaries, check)[["seed", "n_states", "updates"]]
        for check in checks_of(results, "prioritized-sweeping")
    }


def sweeping_rows(updates: dict[Check, pd.DataFrame]) -> pd.DataFrame:
    """``prioritized_sweeping.csv``: agent, n_states, run (index), updates until near-optimal
    (−1: never); agent by agent, scale by scale, run by run."""
    frames = []
    for check, runs in updates.items():
        counts = runs["updates"].to_numpy(float)
        columns = {
            "agent": check.agent,
            "n_states": runs["n_states"].to_numpy(float).astype(np.int64),
            "run": runs["seed"].to_numpy(),
            "updates": np.where(np.isnan(counts), -1, counts).astype(np.int64),
        }
        frames.append(pd.DataFrame(columns))
    return pd.concat(frames, ignore_index=True)


def median_updates(runs: pd.DataFrame) -> float:
    """The median updates until near-optimal over ``runs`` (of :func:`sweeping_updates`), a run
    that never got there counting as infinitely many.

    >>> median_updates(pd.DataFrame({"updates": [10.0, float("nan"), 30.0]}))
    30.0
    """
    counts = runs["updates"].to_numpy(float)
    return float(np.median(np.where(np.isnan(counts), math.inf, counts)))
