"""The markdown tables of a hardware-in-the-loop study (realtime/study.py, docs/realtime.md).

Every statistic is over seeds: each run contributes its own success rate (all episodes, or the
last half: ``late``) and its mean episode length; a cell's estimate is the mean over its seeds
with a 95 % percentile-bootstrap interval (:mod:`skidnav.stats`; no interval from one seed).
Comparisons are paired by seed: runs with the same seed share the map and the root seed, so
rough vs slippery pairs the two floors of one slip condition, and an agent vs Q-learning pairs
the same preset. The resamples come from ``np.random.default_rng(0)``: the same rows give the same
tables.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from skidnav.stats import Interval, bootstrap_interval, difference_interval, ratio_interval

CSV_FIELDS = (
    "agent",
    "preset",
    "seed",
    "episodes",
    "successes",
    "success_rate",
    "mean_episode_actions",
    "aborted",
    "late_episodes",
    "late_successes",
)
BASELINE = "q-learning"
SLIP_CONDITIONS = (("stationary", False), ("drifting", True), ("both", None))

Row = Mapping[str, Any]
Metric = Callable[[Row], float]


def success_rate(row: Row) -> float:
    """Share of a run's episodes that reached the goal."""
    return int(row["successes"]) / int(row["episodes"])


def late_success_rate(row: Row) -> float:
    """Share of the last half of a run's episodes that reached the goal."""
    return int(row["late_successes"]) / int(row["late_episodes"])


def episode_length(row: Row) -> float:
    """Mean actions per episode of a run."""
    return float(row["mean_episode_actions"])


def _interval(value: Interval, scale: float = 100.0, digits: int = 1) -> str:
    text = f"{scale * value.estimate:.{digits}f}"
    if math.isnan(value.low):
        return text
    return f"{text} [{scale * value.low:.{digits}f}, {scale * value.high:.{digits}f}]"


def _signed(value: Interval, scale: float = 100.0) -> str:
    text = f"{scale * value.estimate:+.1f}"
    if math.isnan(value.low):
        return text
    return f"{text} [{scale * value.low:+.1f}, {scale * value.high:+.1f}]"


def _by_seed(rows: Sequence[Row]) -> dict[int, Row]:
    return {int(r["seed"]): r for r in rows}


def _paired(
    first: Sequence[Row], second: Sequence[Row], metric: Metric
) -> tuple[np.ndarray, np.ndarray]:
    """``metric`` of the runs of ``first`` and ``second`` that share a seed, in seed order."""
    a, b = _by_seed(first), _by_seed(second)
    seeds = sorted(set(a) & set(b))
    return np.array([metric(a[s]) for s in seeds]), np.array([metric(b[s]) for s in seeds])


