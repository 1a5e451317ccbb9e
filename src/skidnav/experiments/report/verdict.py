"""The one-line verdict of an experiment: its headline speed-up over the baseline with its
interval, the first line of the report (``id="verdict"``) and the line ``skidnav run`` and
``skidnav report`` print when an experiment is done (:func:`verdict_text`, written once for both).

The speed-up is the report's (:func:`~skidnav.experiments.report.analysis.compare_to_baseline`):
the Kaplan–Meier median convergence episode of the baseline over the agent's, with its
percentile-bootstrap interval over seeds, paired by seed (docs/experiments.md, "Statistics").
The headline is the agent the experiment is about (:func:`headline_agent`: the config's
``headline``, else the thesis's agent ``dyna-full``, else the first agent after the baseline),
never the largest of several estimates, in its first map × preset cell with a known speed-up;
a speed-up under 1 is said as a slow-down (its reciprocal, "slower"). "Significant" means the
interval excludes 1, and an interval's ends are printed with enough digits to show which side
of 1 they are on (:func:`ratio_text`). Then how many of the comparisons were significantly
faster (interval above 1) or slower (below 1). Over fewer than
:data:`~skidnav.statistics.formatting.MIN_INTERVAL_SEEDS` seeds the interval is replaced by a
caveat and nothing is called significant.

An experiment that only compares kinematic models (every agent an arm of
:func:`~skidnav.experiments.report.learning_value.model_arms`: learned, held at the prior, true)
is about the value of learning, not about converging to the oracle's band, which a planner over
continuous wheel speeds may never do: its verdict (:func:`learning_verdict`) gives, in the first
cell, each arm's Kaplan–Meier median driving time to sustained ≥ 90 % greedy success with the
runs that got there, and the paired difference in success rate with its interval; then in how
many of the report's paired differences (metric × cell) the interval is clear of 0.
"""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.report.analysis import compare_to_baseline, speedup_of
from skidnav.experiments.report.learning_value import (
    COMPARISONS,
    arm_survival,
    model_arms,
    signed,
    value_of_learning,
)
from skidnav.experiments.store import ResultStore
from skidnav.statistics.formatting import MIN_INTERVAL_SEEDS, plural, readable, seeds_caveat
from skidnav.statistics.intervals import Interval
from skidnav.statistics.survival import SpeedupInterval

PREFIX = "Verdict: "
THESIS_AGENT = "dyna-full"
"""The agent of the thesis the project reproduces: the headline when the config names none."""
MOST_DIGITS = 4
"""Most decimals :func:`ratio_text` prints to show on which side of 1 a ratio is."""


def ratio_text(value: float, digits: int = 1) -> str:
    """A ratio with ``digits`` decimals, or more (up to :data:`MOST_DIGITS`) when fewer would
    round a value that is not 1 to 1: which side of 1 it is stays visible.

    >>> [ratio_text(value) for value in (5.23, 1.004, 0.996, 1.0, math.inf)]
    ['5.2', '1.004', '0.996', '1.0', '∞']
    """
    if math.isfinite(value) and value != 1.0:
        while digits < MOST_DIGITS and round(value, digits) == 1.0:
            digits += 1
    return readable(value, digits)


def slowdown(speedup: SpeedupInterval) -> SpeedupInterval:
    """The reciprocal of a speed-up: how many times slower (a bound's side swaps).

    >>> slowdown(SpeedupInterval(0.25, 0.2, 0.5))
    SpeedupInterval(estimate=4.0, low=2.0, high=5.0, bound='')
    >>> slowdown(SpeedupInterval(0.5, 0.0, 0.9, "upper"))
    SpeedupInterval(estimate=2.0, low=1.1111111111111112, high=inf, bound='lower')
    """

    def inverse(value: float) -> float:
        return math.inf if value == 0.0 else 1.0 / value

    side = {"lower": "upper", "upper": "lower"}.get(speedup.bound, speedup.bound)
    return SpeedupInterval(
        inverse(speedup.estimate), inverse(speedup.high), inverse(speedup.low), side
    )


