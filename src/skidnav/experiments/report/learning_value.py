"""The value of learning the kinematic model (docs/kinematic-value.md): a section of the
experiment report for every agent of the grid run with more than one ``kinematic_model``.

An agent variant swept over ``kinematic_model`` (``sweep = { kinematic_model = [...] }``) gives
arms that differ in nothing else: "learned" (the thesis's online fit), "prior" (the nominal robot,
never refitted) and "true" (the simulator's expected velocities, a reference no robot offers).
Two differences are reported, each paired by world (map, floor, seed: every arm meets the same
worlds and evaluation seeds), mean over worlds with the report's bootstrap interval:

* **value of learning** = learned − prior;
* **left to learn** = true − learned.

Metrics (summary columns, :mod:`skidnav.experiments.metrics`): seconds of driving to the first
success and to sustained greedy success (≥ 90 % of the evaluation rollouts, from then on), the
same in episodes, the success rate, the driving over all the training episodes and the
collisions per episode. A time is censored (NaN) in a run that never got there: an arm's mean
is over the runs that got there (their count shown), a difference over the worlds where both
arms did. Wherever the interval of learned − prior contains 0, the text says so plainly: no
difference measured. The driving times are also given as each arm's Kaplan–Meier median over
all its runs (:data:`SURVIVAL_METRICS`), which counts the runs that never got there. On a grid
run in parts (``skidnav run --runs``) the arms' cells cover the worlds every arm ran, and the
heading says how many (:func:`~skidnav.experiments.report.analysis.common_worlds`).
"""

from __future__ import annotations

import html
from typing import NamedTuple

import numpy as np
import pandas as pd

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.report.analysis import (
    cells,
    common_worlds,
    paired_difference,
    stats_rng,
)
from skidnav.experiments.report.page import interval_text, table
from skidnav.statistics.formatting import plural
from skidnav.statistics.intervals import Interval, bootstrap_interval, rowwise_mean
from skidnav.statistics.survival import median_interval

MODELS = ("learned", "prior", "true")
"""The arms of a kinematic-model comparison, in table order."""

COMPARISONS = (("learned", "prior"), ("true", "learned"))
"""(first, second) of each paired difference: the value of learning, what is left to learn."""

VALUE_METRICS = {
    "seconds_to_first_success": "driving to the first success [s]",
    "seconds_to_success90": "driving to ≥ 90 % greedy success, sustained [s]",
    "episodes_to_first_success": "episodes to the first success",
    "episodes_to_success90": "episodes to ≥ 90 % greedy success, sustained",
    "success_rate": "success rate (all episodes)",
    "driving_seconds": "driving over all episodes [s]",
    "collisions_per_episode": "collisions per episode",
}
"""Summary columns compared, with their display names."""

CENSORED = frozenset(key for key in VALUE_METRICS if "_to_" in key)
"""The times among :data:`VALUE_METRICS`: NaN where the run never got there."""

SURVIVAL_METRICS = {
    "seconds_to_first_success": "driving to the first success, Kaplan–Meier median [s]",
    "seconds_to_success90": "driving to ≥ 90 % greedy success, Kaplan–Meier median [s]",
}
"""The driving times also given as Kaplan–Meier medians over all of an arm's runs, a run that
never got there censored at its whole driving time (``driving_seconds``): unlike the means over
the runs that got there, they count the runs that did not (∞: more than half never did)."""


class ModelArms(NamedTuple):
    """One agent variant run with several kinematic models.

    Attributes:
        name: display name: the agent's label without its ``kinematic_model`` choice.
        labels: agent label of each model present (keys of :data:`MODELS`).
    """

    name: str
    labels: dict[str, str]


def model_arms(config: ExperimentConfig) -> list[ModelArms]:
    """The agent variants of ``config`` that differ only in ``kinematic_model`` and cover at
    least one comparison of :data:`COMPARISONS`, in config order."""
    groups: dict[tuple[object, ...], dict[str, str]] = {}
    for agent in config.agents:
        params = agent.params_dict()
        model = params.pop("kinematic_model", None)
        if model in MODELS:
            key = (agent.name, agent.discretization, tuple(sorted(params.items())))
            groups.setdefault(key, {})[str(model)] = agent.label
    arms = []
    for variant, labels in groups.items():
        if any(first in labels and second in labels for first, second in COMPARISONS):
            arms.append(ModelArms(_arm_name(str(variant[0]), labels), labels))
    names = [arm.name for arm in arms]
    if len(set(names)) < len(names):  # labels written by hand: name each by its first label
        arms = [ModelArms(next(iter(arm.labels.values())), arm.labels) for arm in arms]
    return arms


