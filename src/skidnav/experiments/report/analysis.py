"""Aggregates over seeds and the comparisons behind the thesis claims (Alhawary (2020), ch. 7;
docs/experiments.md, "Statistics").

Every interval is a seeded percentile bootstrap (:mod:`skidnav.statistics.intervals`); each table
cell gets its own generator keyed by the root seed and the cell's labels, so the numbers do not
depend on the order in which they are computed. Agents are compared *paired by seed*: all agents
of a (map, preset) cell meet the same maps and floors (see :mod:`skidnav.experiments.runs`).

:func:`aggregate`, :func:`compare_surfaces` and :func:`baseline_differences` take the metrics
(summary columns) and preset groups they compare, so the hardware-in-the-loop study
(:mod:`skidnav.studies.hardware.report`) computes its tables here too; they need of the grid only
what :class:`StatsSettings` names.
"""

from __future__ import annotations

import zlib
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any, Protocol

import numpy as np
import pandas as pd

from skidnav.experiments.config import ExperimentConfig
from skidnav.statistics.intervals import (
    Interval,
    bootstrap_interval,
    difference_interval,
    ratio_interval,
    rowwise_iqm,
    rowwise_mean,
)
from skidnav.statistics.survival import (
    SpeedupInterval,
    median_interval,
    probability_of_improvement,
    speedup_interval,
)

METRICS = {
    "convergence_episode": "convergence episode (censored runs at their censoring time)",
    "convergence_steps": "real actions until convergence (censored runs until censoring)",
    "converged": "converged share",
    "pass_share_after": "pass share after convergence",
    "pass_share_after_first_window": "pass share after the first good window",
    "pass_share_last10": "pass share (last 10 %)",
    "optimality_gap": "optimality gap (last evaluations / oracle − 1)",
    "oracle_length": "oracle expected length L* [actions]",
    "first_success_episode": "first successful episode",
    "seconds_to_first_success": "driving to the first success [s] (runs that got there)",
    "seconds_to_success90": "driving to ≥ 90 % greedy success, sustained [s] (runs that got there)",
    "driving_seconds": "driving in the whole run [s]",
    "final_length_actions": "final greedy length [actions]",
    "final_length_m": "final greedy length [m]",
    "success_rate": "success rate (all episodes)",
    "success_rate_last10": "success rate (last 10 %)",
    "mean_return": "mean return",
    "collisions_per_episode": "collisions per episode",
    "planning_updates": "planning updates",
    "wall_time": "wall time [s]",
}
"""Summary columns aggregated in the report, with their display names."""


class StatsSettings(Protocol):
    """What the statistics need of a grid (an :class:`ExperimentConfig` has it all)."""

    @property
    def root_seed(self) -> int: ...
    @property
    def agent_labels(self) -> list[str]: ...
    @property
    def baseline(self) -> str: ...
    @property
    def bootstrap_samples(self) -> int: ...
    @property
    def confidence(self) -> float: ...


def stats_rng(config: StatsSettings, *keys: object) -> np.random.Generator:
    """A generator for one table cell, keyed by the root seed and the cell's labels."""
    key = zlib.crc32("|".join(str(k) for k in keys).encode())
    return np.random.default_rng([config.root_seed, 0x5747, key])


def cells(summaries: pd.DataFrame) -> Iterator[tuple[str, str, pd.DataFrame]]:
    """(map, preset, rows) for every map × preset cell present, in order of appearance."""
    for (map_label, preset), rows in summaries.groupby(["map", "preset"], sort=False):
        yield str(map_label), str(preset), rows


WORLD = ("preset", "seed")
"""The summary columns that name the world a run met: every agent of a grid meets the same."""


def _by_seed(rows: pd.DataFrame, agent: str, column: str) -> pd.Series:
    """``column`` of ``agent``'s rows indexed and sorted by (preset, seed): within one cell by
    seed, over rows of several presets by the world each run met."""
    selected = rows[rows["agent"] == agent].set_index(list(WORLD))[column]
    return selected.sort_index().astype(np.float64)


