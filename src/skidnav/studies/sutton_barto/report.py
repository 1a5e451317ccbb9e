"""The tables and plots of the textbook checks (Sutton & Barto (2018) ch. 8), from their results
directory (:mod:`skidnav.studies.sutton_barto.results`): the report's section
(:func:`report_section`), the summary ``skidnav study reproduce sutton-barto`` prints
(:func:`summary_text`) and the CSV and PNG files it writes (:func:`write_outputs`).

One table per example, of means (medians for Example 8.4) over the finished runs:

* Dyna Maze (Example 8.1): per n, the mean actions of episode 2 and of the last 10 episodes, the
  first episode whose mean is ≤ 18 actions, and the book's "episodes to near-optimal";
* blocking and shortcut mazes (Examples 8.2/8.3): per agent, the mean reward gathered before and
  after the walls change;
* prioritized sweeping (Example 8.4): per maze size, the median value updates until the greedy
  path is near-optimal for Dyna-Q and prioritized sweeping, and their ratio.
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd

from skidnav.experiments.report.page import image, table
from skidnav.files.atomic import write_user_file
from skidnav.studies.sutton_barto.grid import CHANGING_MAZES, SWEEP_AGENTS
from skidnav.studies.sutton_barto.results import (
    NEAR_OPTIMAL,
    ChecksResults,
    changing_curves,
    changing_rows,
    checks_of,
    dyna_maze_rows,
    dyna_maze_steps,
    first_episode_below,
    median_updates,
    read_results,
    sweeping_rows,
    sweeping_updates,
)
from skidnav.studies.sutton_barto.trial import PATH_TOLERANCE

TITLES = {
    "dyna-maze": "Dyna Maze (Example 8.1): Dyna-Q with n planning steps",
    "blocking-maze": "Blocking maze (Example 8.2): Dyna-Q and Dyna-Q+",
    "shortcut-maze": "Shortcut maze (Example 8.3): Dyna-Q and Dyna-Q+",
    "prioritized-sweeping": "Prioritized sweeping and Dyna-Q (Example 8.4)",
}
FILES = {
    "dyna-maze": "dyna_maze",
    "blocking-maze": "blocking_maze",
    "shortcut-maze": "shortcut_maze",
    "prioritized-sweeping": "prioritized_sweeping",
}
"""Example → the name of its CSV and PNG files."""
BOOK_EPISODES = {0: "≈ 25", 5: "≈ 5", 50: "≈ 3"}
"""Sutton & Barto (2018) §8.2: episodes until Dyna-Q with n planning steps is near-optimal."""


class ExampleOutput(NamedTuple):
    """What one example shows and writes."""

    table: pd.DataFrame
    """The table, string cells."""
    rows: pd.DataFrame
    """The rows of its CSV file."""
    plot: Callable[[], bytes]
    """Draws its plot (PNG bytes; matplotlib is imported only then)."""
    note: str
    """What the table's numbers are."""


def _line_plot(
    curves: dict[str, np.ndarray | tuple[np.ndarray, np.ndarray]],
    xlabel: str,
    ylabel: str,
    x0: int = 1,
) -> Callable[[], bytes]:
    def draw() -> bytes:
        from skidnav.experiments.report.plots import line_plot  # matplotlib when drawn

        return line_plot(curves, xlabel, ylabel, x0)

    return draw


def dyna_maze_output(results: ChecksResults) -> ExampleOutput:
    """Example 8.1's table, rows and plot (mean actions per episode from episode 2)."""
    steps = dyna_maze_steps(results)
    means = {n: per_run.mean(axis=0) for n, per_run in steps.items()}
    runs = {n: len(per_run) for n, per_run in steps.items()}
    cells = [
        {
            "n": str(n),
            "runs": str(runs[n]),
            "episode 2 [actions]": f"{mean[1]:.1f}",
            "last 10 episodes [actions]": f"{mean[-10:].mean():.1f}",
            f"first episode with mean ≤ {NEAR_OPTIMAL:g}": str(first_episode_below(mean)),
            "book: episodes to near-optimal": BOOK_EPISODES.get(n, "–"),
        }
        for n, mean in means.items()
    ]
    curves: dict[str, np.ndarray | tuple[np.ndarray, np.ndarray]] = {
        f"n = {n}": mean[1:] for n, mean in means.items()
    }
    note = "Mean actions per episode over the runs; the shortest path is 14 actions (−1: never)."
    return ExampleOutput(
        pd.DataFrame(cells),
        dyna_maze_rows(results),
        _line_plot(curves, "episode", "steps per episode", x0=2),
        note,
    )