def _arm_name(name: str, labels: dict[str, str]) -> str:
    """The common label of the arms with the ``kinematic_model=…`` part dropped (the agent
    name when nothing else is left)."""
    label = next(iter(labels.values()))
    head, _, rest = label.partition("[")
    kept = [part for part in rest.rstrip("]").split(",") if part and "kinematic_model=" not in part]
    return f"{head}[{','.join(kept)}]" if kept else (head or name)


def value_of_learning(summaries: pd.DataFrame, config: ExperimentConfig) -> pd.DataFrame:
    """One row per (map, preset, arms, metric, comparison): map, preset, agent (the arms'
    name), metric, comparison ("learned − prior" or "true − learned"), difference,
    difference_low, difference_high, pairs (worlds compared), no_difference (the interval
    contains 0). Each difference is over the worlds both arms ran (:func:`common_worlds`), so
    paired by world on a grid run only in part too (none compared, ``pairs`` 0, where one arm
    has no run yet). Comparisons between arms the config does not both have are left out."""
    records = []
    metrics = [metric for metric in VALUE_METRICS if metric in summaries.columns]
    for map_label, preset, rows in cells(summaries):
        for arms in model_arms(config):
            for first, second in COMPARISONS:
                if first not in arms.labels or second not in arms.labels:
                    continue
                a, b = arms.labels[first], arms.labels[second]
                both = common_worlds(rows, a, b)
                for metric in metrics:
                    keys = (map_label, preset, a, b, metric, "model value")
                    interval, pairs, _ = paired_difference(both, a, b, metric, config, *keys)
                    records.append({
                        "map": map_label, "preset": preset, "agent": arms.name,
                        "metric": metric, "comparison": f"{first} − {second}",
                        "difference": interval.estimate, "difference_low": interval.low,
                        "difference_high": interval.high, "pairs": pairs,
                        "no_difference": bool(interval.low <= 0.0 <= interval.high),
                    })  # fmt: skip
    return pd.DataFrame.from_records(records)


def _arm_cell(
    rows: pd.DataFrame, label: str, metric: str, config: ExperimentConfig, *cell: str
) -> str:
    """An arm's mean [interval] of ``metric`` over its runs that have it, and for a time how
    many of its runs got there; the generator keyed by the ``cell`` (map, preset)."""
    values = rows.loc[rows["agent"] == label, metric].to_numpy(np.float64)
    rng = stats_rng(config, *cell, label, metric, "model arm")
    mean: Interval = bootstrap_interval(
        values, rng, statistic=rowwise_mean, n_resamples=config.bootstrap_samples,
        confidence=config.confidence,
    )  # fmt: skip
    text = interval_text(mean.estimate, mean.low, mean.high)
    if metric in CENSORED:
        text += f" ({int(np.isfinite(values).sum())}/{values.size} reached)"
    return text


def _difference_cell(row: pd.Series) -> str:
    """A difference with its interval and the worlds compared; "no difference measured" when
    its interval contains 0."""
    text = interval_text(row["difference"], row["difference_low"], row["difference_high"])
    words = " — no difference measured" if row["no_difference"] else ""
    return f"{text} ({plural(int(row['pairs']), 'world')}){words}"


def sentences(rows: pd.DataFrame) -> list[str]:
    """The learned − prior results of one table in words: what showed no difference, what
    differed, what could not be compared (fewer than 2 worlds where both arms got there)."""
    value = rows[rows["comparison"] == "learned − prior"]
    same, differs, unmeasured = [], [], []
    for _, row in value.iterrows():
        name = VALUE_METRICS[str(row["metric"])]
        if not np.isfinite(row["difference_low"]):
            unmeasured.append(f"{name} ({plural(int(row['pairs']), 'world')})")
        elif row["no_difference"]:
            same.append(name)
        else:
            differs.append(f"{name} {signed(row)}")
    said = []
    if same:
        said.append("Learned − prior: no difference measured in " + "; ".join(same) + ".")
    if differs:
        said.append("Learned − prior, intervals clear of 0: " + "; ".join(differs) + ".")
    if unmeasured:
        said.append("Not comparable (too few worlds where both got there): "
                    + "; ".join(unmeasured) + ".")  # fmt: skip
    return said


def signed(row: pd.Series) -> str:
    """A difference as "+1.2 [+0.3, +2.0]"."""
    text = interval_text(row["difference"], row["difference_low"], row["difference_high"])
    return text if text.startswith(("−", "-")) else f"+{text}"


