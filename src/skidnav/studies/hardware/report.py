"""The markdown tables of a hardware-in-the-loop study (studies/hardware/study.py,
docs/realtime.md).

Every statistic comes from :mod:`skidnav.experiments.report.analysis`, over the store's summaries
(one row per run): a cell's estimate is the mean over its seeds of the runs' own rates and lengths,
with a percentile-bootstrap interval (none from one seed) drawn by the cell's own generator, keyed
by the root seed and the cell's labels. An agent minus the baseline (Q-learning) is paired by
(preset, seed): both met the same world. The rough and the slippery floor are different worlds,
compared unpaired. This module only formats.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import pandas as pd

from skidnav.experiments.report.analysis import (
    StatsSettings,
    aggregate,
    baseline_differences,
    compare_surfaces,
)

CELL_METRICS = ("success_rate", "success_rate_last_half", "mean_length")
"""Summary columns of the tables: success (all episodes, last half), episode length [actions]."""
SCALES = {"success_rate": 100.0, "success_rate_last_half": 100.0, "mean_length": 1.0}
"""Display scale of each metric (rates in %)."""
SLIP_CONDITIONS = (("stationary", (False,)), ("drifting", (True,)), ("both", (False, True)))
"""Rows of the floor table: (label, drifting slip? values pooled)."""

Conditions = Mapping[str, tuple[str, bool]]
"""Preset → (slip preset of its floor, drifting slip?)."""


def _interval(estimate: float, low: float, high: float, scale: float, signed: bool = False) -> str:
    """``estimate [low, high]`` times ``scale`` with one decimal (and a sign when ``signed``);
    without the bounds when they are NaN (one seed)."""
    form = "+.1f" if signed else ".1f"
    text = f"{scale * estimate:{form}}"
    if math.isnan(low):
        return text
    return f"{text} [{scale * low:{form}}, {scale * high:{form}}]"


def _by(table: pd.DataFrame, *keys: str) -> dict[tuple[Any, ...], dict[Any, Any]]:
    """The rows of ``table`` as dicts, by the values of the columns ``keys``."""
    return {tuple(row[k] for k in keys): row for row in table.to_dict("records")}


def _cell_table(summaries: pd.DataFrame, settings: StatsSettings, presets: Sequence[str]) -> str:
    lines = [
        "| agent | preset | seeds | episodes | success [%] | success, last half [%] "
        "| episode length [actions] | aborted |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    table = _by(aggregate(summaries, settings, CELL_METRICS), "agent", "preset", "metric")
    for agent in settings.agent_labels:
        for preset in presets:
            runs = summaries[(summaries["agent"] == agent) & (summaries["preset"] == preset)]
            if runs.empty:
                continue
            cells = []
            for metric in CELL_METRICS:
                row = table[(agent, preset, metric)]
                cells.append(
                    _interval(row["mean"], row["mean_low"], row["mean_high"], SCALES[metric])
                )
            lines.append(
                f"| {agent} | {preset} | {len(runs)} | {int(runs['episodes'].sum())} "
                f"| {' | '.join(cells)} | {int(runs['aborted'].sum())} |"
            )
    return "\n".join(lines)


def _floor_presets(conditions: Conditions, floor: str, drifting: Sequence[bool]) -> list[str]:
    return [p for p, (slip, drifts) in conditions.items() if slip == floor and drifts in drifting]


def _ratio(row: Mapping[str, Any]) -> str:
    """Rough / slippery, or why there is no ratio."""
    if row["slippery"] > 0:
        text = f"{row['ratio']:.2f}"
        return (
            text
            if math.isnan(row["ratio_low"])
            else (f"{text} [{row['ratio_low']:.2f}, {row['ratio_high']:.2f}]")
        )
    return "∞ (slippery 0)" if row["rough"] > 0 else "undefined (both 0)"


def _ratio_table(summaries: pd.DataFrame, settings: StatsSettings, conditions: Conditions) -> str:
    """Rough / slippery success in the last half per agent and slip condition run on both
    floors, and both conditions pooled when each was."""
    lines = [
        "| agent | slip | runs (rough, slippery) | rough [%] | slippery [%] | rough / slippery |",
        "|---|---|---:|---:|---:|---:|",
    ]
    matched = {
        drifting
        for drifting in (False, True)
        if _floor_presets(conditions, "rough", (drifting,))
        and _floor_presets(conditions, "slippery", (drifting,))
    }
    tables = {}
    for label, drifting in SLIP_CONDITIONS:
        if not matched >= set(drifting):  # "both" only when each condition has both floors
            continue
        rough = _floor_presets(conditions, "rough", drifting)
        slippery = _floor_presets(conditions, "slippery", drifting)
        metrics = ("success_rate_last_half",)
        table = compare_surfaces(summaries, settings, rough, slippery, metrics)
        tables[label] = _by(table, "agent")
    for agent in settings.agent_labels:
        for label, rows in tables.items():
            row = rows.get((agent,))
            if row is None:
                continue
            lines.append(
                f"| {agent} | {label} | {row['rough_runs']}, {row['slippery_runs']} "
                f"| {100 * row['rough']:.1f} | {100 * row['slippery']:.1f} | {_ratio(row)} |"
            )
    if len(lines) == 2:
        return "(no floor pair: no slip condition was run on both the rough and the slippery floor)"
    return "\n".join(lines)


def _difference_table(
    summaries: pd.DataFrame, settings: StatsSettings, conditions: Conditions
) -> str:
    """Each other agent minus the baseline per floor, paired by (preset, seed)."""
    lines = [
        "| agent | floor | pairs | Δ success [points] | Δ success, last half [points] "
        "| Δ episode length [actions] |",
        "|---|---|---:|---:|---:|---:|",
    ]
    floors = sorted({slip for slip, _ in conditions.values()})
    groups = {
        floor: [p for p, (slip, _) in conditions.items() if slip == floor] for floor in floors
    }
    table = baseline_differences(summaries, settings, CELL_METRICS, groups)
    if table.empty:
        return "(no pair: no other agent ran a preset the baseline ran)"
    rows = _by(table, "agent", "group", "metric")
    for agent, floor in dict.fromkeys(zip(table["agent"], table["group"], strict=True)):
        cells = [
            _interval(row["difference"], row["difference_low"], row["difference_high"],
                      SCALES[metric], signed=True)
            for metric, row in ((m, rows[(agent, floor, m)]) for m in CELL_METRICS)
        ]  # fmt: skip
        first = rows[(agent, floor, CELL_METRICS[0])]
        pairs = f"{first['n']}" if first["paired"] else f"{first['n']} (unpaired)"
        lines.append(f"| {agent} | {floor} | {pairs} | {' | '.join(cells)} |")
    return "\n".join(lines)


def markdown_report(
    summaries: pd.DataFrame, settings: StatsSettings, conditions: Conditions
) -> str:
    """The study's markdown: per agent × preset table, rough/slippery ratios, and (with more
    than one agent) every other agent minus the baseline per floor.

    Args:
        summaries: one row per finished run (``summaries.parquet``: grid coordinates and the
            metrics of :func:`skidnav.studies.hardware.trial.run_summary`).
        settings: root seed, agents, baseline and bootstrap settings (the study's grid).
        conditions: every preset of the grid, in order → (slip preset, drifting slip?).
    """
    present = set(summaries["preset"])
    presets = [preset for preset in conditions if preset in present]
    level = round(100 * settings.confidence)
    parts = [
        f"Estimates are means over seeds with {level} % bootstrap intervals in brackets; an agent "
        f"minus {settings.baseline} is paired by preset and seed, the floors are compared "
        "unpaired.\n",
        "## Success and episode length\n",
        _cell_table(summaries, settings, presets),
        "\n## Rough vs slippery floor (success, last half of the episodes)\n",
        _ratio_table(summaries, settings, conditions),
    ]
    if len(set(summaries["agent"])) > 1:
        parts += [
            f"\n## Minus {settings.baseline}\n",
            _difference_table(summaries, settings, conditions),
        ]
    return "\n".join(parts) + "\n"