def common_worlds(rows: pd.DataFrame, first: str, second: str, *more: str) -> pd.DataFrame:
    """The runs of the agents ``first``, ``second`` (and ``more``) among ``rows`` (summaries)
    in the worlds (preset, seed) every one of them ran: all of them on a finished grid, fewer on
    a grid run in parts (``skidnav run --runs``), none when the arms share no world."""
    agents = [first, second, *more]
    world = pd.MultiIndex.from_frame(rows[list(WORLD)])
    shared = world[rows["agent"] == first]
    for agent in agents[1:]:
        shared = shared.intersection(world[rows["agent"] == agent])
    return rows[rows["agent"].isin(agents) & world.isin(shared)]


def aggregate(
    summaries: pd.DataFrame, config: StatsSettings, metrics: Iterable[str] = METRICS
) -> pd.DataFrame:
    """Mean and IQM with bootstrap intervals of every metric (summary column, default
    :data:`METRICS`) per (map, preset, agent); a metric the summaries lack (runs recorded before
    it existed) is left out.

    Returns a long table: map, preset, agent, metric, n, mean, mean_low, mean_high, iqm,
    iqm_low, iqm_high.
    """
    records = []
    metrics = [metric for metric in metrics if metric in summaries.columns]
    for map_label, preset, rows in cells(summaries):
        for agent in config.agent_labels:
            agent_rows = rows[rows["agent"] == agent]
            if agent_rows.empty:
                continue
            for metric in metrics:
                values = agent_rows[metric].to_numpy(np.float64)
                rng = stats_rng(config, map_label, preset, agent, metric)
                mean = bootstrap_interval(
                    values,
                    rng,
                    statistic=rowwise_mean,
                    n_resamples=config.bootstrap_samples,
                    confidence=config.confidence,
                )
                iqm = bootstrap_interval(
                    values,
                    rng,
                    statistic=rowwise_iqm,
                    n_resamples=config.bootstrap_samples,
                    confidence=config.confidence,
                )
                records.append(
                    {
                        "map": map_label,
                        "preset": preset,
                        "agent": agent,
                        "metric": metric,
                        "n": int(np.isfinite(values).sum()),
                        "mean": mean.estimate,
                        "mean_low": mean.low,
                        "mean_high": mean.high,
                        "iqm": iqm.estimate,
                        "iqm_low": iqm.low,
                        "iqm_high": iqm.high,
                    }
                )
    return pd.DataFrame.from_records(records)


def _paired(
    rows: pd.DataFrame, first: str, second: str, column: str
) -> tuple[np.ndarray, np.ndarray, bool]:
    a, b = _by_seed(rows, first, column), _by_seed(rows, second, column)
    paired = list(a.index) == list(b.index)
    return a.to_numpy(), b.to_numpy(), paired


def compare_to_baseline(summaries: pd.DataFrame, config: ExperimentConfig) -> pd.DataFrame:
    """Each agent against the baseline, per (map, preset), paired by seed.

    Columns: ``speedup`` (Kaplan–Meier median convergence episode of the baseline / of the agent;
    > 1 = faster) and ``speedup_bound`` (:data:`~skidnav.statistics.survival.SPEEDUP_BOUNDS`:
    "lower" when
    more than half of the baseline's runs are censored, its largest censoring time standing in
    for its median, so the speed-up is at least the value shown; "upper" when the agent's are;
    "unknown" when both are), the same in real actions (``speedup_steps``,
    ``speedup_steps_bound``), ``improvement_probability`` (Agarwal et al. (2021) probability that
    an agent run converges before a baseline run, censoring by Gehan's scores),
    ``success_gain`` (success rate agent − baseline, absolute), ``success_gain_relative``
    (agent / baseline − 1), ``success_gain_last10``, ``length_difference`` (final greedy length
    agent − baseline [actions], runs whose final policy reached the goal), ``gap_difference``
    (optimality gap agent − baseline: the last evaluations against the oracle), each with ``_low`` /
    ``_high`` bounds, and ``length_no_difference`` (the interval of the length difference
    contains 0), ``length_pairs`` (seeds where both reached the goal), ``baseline_converged``
    (share of the baseline's runs that converged; the others are censored at N).
    """
    records = []
    base = config.baseline
    for map_label, preset, rows in cells(summaries):
        for agent in config.agent_labels:
            if agent == base or rows[rows["agent"] == agent].empty:
                continue
            record: dict[str, object] = {"map": map_label, "preset": preset, "agent": agent}
            for name, interval in _comparisons(rows, agent, base, config, map_label, preset):
                record[name] = interval.estimate
                record[f"{name}_low"] = interval.low
                record[f"{name}_high"] = interval.high
            record.update(_speedup(rows, agent, base, config, map_label, preset))
            record["length_pairs"] = _length_pairs(rows, agent, base)
            record["gap_pairs"] = _length_pairs(rows, agent, base, "optimality_gap")
            record["baseline_converged"] = float(_by_seed(rows, base, "converged").mean())
            low, high = record["length_difference_low"], record["length_difference_high"]
            record["length_no_difference"] = bool(low <= 0 <= high)  # type: ignore[operator]
            records.append(record)
    return pd.DataFrame.from_records(records)


