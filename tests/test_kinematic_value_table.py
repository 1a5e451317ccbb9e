"""The learned-against-prior table of docs/kinematic-value.md (``benchmarks/
kinematic_value_table.py``): its cells are the report's paired differences and Kaplan–Meier
medians, bold only where the interval excludes 0."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from skidnav.experiments.config import AgentSpec, ExperimentConfig, MapSpec, freeze_params
from tests.benchmark_scripts import benchmark

table = benchmark("kinematic_value_table")


def _arm(model: str) -> AgentSpec:
    params = freeze_params({"kinematic_model": model})
    return AgentSpec("mppi-kinematic", f"mppi-kinematic[kinematic_model={model}]", params)


CONFIG = ExperimentConfig(
    "value", (_arm("learned"), _arm("prior")), (MapSpec("m", "maze"),), seeds=10, episodes=30,
    bootstrap_samples=500,
)  # fmt: skip


def _summaries() -> pd.DataFrame:
    """10 worlds: learned drives 100 s less over the run in every world and reaches the goal
    20 s sooner; the prior arm reaches sustained success in 3 worlds only; collisions alike up
    to noise."""
    rng = np.random.default_rng(5)
    rows = []
    for seed in range(10):
        world = rng.uniform(500, 900)
        for label, shift in (("learned", -100.0), ("prior", 0.0)):
            sustained = label == "learned" or seed < 3
            rows.append({
                "agent": f"mppi-kinematic[kinematic_model={label}]", "map": "m",
                "preset": "rough-physics", "seed": seed,
                "driving_seconds": world + shift,
                "seconds_to_first_success": 50.0 + shift / 5 + seed,
                "episodes_to_first_success": 1.0 if label == "learned" else 2.0,
                "seconds_to_success90": 60.0 + seed if sustained else math.nan,
                "episodes_to_success90": 2.0 if sustained else math.nan,
                "success_rate": 1.0 if label == "learned" else 0.8,
                "collisions_per_episode": 1.0 + rng.normal(0, 0.3),
                "final_greedy": 1.0 if label == "learned" else 0.6,
            })  # fmt: skip
    return pd.DataFrame(rows)


def test_a_row_per_floor_with_the_paired_differences_and_the_censored_medians() -> None:
    (row,) = table.table_rows(_summaries(), CONFIG)
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert len(cells) == len(table.HEADER.splitlines()[1].strip("|").split("|"))
    assert cells[0] == "m · rough-physics"
    assert cells[1].endswith("**−100 [−100, −100]**")  # paired by world: exactly −100 s
    assert cells[2].endswith("**−20.0 [−20.0, −20.0]**")
    assert cells[3].startswith("10 / 3 of 10") and cells[3].endswith("/ ∞")  # 7 of 10 censored
    assert cells[4] == "1 / 2; 2 / ∞"
    assert cells[5].endswith("**+0.200 [0.200, 0.200]**")
    assert cells[6] == "100 % / 60 %"
    assert "**" not in cells[7]  # collisions differ by noise only: not bold


def test_a_config_without_both_arms_gives_no_row() -> None:
    lone = ExperimentConfig("x", (_arm("learned"),), CONFIG.maps, seeds=10)
    assert table.table_rows(_summaries(), lone) == []


def test_a_grid_run_in_part_compares_the_worlds_both_arms_ran() -> None:
    summaries = _summaries()
    prior = summaries["agent"].str.contains("prior")
    summaries.loc[~prior & (summaries["seed"] >= 5), "driving_seconds"] += 10_000.0
    (row,) = table.table_rows(summaries[~prior | (summaries["seed"] < 5)], CONFIG)
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert cells[0] == "m · rough-physics (5 of 10 worlds)"
    learned, prior_mean = (float(x) for x in cells[1].split(":")[0].split(" / "))
    assert learned - prior_mean == pytest.approx(-100, abs=1)  # learned worlds 5-9 left out
    assert cells[1].endswith("**−100 [−100, −100]**")
    assert cells[3].startswith("5 / 3 of 5")


def test_an_arm_with_no_runs_reads_no_runs() -> None:
    summaries = _summaries()
    (row,) = table.table_rows(summaries[~summaries["agent"].str.contains("prior")], CONFIG)
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert cells[0] == "m · rough-physics"
    assert cells[1].endswith(" / no runs: –")
    assert cells[3].startswith("10 / no runs of 10")
    assert cells[6] == "100 % / no runs"


def test_a_floor_that_neither_arm_has_run_yet_gives_no_row() -> None:
    summaries = _summaries()
    other = summaries.assign(agent="dyna-full", preset="slippery-physics")
    rows = table.table_rows(pd.concat([summaries, other]), CONFIG)
    assert [row.split("|")[1].strip() for row in rows] == ["m · rough-physics"]