def learning_value_section(summaries: pd.DataFrame, config: ExperimentConfig) -> str:
    """The report section (module docs); empty when no agent was run with two kinematic
    models."""
    arms_list = model_arms(config)
    values = value_of_learning(summaries, config)
    if not arms_list or values.empty:
        return ""
    parts = [
        "<h2>Value of learning the kinematic model</h2>",
        "<p class='note'>Each agent run with its kinematic model learned online, held at the "
        "prior (the nominal robot) and, where the simulator offers it, the true one; "
        "differences paired by world (map, floor, seed), mean over worlds with a "
        f"{config.confidence:.0%} bootstrap interval. Driving time: actions × the robot's "
        "action duration, summed over the training episodes up to the first success, or up "
        "to the first episode from which every greedy evaluation had ≥ 90 % of its rollouts "
        f"reach the goal (at least {config.convergence_window} evaluations of evidence). A "
        "run that never got there is censored: left out of its arm's mean, and of the "
        "differences, which are over the worlds where both arms got there; the Kaplan–Meier "
        "medians count it, censored at its whole driving time (∞: more than half of the "
        "runs never got there). On a grid run in parts, each arm's cells cover the worlds "
        "every arm ran, and each difference the worlds both of its arms ran.</p>",
    ]
    for (map_label, preset, agent), rows in values.groupby(["map", "preset", "agent"], sort=False):
        arms = next(arms for arms in arms_list if arms.name == agent)
        ran = summaries[(summaries["map"] == map_label) & (summaries["preset"] == preset)]
        cell = common_worlds(ran, *arms.labels.values())
        heading = f"{agent} · {map_label} · {preset}"
        worlds = cell["seed"].nunique()
        if worlds < config.seeds:  # a grid run in parts: the arms' cells cover the same worlds
            heading += f" ({worlds} of {plural(config.seeds, 'world')}, those every arm ran)"
        parts.append(f"<h3>{html.escape(heading)}</h3>")
        frame = _cell_frame(rows, cell, arms, config, (str(map_label), str(preset)))
        parts.append(table(frame, labels=1))
        parts.append("".join(f"<p>{html.escape(text)}</p>" for text in sentences(rows)))
    return "".join(parts)


def _cell_frame(
    rows: pd.DataFrame,
    cell: pd.DataFrame,
    arms: ModelArms,
    config: ExperimentConfig,
    labels: tuple[str, str],
) -> pd.DataFrame:
    """The table of one (map, preset, arms): a row per metric, a column per arm and per
    comparison."""
    records = []
    for metric, title in VALUE_METRICS.items():
        mine = rows[rows["metric"] == metric]
        if mine.empty:
            continue
        record = {"metric": title}
        for model in MODELS:
            if model in arms.labels:
                record[model] = _arm_cell(cell, arms.labels[model], metric, config, *labels)
        for _, row in mine.iterrows():
            record[str(row["comparison"])] = _difference_cell(row)
        records.append(record)
        if metric in SURVIVAL_METRICS and "driving_seconds" in cell.columns:
            survival = {"metric": SURVIVAL_METRICS[metric]}
            for model in MODELS:
                if model in arms.labels:
                    survival[model] = _survival_cell(
                        cell, arms.labels[model], metric, config, *labels
                    )
            records.append(survival)
    return pd.DataFrame.from_records(records).fillna("–")  # no paired difference of medians


def arm_survival(
    rows: pd.DataFrame,
    label: str,
    metric: str,
    config: ExperimentConfig,
    *cell: str,
    censor_at: float | None = None,
) -> Interval:
    """An arm's Kaplan–Meier median of the time ``metric`` with its bootstrap interval over its
    runs (:data:`SURVIVAL_METRICS`): a run that never got there censored at ``censor_at``, or,
    by default, at its whole ``driving_seconds``; the generator keyed by the ``cell`` (map,
    preset)."""
    runs = rows[rows["agent"] == label]
    reached = runs[metric].notna().to_numpy()
    horizon = runs["driving_seconds"] if censor_at is None else censor_at
    times = np.where(reached, runs[metric], horizon).astype(np.float64)
    rng = stats_rng(config, *cell, label, metric, "model arm survival")
    return median_interval(times, reached, rng, n_resamples=config.bootstrap_samples,
                           confidence=config.confidence)  # fmt: skip


def _survival_cell(
    rows: pd.DataFrame, label: str, metric: str, config: ExperimentConfig, *cell: str
) -> str:
    """:func:`arm_survival` as text."""
    median = arm_survival(rows, label, metric, config, *cell)
    return interval_text(median.estimate, median.low, median.high)