def speedup_of(row: pd.Series, name: str = "speedup") -> SpeedupInterval:
    """The speed-up ``name`` (``speedup`` in episodes, ``speedup_steps`` in real actions) of a
    row of :func:`compare_to_baseline`."""
    return SpeedupInterval(
        float(row[name]), float(row[f"{name}_low"]), float(row[f"{name}_high"]),
        str(row[f"{name}_bound"]),
    )  # fmt: skip


def survival_columns(
    rows: pd.DataFrame, agent: str, time: str = "convergence_episode"
) -> tuple[np.ndarray, np.ndarray]:
    """(convergence times, converged flags) of an agent's runs, by seed (each (n,)); times in
    episodes, or in real actions with ``time = "convergence_steps"``."""
    times = _by_seed(rows, agent, time).to_numpy()
    return times, _by_seed(rows, agent, "converged").to_numpy() > 0.5


def _speedup(
    rows: pd.DataFrame, agent: str, base: str, config: ExperimentConfig, *cell: str
) -> dict[str, object]:
    """Speed-up of ``agent`` over ``base`` (ratio of Kaplan–Meier medians), paired by seed, in
    episodes (``speedup``) and, where recorded, in real actions (``speedup_steps``)."""
    paired = list(_by_seed(rows, agent, "converged").index) == list(
        _by_seed(rows, base, "converged").index
    )
    record: dict[str, object] = {}
    for time, name in (("convergence_episode", "speedup"), ("convergence_steps", "speedup_steps")):
        if time not in rows.columns:
            continue
        ratio = speedup_interval(
            *survival_columns(rows, base, time), *survival_columns(rows, agent, time),
            stats_rng(config, *cell, agent, name), paired=paired,
            n_resamples=config.bootstrap_samples, confidence=config.confidence,
        )  # fmt: skip
        record.update({name: ratio.estimate, f"{name}_low": ratio.low,
                       f"{name}_high": ratio.high, f"{name}_bound": ratio.bound})  # fmt: skip
    return record


def convergence_table(summaries: pd.DataFrame, config: ExperimentConfig) -> pd.DataFrame:
    """Per (map, preset, agent): runs, converged share, Kaplan–Meier median convergence episode
    with its bootstrap interval (inf: more than half of the runs censored), largest censoring
    time. Columns: map, preset, agent, n, converged, median, median_low, median_high, censored_at.
    """
    records = []
    for map_label, preset, rows in cells(summaries):
        for agent in config.agent_labels:
            if rows[rows["agent"] == agent].empty:
                continue
            times, seen = survival_columns(rows, agent)
            median = median_interval(
                times, seen, stats_rng(config, map_label, preset, agent, "median"),
                n_resamples=config.bootstrap_samples, confidence=config.confidence,
            )  # fmt: skip
            records.append({
                "map": map_label, "preset": preset, "agent": agent,
                "n": int(np.isfinite(times).sum()), "converged": float(np.mean(seen)),
                "median": median.estimate, "median_low": median.low, "median_high": median.high,
                "censored_at": float(times[~seen].max()) if (~seen).any() else float("nan"),
            })  # fmt: skip
    return pd.DataFrame.from_records(records)


