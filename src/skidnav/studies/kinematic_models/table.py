"""The table of a kinematic-model comparison: per model and output, each metric's mean over
seeds with its 95 % percentile-bootstrap interval
(:func:`skidnav.statistics.intervals.bootstrap_interval`),
as text (``skidnav study kinematic compare``) and as the report's HTML section.

The intervals are drawn from one generator seeded 0, model by model, output by output, metric
by metric (RMSE, coverage, width, fit time), each over the seeds in seed order: the same
results give the same table, wherever it is printed.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.store import ResultStore
from skidnav.robot.params import RobotParams
from skidnav.statistics.formatting import MIN_INTERVAL_SEEDS, interval, plural, seeds_caveat
from skidnav.statistics.intervals import bootstrap_interval
from skidnav.studies.kinematic_models.grid import LAYOUT, OUTPUTS, ModelComparison

HEADER = ("RMSE [mm/s | mrad/s]", "90 % coverage", "width [mm/s | mrad/s]", "fit [s]")
"""The metric columns: held-out RMSE and interval width in thousandths of the output's unit, the
coverage of the 90 % interval, the fit time."""
_WIDTHS, _DIGITS, _SCALES = (26, 24, 26, 22), (2, 3, 2, 2), (1000.0, 1.0, 1000.0, 1.0)


def describe(comparison: ModelComparison) -> str:
    """One line: the condition, the log's split and the window."""
    dt = RobotParams().dt
    n_train = comparison.n_train
    return (
        f"{comparison.slip}, drift A = {comparison.drift:g} over P = {comparison.period:g} s; "
        f"per seed {comparison.samples:,} sub-steps ({comparison.samples * dt:g} s): the first "
        f"{n_train:,} fitted, the other {comparison.samples - n_train:,} predicted; window "
        f"{comparison.window}; means over {plural(comparison.seeds, 'seed')}"
        + (
            " [95 % bootstrap interval]"
            if comparison.seeds >= MIN_INTERVAL_SEEDS
            else f" [95 % bootstrap interval, not meaningful: {seeds_caveat(comparison.seeds)}]"
        )
    )


def table_rows(comparison: ModelComparison, summaries: pd.DataFrame) -> list[list[str]]:
    """One row per model and output: model, output and a cell ``mean [low, high]`` per metric
    of :data:`HEADER`, over the runs of ``summaries`` (one row per model and seed)."""
    rng = np.random.default_rng(0)
    rows = []
    for model in comparison.models:
        runs = summaries[summaries["algorithm"] == model].sort_values("seed")
        for output in OUTPUTS:
            columns = (f"rmse_{output}", f"coverage_{output}", f"width_{output}", "fit_seconds")
            cells = [
                _cell(bootstrap_interval(scale * runs[column].to_numpy(float), rng), digits)
                for column, scale, digits in zip(columns, _SCALES, _DIGITS, strict=True)
            ]
            rows.append([model, output, *cells])
    return rows


def _cell(bounds: tuple[float, float, float], digits: int) -> str:
    """``estimate [low, high]`` (:func:`skidnav.statistics.formatting.interval`: "n/a" when
    undefined, the
    estimate alone over one seed; over fewer than
    :data:`~skidnav.statistics.formatting.MIN_INTERVAL_SEEDS` seeds :func:`describe` says the
    intervals
    mean little)."""
    return interval(*bounds, digits)


def text_table(rows: list[list[str]]) -> list[str]:
    """The lines of the table of :func:`table_rows`, a header first."""
    titles = [f"{title:>{width}s}" for title, width in zip(HEADER, _WIDTHS, strict=True)]
    lines = [f"{'model':6s} {'output':9s} " + " ".join(titles)]
    for model, output, *cells in rows:
        padded = [f"{cell:>{width}s}" for cell, width in zip(cells, _WIDTHS, strict=True)]
        lines.append(f"{model:6s} {output:9s} " + " ".join(padded))
    return lines


def report_section(run_dir: Path) -> str:
    """The comparison's section of the HTML report of ``run_dir``: :func:`describe` and the
    table of :func:`table_rows` (fit time: all three outputs together, one per model and seed).

    Raises:
        UserError: ``run_dir`` holds no comparison results, or none finished.
    """
    store = ResultStore(run_dir, LAYOUT)
    comparison = store.config()
    summaries = store.load_tables()[1]
    frame = pd.DataFrame(table_rows(comparison, summaries), columns=["model", "output", *HEADER])
    return (
        "<h2>Kinematic models: Bayesian ridge and Gaussian process</h2>"
        f"<p>{html.escape(describe(comparison))}; {len(summaries)} of {comparison.n_runs} runs "
        "finished.</p>"
        + frame.to_html(index=False, escape=True, border=0)
        + '<p class="note">Held-out sub-steps predicted from (region, commanded wheel speeds); '
        "coverage of the central 90 % predictive interval (0.90 when calibrated); the fit time "
        "is that of all three outputs together (docs/gp-kinematic.md).</p>"
    )
