"""The headline figure (README, docs/index.md, docs/summary.md), drawn from the measured tables of
docs/results.md: the speed-up of each of the thesis's model-based agents over Q-learning, with
its 95 % bootstrap interval, on the 30 worlds of ``configs/claims.toml`` (100 planning updates per
real step, both planning targets), in episodes and in real actions.

    PYTHONPATH=src python docs/tools/speed_up_figure.py   # rewrites docs/data/claims-speed-up.png

The numbers plotted are stored in the PNG's metadata (key ``numbers``, JSON), so a test can tell
whether the figure still shows what docs/results.md says.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "results.md"
FIGURE = ROOT / "docs" / "data" / "claims-speed-up.png"
SECTION = "## Claims under"
"""The heading of the section of docs/results.md the rows come from."""
ROWS = (
    ("dyna-q", "dyna-q, most-probable (thesis)", "dyna-q, expected"),
    (
        "trajectory-prioritized",
        "trajectory-prioritized, most-probable (thesis)",
        "trajectory-prioritized, expected",
    ),
    (
        "dyna-kinematic",
        "dyna-kinematic, most-probable, 100 updates",
        "dyna-kinematic, expected, 100 updates",
    ),
    (
        "dyna-full",
        "dyna-full, most-probable target (thesis)",
        "dyna-full, expected target (default)",
    ),
)
"""Per agent: its label and the first cells of its rows with the thesis's most-probable and with
the expected planning target."""
SPEED_UP = re.compile(r"([\d.]+)× \[([\d.]+), ([\d.]+)\]")
THESIS_CLAIM = 16.0
"""The thesis's "up to 16×" (Alhawary (2020), ch. 7)."""


class SpeedUp(NamedTuple):
    """A speed-up over Q-learning and its 95 % interval."""

    value: float
    low: float
    high: float


class Row(NamedTuple):
    """One table row: its first cell, and its speed-ups in episodes and in real actions."""

    label: str
    episodes: SpeedUp
    actions: SpeedUp


def table_rows(section: str) -> dict[str, Row]:
    """Every row of the section's tables that has both speed-ups, by first cell; a label seen
    twice keeps its first row."""
    rows: dict[str, Row] = {}
    header: list[str] = []
    for line in section.splitlines():
        if not line.startswith("|"):
            header = []
            continue
        cells = [cell.strip().strip("*") for cell in line.strip("|").split("|")]
        if not header:
            header = cells
            continue
        columns = [index for index, name in enumerate(header) if name.startswith("speed-up")]
        found = [SPEED_UP.search(cells[index]) for index in columns if index < len(cells)]
        if len(found) == 2 and all(found) and "tuned" not in " ".join(header):
            episodes, actions = (SpeedUp(*map(float, match.groups())) for match in found if match)
            rows.setdefault(cells[0], Row(cells[0], episodes, actions))
    return rows


def measured_rows(text: str) -> list[tuple[str, Row, Row]]:
    """Per agent of :data:`ROWS`: its label, its most-probable row and its expected row."""
    start = text.index(SECTION)
    end = text.find("\n## ", start + len(SECTION))
    rows = table_rows(text[start : end if end > 0 else None])
    missing = [label for _, *labels in ROWS for label in labels if label not in rows]
    if missing:
        raise ValueError(f"{RESULTS.name}: expected rows {missing} in the section {SECTION!r}")
    return [(agent, rows[probable], rows[expected]) for agent, probable, expected in ROWS]


def draw(measured: list[tuple[str, Row, Row]], path: Path) -> None:
    """Two panels (episodes, real actions): per agent both targets with their intervals, in the
    agent's colour of every report (:mod:`skidnav.experiments.report.colours`); the target by
    marker (most-probable: filled circle, expected: open square)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skidnav.experiments.report.colours import agent_colours

    colours = agent_colours(agent for agent, _, _ in measured)
    figure, axes = plt.subplots(1, 2, figsize=(9, 3.6), sharey=True, layout="constrained")
    for axis, unit in zip(axes, ("episodes", "actions"), strict=True):
        for position, (agent, probable, expected) in enumerate(measured):
            for offset, row, style in ((0.15, probable, "o"), (-0.15, expected, "s")):
                speed_up: SpeedUp = getattr(row, unit)
                axis.errorbar(
                    speed_up.value, position + offset, capsize=3, fmt=style,
                    xerr=[[speed_up.value - speed_up.low], [speed_up.high - speed_up.value]],
                    color=colours[agent], mfc=colours[agent] if style == "o" else "white",
                )  # fmt: skip
        axis.axvline(1.0, color="grey", linewidth=1)
        axis.axvline(THESIS_CLAIM, color="black", linestyle="--", linewidth=1)
        axis.set_xscale("log")
        axis.set_xlim(0.5, 80)
        axis.set_xticks(
            [1, 2, 4, 8, 16, 32, 64], labels=["1×", "2×", "4×", "8×", "16×", "32×", "64×"]
        )
        title = "in episodes" if unit == "episodes" else "in real actions"
        axis.set_title(f"speed-up over Q-learning, {title}", fontsize=10)
        axis.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(range(len(measured)), labels=[agent for agent, _, _ in measured])
    for tick, (agent, _, _) in zip(axes[0].get_yticklabels(), measured, strict=True):
        tick.set_color(colours[agent])
    axes[0].invert_yaxis()
    handles = [
        plt.Line2D([], [], marker="o", linestyle="", color="black"),
        plt.Line2D([], [], marker="s", linestyle="", color="black", mfc="white"),
        plt.Line2D([], [], linestyle="--", color="black"),
    ]
    labels = ["most-probable target (thesis)", "expected target (default)", "thesis: up to 16×"]
    figure.legend(handles, labels, loc="outside lower center", ncols=3, frameon=False)
    figure.suptitle(
        "To a greedy policy that stays converged: 30 worlds (configs/claims.toml), 100 planning "
        "updates per real step; bars: 95 % bootstrap intervals",
        fontsize=9,
    )
    numbers = json.dumps([[agent, list(p), list(e)] for agent, p, e in measured])
    figure.savefig(path, dpi=110, metadata={"numbers": numbers, "Source": "docs/results.md"})
    plt.close(figure)


def main() -> None:
    """Draw :data:`FIGURE` from :data:`RESULTS`."""
    draw(measured_rows(RESULTS.read_text(encoding="utf-8")), FIGURE)
    print(f"written {FIGURE.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