def _length_pairs(
    rows: pd.DataFrame, agent: str, base: str, column: str = "final_length_actions"
) -> int:
    """Seeds where both agents' ``column`` is defined (e.g. both final greedy trajectories
    reached the goal)."""
    a, b, _ = _paired(rows, agent, base, column)
    return int((np.isfinite(a) & np.isfinite(b)).sum()) if a.size == b.size else 0


def _options(config: StatsSettings) -> dict[str, Any]:
    """The bootstrap settings of ``config``."""
    return {"n_resamples": config.bootstrap_samples, "confidence": config.confidence}


def paired_difference(
    rows: pd.DataFrame, agent: str, base: str, column: str, config: StatsSettings, *keys: str
) -> tuple[Interval, int, bool]:
    """(mean ``column`` of ``agent`` − of ``base`` with its interval, pairs or runs compared,
    paired?) over ``rows`` (summaries): paired by (preset, seed) — by world — when both have
    the same runs, else unpaired; pairs where either value is NaN (e.g. a censored time) are
    left out. The generator is keyed by ``keys`` (:func:`stats_rng`)."""
    a, b, paired = _paired(rows, agent, base, column)
    interval = difference_interval(
        a, b, stats_rng(config, *keys), paired=paired, **_options(config)
    )
    n = int((np.isfinite(a) & np.isfinite(b)).sum()) if paired else min(a.size, b.size)
    return interval, n, paired


def _comparisons(
    rows: pd.DataFrame, agent: str, base: str, config: ExperimentConfig, *cell: str
) -> Iterator[tuple[str, Interval]]:
    options = _options(config)
    a_times, a_seen = survival_columns(rows, agent)
    b_times, b_seen = survival_columns(rows, base)
    yield "improvement_probability", probability_of_improvement(
        a_times, a_seen, b_times, b_seen, stats_rng(config, *cell, agent, "improvement"),
        **options,
    )  # fmt: skip
    for name, column in (
        ("success_gain", "success_rate"),
        ("success_gain_last10", "success_rate_last10"),
        ("length_difference", "final_length_actions"),
        ("gap_difference", "optimality_gap"),
    ):
        yield name, paired_difference(rows, agent, base, column, config, *cell, agent, name)[0]
    a, b, paired = _paired(rows, agent, base, "success_rate")
    ratio = ratio_interval(
        a, b, stats_rng(config, *cell, agent, "relative"), paired=paired, **options
    )
    yield "success_gain_relative", Interval(ratio.estimate - 1, ratio.low - 1, ratio.high - 1)


def compare_surfaces(
    summaries: pd.DataFrame,
    config: StatsSettings,
    rough: str | Sequence[str] = "rough",
    slippery: str | Sequence[str] = "slippery",
    metrics: Sequence[str] = ("success_rate", "success_rate_last10"),
) -> pd.DataFrame:
    """Mean of each metric on the rough floor over that on the slippery floor, per (map, agent).

    ``rough`` and ``slippery`` each name a preset, or a group of presets pooled (e.g. one floor
    under stationary and under drifting slip). The two floors are different worlds, so the runs
    are resampled independently (unpaired). Each (map, agent, metric) has its own generator,
    keyed also by the presets when groups are given.
    Columns: map, agent, metric, ratio, ratio_low, ratio_high, rough, slippery (mean rates),
    rough_runs, slippery_runs (runs with a value, not NaN).
    """
    first, second = _group(rough), _group(slippery)
    present = set(summaries["preset"])
    if not (present & set(first) and present & set(second)):
        return pd.DataFrame()
    groups = () if isinstance(rough, str) and isinstance(slippery, str) else (*first, *second)
    records = []
    for (map_label, agent), rows in summaries.groupby(["map", "agent"], sort=False):
        for metric in metrics:
            a = rows[rows["preset"].isin(first)][metric].to_numpy(np.float64)
            b = rows[rows["preset"].isin(second)][metric].to_numpy(np.float64)
            rng = stats_rng(config, map_label, agent, metric, "surfaces", *groups)
            ratio = ratio_interval(a, b, rng, paired=False, **_options(config))
            records.append({
                "map": map_label, "agent": agent, "metric": metric,
                "ratio": ratio.estimate, "ratio_low": ratio.low, "ratio_high": ratio.high,
                "rough": _mean(a), "slippery": _mean(b),
                "rough_runs": int((~np.isnan(a)).sum()),
                "slippery_runs": int((~np.isnan(b)).sum()),
            })  # fmt: skip
    return pd.DataFrame.from_records(records)