def _cell_table(rows: Sequence[Row], agents: list[str], presets: list[str]) -> str:
    lines = [
        "| agent | preset | seeds | episodes | success [%] | success, last half [%] "
        "| episode length [actions] | aborted |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    rng = np.random.default_rng(0)
    for agent in agents:
        for preset in presets:
            cell = [r for r in rows if r["agent"] == agent and r["preset"] == preset]
            if not cell:
                continue
            success, late, length = (
                bootstrap_interval([metric(r) for r in cell], rng)
                for metric in (success_rate, late_success_rate, episode_length)
            )
            episodes = sum(int(r["episodes"]) for r in cell)
            aborted = sum(int(r["aborted"]) for r in cell)
            lines.append(
                f"| {agent} | {preset} | {len(cell)} | {episodes} | {_interval(success)} "
                f"| {_interval(late)} | {_interval(length, 1.0)} | {aborted} |"
            )
    return "\n".join(lines)


def _floor_pairs(
    rows: Sequence[Row],
    agent: str,
    conditions: Mapping[str, tuple[str, bool]],
    drifting: bool | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Late success on the rough and on the slippery floor, paired by (slip condition, seed)."""
    rough, slippery = [], []
    for is_drifting in (False, True):
        if drifting is not None and is_drifting != drifting:
            continue

        def of(floor: str, is_drifting: bool = is_drifting) -> list[Row]:
            return [
                r
                for r in rows
                if r["agent"] == agent and conditions[r["preset"]] == (floor, is_drifting)
            ]

        a, b = _paired(of("rough"), of("slippery"), late_success_rate)
        rough.append(a)
        slippery.append(b)
    return np.concatenate(rough), np.concatenate(slippery)


def _ratio_table(
    rows: Sequence[Row], agents: list[str], conditions: Mapping[str, tuple[str, bool]]
) -> str:
    """Rough / slippery late success per agent and slip condition (and both pooled)."""
    lines = [
        "| agent | slip | pairs | rough [%] | slippery [%] | rough / slippery |",
        "|---|---|---:|---:|---:|---:|",
    ]
    rng = np.random.default_rng(0)
    for agent in agents:
        for label, drifting in SLIP_CONDITIONS:
            rough, slippery = _floor_pairs(rows, agent, conditions, drifting)
            if rough.size == 0:
                continue
            if slippery.mean() > 0:
                ratio = _interval(ratio_interval(rough, slippery, rng), 1.0, 2)
            else:
                ratio = "∞ (slippery 0)" if rough.mean() > 0 else "undefined (both 0)"
            lines.append(
                f"| {agent} | {label} | {rough.size} | {100 * rough.mean():.1f} "
                f"| {100 * slippery.mean():.1f} | {ratio} |"
            )
    if len(lines) == 2:
        return "(no floor pairs: no slip condition was run on both floors with the same seed)"
    return "\n".join(lines)


def _versus_baseline(
    rows: Sequence[Row], agent: str, presets: Sequence[str], metric: Metric
) -> tuple[np.ndarray, np.ndarray]:
    """``metric`` of ``agent`` and of Q-learning, paired by (preset, seed) over ``presets``."""
    pairs = [
        _paired(
            [r for r in rows if r["agent"] == agent and r["preset"] == preset],
            [r for r in rows if r["agent"] == BASELINE and r["preset"] == preset],
            metric,
        )
        for preset in presets
    ]
    return np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])


def _difference_table(
    rows: Sequence[Row], agents: list[str], conditions: Mapping[str, tuple[str, bool]]
) -> str:
    """Each other agent minus Q-learning, paired by (preset, seed), per floor."""
    lines = [
        "| agent | floor | pairs | Δ success [points] | Δ success, last half [points] "
        "| Δ episode length [actions] |",
        "|---|---|---:|---:|---:|---:|",
    ]
    rng = np.random.default_rng(0)
    metrics = ((success_rate, 100.0), (late_success_rate, 100.0), (episode_length, 1.0))
    for agent in (a for a in agents if a != BASELINE):
        for floor in sorted({slip for slip, _ in conditions.values()}):
            presets = [preset for preset, (slip, _) in conditions.items() if slip == floor]
            cells = []
            for metric, scale in metrics:
                ours, theirs = _versus_baseline(rows, agent, presets, metric)
                cells.append(_signed(difference_interval(ours, theirs, rng), scale))
            if ours.size:
                lines.append(f"| {agent} | {floor} | {ours.size} | {' | '.join(cells)} |")
    return "\n".join(lines)


def markdown_report(rows: Sequence[Row], conditions: Mapping[str, tuple[str, bool]]) -> str:
    """The study's markdown: per agent × preset table, rough/slippery ratios, and (with
    Q-learning among the agents) every other agent minus Q-learning per floor.

    Args:
        rows: run records (keys of :data:`CSV_FIELDS`).
        conditions: preset → (slip preset of its floor, drifting slip?).
    """
    agents = list(dict.fromkeys(str(r["agent"]) for r in rows))
    presets = [p for p in conditions if any(r["preset"] == p for r in rows)]
    parts = [
        "Estimates are means over seeds with 95 % bootstrap intervals in brackets; comparisons "
        "are paired by seed.\n",
        "## Success and episode length\n",
        _cell_table(rows, agents, presets),
        "\n## Rough vs slippery floor (success, last half of the episodes)\n",
        _ratio_table(rows, agents, conditions),
    ]
    if BASELINE in agents and len(agents) > 1:
        parts += [f"\n## Minus {BASELINE}\n", _difference_table(rows, agents, conditions)]
    return "\n".join(parts) + "\n"