def speedup_words(speedup: SpeedupInterval, seeds: int, confidence: float) -> tuple[str, str]:
    """(the estimate, what backs it): ``("5.2×", "95% interval [3.1, 9.8], 6 seeds")``; ≥ / ≤
    for a bound (:class:`~skidnav.statistics.survival.SpeedupInterval`), the caveat instead of the
    interval over too few seeds; ends near 1 with the digits that tell their side
    (:func:`ratio_text`).

    >>> speedup_words(SpeedupInterval(5.23, 3.1, 9.8), 6, 0.95)
    ('5.2×', '95% interval [3.1, 9.8], 6 seeds')
    >>> speedup_words(SpeedupInterval(4.0, 2.5, math.inf, "lower"), 6, 0.95)
    ('≥ 4.0×', '95% interval [2.5, ∞), 6 seeds')
    >>> speedup_words(SpeedupInterval(1.8, 1.004, 3.2), 6, 0.95)
    ('1.8×', '95% interval [1.004, 3.2], 6 seeds')
    >>> speedup_words(SpeedupInterval(4.0, 2.5, 7.0), 2, 0.95)
    ('4.0×', '2 seeds: too few for an interval')
    """
    sign = {"lower": "≥ ", "upper": "≤ "}.get(speedup.bound, "")
    estimate = f"{sign}{ratio_text(speedup.estimate)}×"
    if seeds < MIN_INTERVAL_SEEDS:
        return estimate, seeds_caveat(seeds)
    if math.isnan(speedup.low) or math.isnan(speedup.high):
        return estimate, plural(seeds, "seed")
    opening, low = ("(", "0") if speedup.bound == "upper" else ("[", ratio_text(speedup.low))
    closing = ")" if math.isinf(speedup.high) else "]"
    bounds = f"{opening}{low}, {ratio_text(speedup.high)}{closing}"
    return estimate, f"{confidence:.0%} interval {bounds}, {plural(seeds, 'seed')}"


def headline_agent(config: ExperimentConfig) -> str:
    """The label of the agent the verdict leads with: the config's ``headline``, else the first
    agent named :data:`THESIS_AGENT` (not the baseline), else the first agent after the
    baseline (the config's order); the baseline itself when it is the only agent."""
    if config.headline:
        return config.headline
    others = [agent for agent in config.agents if agent.label != config.baseline]
    thesis = [agent.label for agent in others if agent.name == THESIS_AGENT]
    return (thesis or [agent.label for agent in others] or [config.baseline])[0]


def _seeds(summaries: pd.DataFrame, row: pd.Series) -> int:
    """Seeds of the comparison ``row`` (runs of its agent in its cell)."""
    mine = summaries[
        (summaries["map"] == row["map"]) & (summaries["preset"] == row["preset"])
        & (summaries["agent"] == row["agent"])
    ]  # fmt: skip
    return int(mine["seed"].nunique())


def _claim(speedup: SpeedupInterval, seeds: int, confidence: float) -> tuple[str, str]:
    """(``"5.2× faster"`` or ``"4.0× slower"``, what backs it, led by whether it is
    significant when there is an interval)."""
    direction = "faster"
    if speedup.estimate < 1.0:
        speedup, direction = slowdown(speedup), "slower"
    estimate, backing = speedup_words(speedup, seeds, confidence)
    if seeds >= MIN_INTERVAL_SEEDS and not math.isnan(speedup.low):
        excludes = speedup.low > 1.0 or speedup.high < 1.0
        backing = f"{'significant' if excludes else 'not significant'}: {backing}"
    return f"{estimate} {direction}", backing