def _group(presets: str | Sequence[str]) -> tuple[str, ...]:
    """A preset name as a group of one, a group as a tuple."""
    return (presets,) if isinstance(presets, str) else tuple(presets)


def _mean(values: np.ndarray) -> float:
    """Mean of the values that are not NaN, NaN without any."""
    kept = values[~np.isnan(values)]
    return float(kept.mean()) if kept.size else float("nan")


def baseline_differences(
    summaries: pd.DataFrame,
    config: StatsSettings,
    metrics: Sequence[str],
    groups: Mapping[str, Sequence[str]],
) -> pd.DataFrame:
    """Each agent's mean of each metric minus the baseline's, per map and group of presets.

    The runs of a group's presets are pooled and paired by (preset, seed): every agent of a
    (map, preset, seed) meets the same world. With different runs on the two sides (an
    unfinished grid) they are compared unpaired. Each (map, group, agent, metric) has its own
    generator. Columns: map, group, agent, metric, difference, difference_low,
    difference_high, n (pairs, or the smaller side's runs), paired.
    """
    base = config.baseline
    records = []
    for map_label, rows in summaries.groupby("map", sort=False):
        for group, presets in groups.items():
            selected = rows[rows["preset"].isin(presets)]
            for agent in config.agent_labels:
                if agent == base or selected[selected["agent"] == agent].empty:
                    continue
                for metric in metrics:
                    keys = (str(map_label), group, agent, metric, "difference")
                    interval, n, paired = paired_difference(
                        selected, agent, base, metric, config, *keys
                    )
                    records.append({
                        "map": map_label, "group": group, "agent": agent, "metric": metric,
                        "difference": interval.estimate, "difference_low": interval.low,
                        "difference_high": interval.high, "n": n, "paired": paired,
                    })  # fmt: skip
    return pd.DataFrame.from_records(records)


def budget_rows(
    comparisons: pd.DataFrame, aggregates: pd.DataFrame, config: ExperimentConfig
) -> pd.DataFrame:
    """Speed-up and wall time against the planning budget, one row per (map, preset, agent)
    whose parameters set ``planning_steps``: map, preset, algorithm, planning_steps, speedup,
    speedup_low, speedup_high, bound (as ``speedup_bound``), wall_time, wall_time_low,
    wall_time_high (mean wall time per run [s] with its interval)."""
    steps = {
        agent.label: (agent.name, int(agent.params_dict()["planning_steps"]))  # type: ignore[arg-type]
        for agent in config.agents
        if "planning_steps" in agent.params_dict()
    }
    records = []
    for _, row in comparisons.iterrows():
        if row["agent"] not in steps:
            continue
        wall = aggregates[
            (aggregates["map"] == row["map"]) & (aggregates["preset"] == row["preset"])
            & (aggregates["agent"] == row["agent"]) & (aggregates["metric"] == "wall_time")
        ].iloc[0]  # fmt: skip
        algorithm, planning_steps = steps[row["agent"]]
        records.append({
            "map": row["map"], "preset": row["preset"], "algorithm": algorithm,
            "planning_steps": planning_steps, "speedup": row["speedup"],
            "speedup_low": row["speedup_low"], "speedup_high": row["speedup_high"],
            "bound": row["speedup_bound"], "wall_time": wall["mean"],
            "wall_time_low": wall["mean_low"], "wall_time_high": wall["mean_high"],
        })  # fmt: skip
    return pd.DataFrame.from_records(records)
