"""The markdown tables of a hardware-in-the-loop study (realtime/study.py, docs/realtime.md).

Rates are pooled over seeds: successes / episodes of all runs of a cell; episode lengths are
episode-weighted means of the runs' ``mean_episode_actions``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

CSV_FIELDS = (
    "agent",
    "preset",
    "seed",
    "episodes",
    "successes",
    "success_rate",
    "mean_episode_actions",
    "aborted",
)
BASELINE = "q-learning"


def _pool(rows: Iterable[Mapping[str, Any]]) -> tuple[int, int, float, int, int]:
    """(runs, episodes, mean episode length [actions], successes, aborted episodes)."""
    rows = list(rows)
    episodes = sum(int(r["episodes"]) for r in rows)
    successes = sum(int(r["successes"]) for r in rows)
    actions = sum(float(r["mean_episode_actions"]) * int(r["episodes"]) for r in rows)
    aborted = sum(int(r["aborted"]) for r in rows)
    return len(rows), episodes, actions / episodes if episodes else float("nan"), successes, aborted


def _rate(rows: Iterable[Mapping[str, Any]]) -> float | None:
    """Pooled success rate, None without episodes."""
    _, episodes, _, successes, _ = _pool(rows)
    return successes / episodes if episodes else None


def _pct(value: float | None) -> str:
    return "—" if value is None else f"{100 * value:.1f} %"


def _cell_table(rows: Sequence[Mapping[str, Any]], agents: list[str], presets: list[str]) -> str:
    lines = [
        "| agent | preset | seeds | episodes | success rate | mean episode length [actions] "
        "| aborted |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for agent in agents:
        for preset in presets:
            cell = [r for r in rows if r["agent"] == agent and r["preset"] == preset]
            if not cell:
                continue
            runs, episodes, length, successes, aborted = _pool(cell)
            lines.append(
                f"| {agent} | {preset} | {runs} | {episodes} | {_pct(successes / episodes)} "
                f"({successes}/{episodes}) | {length:.1f} | {aborted} |"
            )
    return "\n".join(lines)


def _ratio_table(
    rows: Sequence[Mapping[str, Any]], agents: list[str], conditions: Mapping[str, tuple[str, bool]]
) -> str:
    """Rough / slippery success ratio per agent and slip condition (and pooled)."""
    lines = ["| agent | slip | rough / slippery success |", "|---|---|---:|"]
    for agent in agents:
        for label, drifting in (("stationary", False), ("drifting", True), ("both", None)):

            def of(floor: str, agent: str = agent, drifting: bool | None = drifting) -> list[Any]:
                return [
                    r
                    for r in rows
                    if r["agent"] == agent
                    and conditions[r["preset"]][0] == floor
                    and (drifting is None or conditions[r["preset"]][1] == drifting)
                ]

            rough, slippery = _rate(of("rough")), _rate(of("slippery"))
            if rough is None or slippery is None:
                continue
            if slippery > 0:
                ratio = f"{rough / slippery:.2f}"
            else:
                ratio = "∞ (slippery 0)" if rough > 0 else "undefined (both 0)"
            lines.append(f"| {agent} | {label} | {ratio} |")
    return "\n".join(lines)


def _difference_table(
    rows: Sequence[Mapping[str, Any]], agents: list[str], conditions: Mapping[str, tuple[str, bool]]
) -> str:
    """Success of each model-based agent minus Q-learning's, per floor (pooled over slip)."""
    others = [agent for agent in agents if agent != BASELINE]
    header = " | ".join(f"{a} − {BASELINE}" for a in others)
    lines = [
        f"| floor | {BASELINE} success | {header} |",
        "|---|---:|" + "---:|" * len(others),
    ]
    for floor in sorted({slip for slip, _ in conditions.values()}):
        on_floor = [r for r in rows if conditions[r["preset"]][0] == floor]
        base = _rate(r for r in on_floor if r["agent"] == BASELINE)
        cells = []
        for agent in others:
            rate = _rate(r for r in on_floor if r["agent"] == agent)
            cells.append(
                "—" if rate is None or base is None else f"{100 * (rate - base):+.1f} points"
            )
        lines.append(f"| {floor} | {_pct(base)} | {' | '.join(cells)} |")
    return "\n".join(lines)


def markdown_report(
    rows: Sequence[Mapping[str, Any]], conditions: Mapping[str, tuple[str, bool]]
) -> str:
    """The study's markdown: per agent × preset table, rough/slippery ratios, and (with
    Q-learning among the agents) model-based minus Q-learning success per floor.

    Args:
        rows: run records (keys of :data:`CSV_FIELDS`).
        conditions: preset → (slip preset of its floor, drifting slip?).
    """
    agents = list(dict.fromkeys(str(r["agent"]) for r in rows))
    presets = [p for p in conditions if any(r["preset"] == p for r in rows)]
    parts = ["## Success and episode length\n", _cell_table(rows, agents, presets)]
    parts += ["\n## Rough vs slippery floor\n", _ratio_table(rows, agents, conditions)]
    if BASELINE in agents and len(agents) > 1:
        parts += [
            "\n## Model-based minus Q-learning\n",
            _difference_table(rows, agents, conditions),
        ]
    return "\n".join(parts) + "\n"
