"""The one-line verdict of an experiment: its headline speed-up over the baseline with its
interval, the first line of the report (``id="verdict"``) and the line ``skidnav run`` and
``skidnav report`` print when an experiment is done (:func:`verdict_text`, written once for both).

The speed-up is the report's (:func:`~skidnav.experiments.report.analysis.compare_to_baseline`):
the Kaplan–Meier median convergence episode of the baseline over the agent's, with its
percentile-bootstrap interval over seeds, paired by seed (docs/experiments.md, "Statistics").
The headline is the largest speed-up of any agent in any map × preset cell, then how many of the
comparisons were significantly faster (interval above 1). Over fewer than
:data:`~skidnav.statistics.formatting.MIN_INTERVAL_SEEDS` seeds the interval is replaced by a
caveat.
"""

from __future__ import annotations

import html
import math
from pathlib import Path

import pandas as pd

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.report.analysis import compare_to_baseline, speedup_of
from skidnav.experiments.store import ResultStore
from skidnav.statistics.formatting import MIN_INTERVAL_SEEDS, plural, readable, seeds_caveat
from skidnav.statistics.survival import SpeedupInterval

PREFIX = "Verdict: "


def _seeds(summaries: pd.DataFrame, row: pd.Series) -> int:
    """Seeds of the comparison ``row`` (runs of its agent in its cell)."""
    mine = summaries[
        (summaries["map"] == row["map"]) & (summaries["preset"] == row["preset"])
        & (summaries["agent"] == row["agent"])
    ]  # fmt: skip
    return int(mine["seed"].nunique())


def speedup_words(speedup: SpeedupInterval, seeds: int, confidence: float) -> tuple[str, str]:
    """(the estimate, what backs it): ``("5.2×", "95% interval [3.1, 9.8], 6 seeds")``; ≥ / ≤
    for a bound (:class:`~skidnav.statistics.survival.SpeedupInterval`), the caveat instead of the
    interval
    over too few seeds.

    >>> speedup_words(SpeedupInterval(5.23, 3.1, 9.8), 6, 0.95)
    ('5.2×', '95% interval [3.1, 9.8], 6 seeds')
    >>> speedup_words(SpeedupInterval(4.0, 2.5, math.inf, "lower"), 6, 0.95)
    ('≥ 4.0×', '95% interval [2.5, ∞), 6 seeds')
    >>> speedup_words(SpeedupInterval(4.0, 2.5, 7.0), 2, 0.95)
    ('4.0×', '2 seeds: too few for an interval')
    """
    sign = {"lower": "≥ ", "upper": "≤ "}.get(speedup.bound, "")
    estimate = f"{sign}{readable(speedup.estimate, 1)}×"
    if seeds < MIN_INTERVAL_SEEDS:
        return estimate, seeds_caveat(seeds)
    if math.isnan(speedup.low) or math.isnan(speedup.high):
        return estimate, plural(seeds, "seed")
    opening, low = ("(", "0") if speedup.bound == "upper" else ("[", readable(speedup.low, 1))
    closing = ")" if math.isinf(speedup.high) else "]"
    bounds = f"{opening}{low}, {readable(speedup.high, 1)}{closing}"
    return estimate, f"{confidence:.0%} interval {bounds}, {plural(seeds, 'seed')}"


def verdict_text(
    comparisons: pd.DataFrame, summaries: pd.DataFrame, config: ExperimentConfig
) -> str:
    """The verdict line (module doc) of an experiment's comparisons with the baseline
    (:func:`compare_to_baseline` of ``summaries``), starting "Verdict: "."""
    base = config.baseline
    if comparisons.empty:
        return f"{PREFIX}one agent only ({base}): no speed-up to report."
    known = comparisons[comparisons["speedup"].notna()]
    if known.empty:
        return (
            f"{PREFIX}speed-up over {base} unknown: in every cell both it and the other agents "
            "stayed unconverged in more than half of their runs."
        )
    best = known.iloc[int(known["speedup"].to_numpy().argmax())]
    seeds = _seeds(summaries, best)
    estimate, backing = speedup_words(speedup_of(best), seeds, config.confidence)
    line = (
        f"{PREFIX}{best['agent']} converges {estimate} faster than {base} ({backing}; median "
        f"convergence episode, {best['map']} · {best['preset']})"
    )
    if seeds < MIN_INTERVAL_SEEDS:
        return line + "."
    faster = int((comparisons["speedup_low"] > 1.0).sum())
    compared = plural(len(comparisons), "comparison")
    return f"{line}; significantly faster in {faster} of {compared} (agent × cell)."


def verdict_html(text: str) -> str:
    """The verdict line as the report's first element, ``<p id="verdict">``."""
    rest = text.removeprefix(PREFIX)
    return f'<p id="verdict"><b>Verdict:</b> {html.escape(rest)}</p>'


def experiment_verdict(run_dir: Path | str) -> str:
    """The verdict line of the experiment in ``run_dir`` (what its report opens with).

    Raises:
        UserError: the results are missing or damaged.
    """
    store = ResultStore(run_dir)
    config = store.config()
    summaries = store.load_tables()[1]
    return verdict_text(compare_to_baseline(summaries, config), summaries, config)
