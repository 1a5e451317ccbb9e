"""The speed table of the docs, generated: ``make bench`` writes it from the figures it has just
recorded (:mod:`history`) into ``docs/speed.md`` (the site's Speed page), between :data:`BEGIN`
and :data:`END`; nothing there is kept by hand, and each run replaces the table with that
machine's figures, its commit and the date."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import key_figures
import time_to_learn
from history import MACHINE, RESULTS, Figures, Record

from skidnav.statistics.intervals import Interval

ROOT = Path(__file__).resolve().parents[1]
TARGETS = (ROOT / "docs" / "speed.md",)
BEGIN = "<!-- speed table: written by `make bench` (benchmarks/speed_table.py) -->"
END = "<!-- end of the speed table -->"
KEY = "figures.KeyFigures.track_{}"
LEARNING = "figures.TimeToLearn.track_{}"


def rate(value: float) -> str:
    """A rate [1/s] with k or M, 3 significant digits; "–" for NaN."""
    if math.isnan(value):
        return "–"
    for scale, prefix in ((1e6, " M"), (1e3, " k")):
        if value >= scale:
            return f"{value / scale:.3g}{prefix}"
    return f"{value:.3g}"


def key_table(figures: Figures) -> list[str]:
    """One row per key figure: the compiled path's rate, its twin's, the ratio, the floor."""
    rows = [
        "| compiled path | its rate | against | the twin's rate | ratio | guard's floor |",
        "|---|---|---|---|---|---|",
    ]
    for name, figure in key_figures.FIGURES.items():
        compiled = 1e6 / figures[KEY.format("time_per_million"), name]
        twin = compiled * figures[KEY.format("relative_time"), name]
        ratio = time_to_learn.describe(compiled / twin, "×")
        floor = f"{figure.floor:g}×" if figure.guarded else "not guarded"
        rows.append(
            f"| {figure.compiled} | {rate(compiled)} {figure.unit}/s | {figure.twin} "
            f"| {rate(twin)}/s | **{ratio}** | {floor} |"
        )
    return rows


def unbounded(value: float) -> float:
    """A recorded median or interval end: NaN (asv's "not measured") stands for ∞, since every
    agent has at least two runs (a NaN interval only with one)."""
    return math.inf if math.isnan(value) else value


def with_interval(figures: Figures, name: str, agent: str, unit: str = "") -> str:
    """The recorded median ``name`` of ``agent`` with its interval, e.g. "0.48 s [0.31 s, ∞]"."""
    estimate, low, high = (
        unbounded(figures[LEARNING.format(name + end), agent]) for end in ("", "_low", "_high")
    )
    return time_to_learn.with_interval(Interval(estimate, low, high), unit)


def learning_table(figures: Figures) -> list[str]:
    """One row per agent of ``time_to_learn.toml``: how long it took to learn."""
    runs, _ = time_to_learn.budget()
    rows = [
        "| agent | converged | median convergence episode | median training time to it "
        "| planning updates/s | real steps/s |",
        "|---|---|---|---|---|---|",
    ]
    for agent in time_to_learn.agent_labels():
        value = {
            name: figures[LEARNING.format(name), agent]
            for name in ("unconverged_runs", "time_per_update", "time_per_step")
        }
        rows.append(
            f"| {agent} | {runs - value['unconverged_runs']:.0f}/{runs} "
            f"| {with_interval(figures, 'episodes', agent)} "
            f"| **{with_interval(figures, 'seconds', agent, ' s')}** "
            f"| {rate(1e9 / value['time_per_update'])} | {rate(1e6 / value['time_per_step'])} |"
        )
    return rows


def machine() -> str:
    """This machine as asv describes it: its name, CPU and core count."""
    info = json.loads((RESULTS / MACHINE / "machine.json").read_text())
    return f"{info['machine']} ({info['cpu']}, {info['num_cpu']} cores)"


def table(record: Record) -> str:
    """The whole generated text of ``record``: where, what and when, then both tables."""
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(record.measured_at / 1000))
    runs, given = time_to_learn.budget()
    return "\n".join([
        BEGIN,
        f"Measured by `make bench` on {machine()} at commit `{record.commit[:8]}`, {when}; "
        "each compiled path and its twin one after the other on one core.",
        "",
        *key_table(record.figures),
        "",
        f"Time to learn (`benchmarks/{time_to_learn.CONFIG.name}`: the demo's arena, 25 × 25 × "
        f"20 with obstacles, thesis slip; {runs} runs per agent of {given}, one after another on "
        "one core; training time only; Kaplan–Meier medians over the runs with their "
        f"{time_to_learn.confidence():.0%} "
        "percentile-bootstrap intervals, ∞ where more than half of the runs in a resample did "
        "not converge):",
        "",
        *learning_table(record.figures),
        END,
    ])  # fmt: skip


def write(text: str) -> None:
    """Put ``text`` in place of the generated table in each of :data:`TARGETS`."""
    for path in TARGETS:
        old = path.read_text()
        start, end = old.find(BEGIN), old.find(END)
        if start < 0 or end < start:
            raise ValueError(f"{path}: expected the generated table's markers {BEGIN} … {END}")
        path.write_text(old[:start] + text + old[end + len(END) :])
