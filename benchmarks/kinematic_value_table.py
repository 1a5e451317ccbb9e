"""The learned-against-prior tables of docs/kinematic-value.md, read from the results of a
config that sweeps ``kinematic_model`` over "learned" and "prior" (e.g.
``configs/kinematic-value-seconds-mppi.toml``): one Markdown row per map and floor.

Cells are learned / prior; a difference is learned − prior paired by world with its 95 %
bootstrap interval (:func:`skidnav.experiments.report.learning_value.value_of_learning`, the
report's own numbers), **bold** where the interval excludes 0. Times to the first and to
sustained success (every evaluation from then on with ≥ 90 % of its rollouts at the goal) are
each arm's Kaplan–Meier median over all its runs, a run that never got there censored at its
whole driving time, or at the run's last episode for the episode counts (∞: more than half never
did); the mean difference of the first success is over the worlds where both arms got there.
Final greedy success: the mean over worlds of the last evaluation's share of starts at the goal.
On a grid run in parts (``skidnav run --runs``) every cell of a row is over the worlds both arms
ran, named in the row ("k of N worlds") when fewer than the grid's; an arm with no runs in a
row reads "no runs", with only the other arm's cells filled in.

    python benchmarks/kinematic_value_table.py runs/kinematic-value-seconds-mppi
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
from navigator_targets import final_greedy

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.report.analysis import common_worlds
from skidnav.experiments.report.learning_value import (
    arm_survival,
    model_arms,
    signed,
    value_of_learning,
)
from skidnav.experiments.store import EXPERIMENT_LAYOUT, ResultStore
from skidnav.statistics.formatting import readable

HEADER = (
    "| map · floor | driving over all episodes [s] | first success: KM median [s]; mean "
    "difference | sustained ≥ 90 %: runs, KM median [s] | episodes to first / sustained "
    "success, KM median | success rate | final greedy success | collisions per episode |\n"
    "|---|---|---|---|---|---|---|---|"
)


MINUS = str.maketrans("-", "−")
"""Numbers are printed with the minus sign, as the docs' tables are."""


def number(value: float) -> str:
    """A value rounded for people (∞ for an infinite one)."""
    return readable(value).translate(MINUS)


def difference(values: pd.DataFrame, metric: str) -> str:
    """learned − prior of ``metric`` with its interval, bold where it excludes 0 ("–" with no
    world run by both arms)."""
    row = values[values["metric"] == metric]
    if row.empty or row.iloc[0]["pairs"] == 0:
        return "–"
    found = row.iloc[0]
    text = signed(found).translate(MINUS)
    clear = np.isfinite(found["difference_low"]) and not found["no_difference"]
    return f"**{text}**" if clear else text


def cell_row(
    cell: pd.DataFrame, values: pd.DataFrame, labels: tuple[str, str], config: ExperimentConfig
) -> str:
    """The Markdown row of one map and floor: ``cell`` its runs, ``values`` its learned − prior
    differences, ``labels`` the learned and prior arms' agent labels."""
    key = (str(cell["map"].iloc[0]), str(cell["preset"].iloc[0]))
    ran = [label for label in labels if (cell["agent"] == label).any()]
    if len(ran) == len(labels):
        cell = common_worlds(cell, *labels)
    arm = {label: cell[cell["agent"] == label] for label in labels}
    worlds = len(arm[ran[0]])
    title = f"{key[0]} · {key[1]}"
    if worlds < config.seeds:
        title += f" ({worlds} of {config.seeds} worlds)"

    def both(text: Callable[[str], str]) -> str:
        return " / ".join(text(label) if label in ran else "no runs" for label in labels)

    def mean(metric: str) -> str:
        return both(lambda label: number(arm[label][metric].mean()))

    def survival(metric: str, censor_at: float | None = None) -> str:
        return both(
            lambda label: number(
                arm_survival(cell, label, metric, config, *key, censor_at=censor_at).estimate
            )
        )

    def episodes(metric: str) -> str:  # a run that never got there: censored at its last episode
        return survival(metric, censor_at=float(config.episodes))

    reached = both(lambda label: str(int(arm[label]["seconds_to_success90"].notna().sum())))
    final = both(lambda label: f"{100 * arm[label]['final_greedy'].mean():.0f} %")
    cells = [
        title,
        f"{mean('driving_seconds')}: {difference(values, 'driving_seconds')}",
        f"{survival('seconds_to_first_success')}; {difference(values, 'seconds_to_first_success')}",
        f"{reached} of {worlds}; {survival('seconds_to_success90')}",
        f"{episodes('episodes_to_first_success')}; {episodes('episodes_to_success90')}",
        f"{mean('success_rate')}: {difference(values, 'success_rate')}",
        final,
        f"{mean('collisions_per_episode')}: {difference(values, 'collisions_per_episode')}",
    ]
    return "| " + " | ".join(cells) + " |"


def table_rows(summaries: pd.DataFrame, config: ExperimentConfig) -> list[str]:
    """The Markdown rows of the module doc, one per (learned/prior arms, map, floor), from the
    runs' summaries with their ``final_greedy`` column."""
    values = value_of_learning(summaries, config)
    if values.empty:
        return []
    values = values[values["comparison"] == "learned − prior"]
    lines = []
    for arms in model_arms(config):
        if "learned" not in arms.labels or "prior" not in arms.labels:
            continue
        labels = (arms.labels["learned"], arms.labels["prior"])
        for (map_label, preset), cell in summaries.groupby(["map", "preset"], sort=False):
            if not cell["agent"].isin(labels).any():
                continue  # neither arm run here yet
            mine = values[
                (values["map"] == map_label) & (values["preset"] == preset)
                & (values["agent"] == arms.name)
            ]  # fmt: skip
            lines.append(cell_row(cell, mine, labels, config))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a results directory of a learned/prior sweep")
    args = parser.parse_args()
    config = ResultStore(args.run, EXPERIMENT_LAYOUT).config()
    print(HEADER)
    print("\n".join(table_rows(final_greedy(args.run), config)))


if __name__ == "__main__":
    main()