def changing_output(results: ChecksResults, example: str) -> ExampleOutput:
    """Example 8.2's or 8.3's table, rows and plot (mean cumulative reward per time step)."""
    curves = changing_curves(results, example)
    n_steps, change = CHANGING_MAZES[example]
    cells = []
    for agent, per_run in curves.items():
        before, total = per_run[:, change - 1], per_run[:, -1]
        cells.append(
            {
                "agent": agent,
                "runs": str(len(per_run)),
                f"reward in steps 1–{change}": f"{before.mean():.1f}",
                f"reward in steps {change + 1}–{n_steps}": f"{(total - before).mean():.1f}",
            }
        )
    means: dict[str, np.ndarray | tuple[np.ndarray, np.ndarray]] = {
        agent: per_run.mean(axis=0) for agent, per_run in curves.items()
    }
    note = f"Mean reward gathered over the runs; the walls change after step {change}."
    return ExampleOutput(
        pd.DataFrame(cells),
        changing_rows(curves),
        _line_plot(means, "time step", "cumulative reward"),
        note,
    )


def sweeping_output(results: ChecksResults) -> ExampleOutput:
    """Example 8.4's table, rows and plot (median updates against the maze's scale)."""
    updates = sweeping_updates(results)
    medians = {(check.agent, check.scale): median_updates(runs) for check, runs in updates.items()}
    states = {check.scale: int(runs["n_states"].iloc[0]) for check, runs in updates.items()}
    cells = []
    for scale in sorted(states):
        dyna, sweep = (medians.get((agent, scale), math.nan) for agent, _ in SWEEP_AGENTS)
        cells.append(
            {
                "states": str(states[scale]),
                "runs": str(max(len(runs) for c, runs in updates.items() if c.scale == scale)),
                "dyna-q [updates]": _count(dyna),
                "prioritized sweeping [updates]": _count(sweep),
                "ratio": _ratio(dyna, sweep),
            }
        )
    curves: dict[str, np.ndarray | tuple[np.ndarray, np.ndarray]] = {}
    for agent in dict.fromkeys(check.agent for check in updates):
        points = sorted((s, m) for (a, s), m in medians.items() if a == agent)
        x, y = (np.array(values, dtype=float) for values in zip(*points, strict=True))
        curves[agent] = (x, np.where(np.isfinite(y), y, np.nan))  # never: not drawn
    note = (
        f"Median value updates until the greedy path is first within {PATH_TOLERANCE:g}× the "
        "shortest (real and planning updates for Dyna-Q, queue updates for prioritized "
        "sweeping); a run that never gets there counts as infinitely many."
    )
    plot = _line_plot(curves, "maze scale", "updates until optimal")
    return ExampleOutput(pd.DataFrame(cells), sweeping_rows(updates), plot, note)


def _ratio(dyna: float, sweep: float) -> str:
    """``"12.3×"``: how many times fewer updates prioritized sweeping needed; ``"–"`` unless
    both medians are finite."""
    if not (math.isfinite(dyna) and math.isfinite(sweep) and sweep > 0):
        return "–"
    return f"{dyna / sweep:.1f}×"


def _count(value: float) -> str:
    if math.isnan(value):
        return "–"
    return f"{value:.0f}" if math.isfinite(value) else "never"


def example_outputs(results: ChecksResults) -> dict[str, ExampleOutput]:
    """Example → its output, for the examples with finished runs, in config order."""
    outputs = {}
    for example in results.config.examples:
        if not checks_of(results, example):
            continue
        if example == "dyna-maze":
            outputs[example] = dyna_maze_output(results)
        elif example == "prioritized-sweeping":
            outputs[example] = sweeping_output(results)
        else:
            outputs[example] = changing_output(results, example)
    return outputs


def summary_text(results: ChecksResults) -> str:
    """The tables as text: per example its title, table and note."""
    parts = []
    for example, output in example_outputs(results).items():
        parts += [TITLES[example], output.table.to_string(index=False), output.note, ""]
    return "\n".join(parts)


def write_outputs(out: Path, results: ChecksResults) -> list[Path]:
    """Per example ``NAME.csv`` (:mod:`skidnav.studies.sutton_barto.results`' rows) then
    ``NAME.png`` in ``out``, each written all-or-nothing; returns their paths."""
    written = []
    for example, output in example_outputs(results).items():
        csv_path, png_path = (out / f"{FILES[example]}.{suffix}" for suffix in ("csv", "png"))
        write_user_file(csv_path, output.rows.to_csv(index=False).encode(), "CSV file")
        write_user_file(png_path, output.plot(), "plot")
        written += [csv_path, png_path]
    return written


def report_section(run_dir: Path | str) -> str:
    """The checks' section of the report of ``run_dir`` (an HTML fragment): per example its
    table, note and plot."""
    results = read_results(run_dir)
    config = results.config
    parts = [
        "<h2>Sutton &amp; Barto (2018), chapter 8: textbook checks</h2>",
        f"<p>{len(results.summaries)} of {config.n_runs} runs finished "
        f"({config.runs} per check, root seed {config.root_seed}).</p>",
    ]
    for example, output in example_outputs(results).items():
        parts += [
            f"<h3>{html.escape(TITLES[example])}</h3>",
            table(output.table),
            f'<p class="note">{html.escape(output.note)}</p>',
            image(output.plot(), TITLES[example]),
        ]
    return "".join(parts)
