"""Comparisons with the baseline and the thesis verdicts on synthetic per-run summaries."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

from skidnav.experiments.config import AgentSpec, ExperimentConfig, MapSpec
from skidnav.experiments.report.analysis import (
    aggregate,
    compare_surfaces,
    compare_to_baseline,
    convergence_table,
)
from skidnav.experiments.report.cells import aggregate_table
from skidnav.experiments.report.reproduction import reproduction_section

CONFIG = ExperimentConfig(
    "synthetic",
    (AgentSpec("q-learning", "Q"), AgentSpec("dyna-q", "D")),
    (MapSpec("m", "free"),),
    presets=("rough", "slippery"),
    seeds=30,
    bootstrap_samples=500,
)


def _summaries(seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    rows = []
    for preset, rate in (("rough", 0.8), ("slippery", 0.4)):
        for s in range(30):
            base = rng.uniform(80, 120)
            length = rng.uniform(10, 14)
            for agent, factor, gain in (("Q", 1.0, 0.0), ("D", 0.25, 0.1)):
                rows.append({
                    "agent": agent, "map": "m", "preset": preset, "seed": s,
                    "convergence_episode": base * factor, "optimality_gap": 0.05,
                    "oracle_length": 12.0, "converged": 1.0, "first_success_episode": 1.0,
                    "final_length_actions": length, "final_length_m": length * 0.04,
                    "success_rate": rate * (1 - gain) + gain, "success_rate_last10": rate,
                    "mean_return": -10.0, "collisions_per_episode": 1.0,
                    "planning_updates": 0.0, "wall_time": 1.0,
                })  # fmt: skip
    return pd.DataFrame(rows)


def test_speedup_gain_and_length_difference() -> None:
    table = compare_to_baseline(_summaries(), CONFIG)
    assert len(table) == 2 and set(table["agent"]) == {"D"}
    row = table[table["preset"] == "rough"].iloc[0]
    assert row["speedup"] == pytest.approx(4.0) and row["speedup_low"] == pytest.approx(4.0)
    assert row["success_gain"] == pytest.approx(0.1 * (1 - 0.8))
    assert row["length_difference"] == 0.0 and row["length_no_difference"]
    assert row["length_pairs"] == 30 and row["baseline_converged"] == 1.0


def test_a_mostly_censored_baseline_gives_a_lower_bound() -> None:
    summaries = _summaries()
    base = summaries["agent"] == "Q"
    censored = base & (summaries["seed"] >= 10)  # 20 of 30 baseline runs never converged
    summaries.loc[censored, "converged"] = 0.0
    summaries.loc[censored, "convergence_episode"] = 491.0
    row = compare_to_baseline(summaries, CONFIG).iloc[0]
    assert row["speedup_bound"] == "lower"
    # The baseline's largest censoring time stands in for its (infinite) median.
    agent_median = np.median(
        summaries[(summaries["agent"] == "D") & (summaries["preset"] == "rough")][
            "convergence_episode"
        ]
    )
    assert row["speedup"] == pytest.approx(491.0 / agent_median, rel=0.1)
    assert row["improvement_probability"] > 0.99
    table = convergence_table(summaries, CONFIG)
    q = table[(table["agent"] == "Q") & (table["preset"] == "rough")].iloc[0]
    assert (
        q["median"] == np.inf and q["converged"] == pytest.approx(1 / 3) and q["censored_at"] == 491
    )
    text = reproduction_section(
        compare_to_baseline(summaries, CONFIG), pd.DataFrame(), summaries, CONFIG
    )
    assert "≥ " in text


def test_aggregate_has_intervals_around_estimates() -> None:
    table = aggregate(_summaries(), CONFIG)
    assert set(table["metric"]) >= {"convergence_episode", "success_rate"}
    assert (table["mean_low"] <= table["mean"] + 1e-9).all()
    assert (table["mean"] <= table["mean_high"] + 1e-9).all()
    assert (table["n"] == 30).all()


def test_surfaces_ratio_and_verdicts() -> None:
    summaries = _summaries()
    surfaces = compare_surfaces(summaries, CONFIG)
    q = surfaces[(surfaces["agent"] == "Q") & (surfaces["metric"] == "success_rate")].iloc[0]
    assert q["ratio"] == pytest.approx(2.0)
    text = reproduction_section(compare_to_baseline(summaries, CONFIG), surfaces, summaries, CONFIG)
    assert "4.00×" in text and "no difference found" in text
    assert "mixed: 2× within 1 of 2" in text  # D's ratio (0.82 / 0.46) excludes 2


def test_few_pairs_make_the_length_claim_inconclusive() -> None:
    summaries = _summaries()
    summaries.loc[
        (summaries["agent"] == "Q") & (summaries["seed"] >= 5), "final_length_actions"
    ] = np.nan
    comparisons = compare_to_baseline(summaries, CONFIG)
    assert (comparisons["length_pairs"] == 5).all()
    text = reproduction_section(comparisons, pd.DataFrame(), summaries, CONFIG)
    assert "inconclusive" in text


def test_one_seed_prints_estimates_without_bounds() -> None:
    summaries = _summaries()
    one_seed = summaries[summaries["seed"] == 0]
    text = aggregate_table(aggregate(one_seed, CONFIG), "m", "rough")
    assert "nan" not in text and not re.search(r"\d \[", text)  # no "12.00 [nan, nan]"
    assert "<td>1</td>" in text  # e.g. the converged share of the single seed
    details = reproduction_section(
        compare_to_baseline(one_seed, CONFIG), pd.DataFrame(), one_seed, CONFIG
    )
    assert "nan" not in details


def test_floor_claim_points_to_the_surfaces_config() -> None:
    summaries = _summaries()
    thesis_like = summaries[summaries["preset"] == "rough"]
    text = reproduction_section(
        compare_to_baseline(thesis_like, CONFIG), pd.DataFrame(), thesis_like, CONFIG
    )
    assert "rough floor ≈ 2×" in text and "configs/surfaces.toml" in text
    assert "not measured here" in text


def test_budget_rows_and_figure_for_a_planning_sweep() -> None:
    from skidnav.experiments.report.analysis import budget_rows
    from skidnav.experiments.report.html import budget_section

    config = ExperimentConfig(
        "budget",
        (
            AgentSpec("q-learning", "Q"),
            AgentSpec("dyna-q", "D10", (("planning_steps", 10),)),
            AgentSpec("dyna-q", "D100", (("planning_steps", 100),)),
        ),
        (MapSpec("m", "free"),),
        seeds=30,
        bootstrap_samples=200,
    )
    rng = np.random.default_rng(1)
    rows = []
    for seed in range(30):
        base = rng.uniform(800, 1200)
        for agent, factor, wall in (("Q", 1.0, 1.0), ("D10", 0.5, 2.0), ("D100", 0.1, 9.0)):
            rows.append({"agent": agent, "map": "m", "preset": "thesis", "seed": seed,
                         "convergence_episode": base * factor, "converged": 1.0,
                         "optimality_gap": 0.0, "oracle_length": 12.0, "first_success_episode": 1.0,
                         "final_length_actions": 12.0, "final_length_m": 0.5, "success_rate": 0.9,
                         "success_rate_last10": 1.0, "mean_return": -5.0,
                         "collisions_per_episode": 0.0, "planning_updates": 0.0,
                         "wall_time": wall})  # fmt: skip
    summaries = pd.DataFrame(rows)
    comparisons = compare_to_baseline(summaries, config)
    aggregates = aggregate(summaries, config)
    table = budget_rows(comparisons, aggregates, config).set_index("planning_steps")
    assert table.loc[10, "speedup"] == pytest.approx(2.0)
    assert table.loc[100, "speedup"] == pytest.approx(10.0)
    assert table.loc[100, "wall_time"] == pytest.approx(9.0)
    assert (table["bound"] == "").all()
    assert "Planning budget" in budget_section(comparisons, aggregates, config)