def verdict_text(
    comparisons: pd.DataFrame, summaries: pd.DataFrame, config: ExperimentConfig
) -> str:
    """The verdict line (module doc) of an experiment's comparisons with the baseline
    (:func:`compare_to_baseline` of ``summaries``), starting "Verdict: "."""
    base = config.baseline
    if _compares_models_only(config):
        return learning_verdict(summaries, config)
    if comparisons.empty:
        return f"{PREFIX}one agent only ({base}): no speed-up to report."
    agent = headline_agent(config)
    mine = comparisons[comparisons["agent"] == agent]
    known = mine[mine["speedup"].notna()]
    if known.empty:
        return (
            f"{PREFIX}speed-up of {agent} over {base} unknown: in every cell both stayed "
            "unconverged in more than half of their runs."
        )
    row = known.iloc[0]
    seeds = _seeds(summaries, row)
    claim, backing = _claim(speedup_of(row), seeds, config.confidence)
    line = (
        f"{PREFIX}{agent} converges {claim} than {base} ({backing}; median convergence "
        f"episode, {row['map']} · {row['preset']})"
    )
    if seeds < MIN_INTERVAL_SEEDS:
        return line + "."
    faster = int((comparisons["speedup_low"] > 1.0).sum())
    slower = int((comparisons["speedup_high"] < 1.0).sum())
    compared = plural(len(comparisons), "comparison")
    return (
        f"{line}; significantly faster in {faster}, slower in {slower}, of {compared} "
        "(agent × cell)."
    )


def _compares_models_only(config: ExperimentConfig) -> bool:
    """Whether every agent of ``config`` is an arm of a kinematic-model comparison."""
    arms = {label for group in model_arms(config) for label in group.labels.values()}
    return bool(arms) and all(agent.label in arms for agent in config.agents)


def _median_words(median: Interval) -> str:
    """A Kaplan–Meier median in seconds: "20 s", or "∞" when more than half never got there."""
    text = readable(median.estimate)
    return text if math.isinf(median.estimate) else f"{text} s"


def learning_verdict(summaries: pd.DataFrame, config: ExperimentConfig) -> str:
    """The verdict line of a kinematic-model comparison (module doc), starting "Verdict: "."""
    values = value_of_learning(summaries, config)
    if values.empty:
        return f"{PREFIX}no cell has two kinematic models to compare."
    arms = model_arms(config)[0]
    first, second = next(pair for pair in COMPARISONS if set(pair) <= set(arms.labels))
    comparison = f"{first} − {second}"
    mine = values[(values["agent"] == arms.name) & (values["comparison"] == comparison)]
    map_label, preset = mine.iloc[0]["map"], mine.iloc[0]["preset"]
    cell = summaries[(summaries["map"] == map_label) & (summaries["preset"] == preset)]
    said = [
        f"{PREFIX}value of learning the kinematic model of {arms.name}, {comparison} "
        f"(paired by world, {map_label} · {preset})"
    ]
    if {"seconds_to_success90", "driving_seconds"} <= set(cell.columns) and bool(
        cell["driving_seconds"].notna().all()
    ):
        medians, reached = [], []
        for model in (first, second):
            rows = cell[cell["agent"] == arms.labels[model]]
            median = arm_survival(
                cell, arms.labels[model], "seconds_to_success90", config, map_label, preset
            )
            medians.append(_median_words(median))
            reached.append(f"{int(rows['seconds_to_success90'].notna().sum())} of {len(rows)}")
        said.append(
            f"driving to sustained ≥ 90 % greedy success, Kaplan–Meier median {medians[0]} "
            f"against {medians[1]} ({reached[0]} and {reached[1]} runs got there)"
        )
    rate = mine[mine["metric"] == "success_rate"]
    if not rate.empty:
        row = rate.iloc[0]
        pairs = int(row["pairs"])
        if pairs < MIN_INTERVAL_SEEDS or not math.isfinite(row["difference_low"]):
            backing = seeds_caveat(pairs)
        else:
            words = "not significant" if row["no_difference"] else "significant"
            backing = f"{words}: {config.confidence:.0%} interval, {plural(pairs, 'world')}"
        said.append(f"success rate {signed(row)} ({backing})")
    measured = mine[np.isfinite(mine["difference_low"].to_numpy(np.float64))]
    clear = int((~measured["no_difference"].astype(bool)).sum())
    counts = f"clear of 0 in {clear}, no difference measured in {len(measured) - clear}"
    if len(mine) > len(measured):
        counts += f", too few worlds to compare in {len(mine) - len(measured)}"
    head, *rest = said
    return (
        head + (": " + "; ".join(rest) if rest else "") + f"; {comparison} {counts}, of "
        f"{plural(len(mine), 'comparison')} (metric × cell)."
    )


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
