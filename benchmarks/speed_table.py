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
            for name in ("seconds", "episodes", "unconverged_runs", "time_per_update",
                         "time_per_step")
        }  # fmt: skip
        rows.append(
            f"| {agent} | {runs - value['unconverged_runs']:.0f}/{runs} "
            f"| {time_to_learn.describe(value['episodes'])} "
            f"| **{time_to_learn.describe(value['seconds'], ' s')}** "
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
        "one core; training time only, Kaplan–Meier medians over the runs):",
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
