"""The report's one-line verdict: the headline speed-up with its interval, the caveat over too
few seeds, and the same line from ``skidnav run`` as in the report."""

from __future__ import annotations

import dataclasses
import math
import re
import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from skidnav.experiments.config import AgentSpec, ExperimentConfig, MapSpec
from skidnav.experiments.report.analysis import compare_to_baseline
from skidnav.experiments.report.verdict import verdict_text
from tests.experiments.exp_support import cli_command, cli_env
from tests.experiments.test_analysis import CONFIG, _summaries
from tests.experiments.test_driving_time import CONFIG as VALUE_CONFIG
from tests.experiments.test_driving_time import _summaries as value_summaries


def _verdict(summaries: pd.DataFrame) -> str:
    return verdict_text(compare_to_baseline(summaries, CONFIG), summaries, CONFIG)


def test_the_verdict_gives_the_speed_up_with_its_interval() -> None:
    summaries = _summaries()
    slower = (summaries["agent"] == "D") & (summaries["preset"] == "slippery")
    summaries.loc[slower, "convergence_episode"] *= 2.0  # D: 4× on rough, 2× on slippery
    line = _verdict(summaries)
    match = re.fullmatch(
        r"Verdict: D converges (\d+\.\d)× faster than Q \(significant: 95% interval "
        r"\[(\d+\.\d), (\d+\.\d)\], 30 seeds; median convergence episode, m · rough\); "
        r"significantly faster in 2, slower in 0, of 2 comparisons \(agent × cell\)\.",
        line,
    )
    assert match is not None, line
    estimate, low, high = (float(group) for group in match.groups())
    assert estimate == 4.0 and low <= estimate <= high


THREE = ExperimentConfig(
    "synthetic",
    (AgentSpec("q-learning", "Q"), AgentSpec("dyna-q", "D"), AgentSpec("dyna-full", "F")),
    (MapSpec("m", "free"),),
    seeds=6,
)


def _table(*rows: tuple[str, float, float, float]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(comparisons, summaries) of agents against Q in one cell, 6 seeds each: rows of
    (agent, speed-up, interval low, interval high)."""
    comparisons = pd.DataFrame(
        [
            {"map": "m", "preset": "thesis", "agent": agent, "speedup": estimate,
             "speedup_low": low, "speedup_high": high, "speedup_bound": ""}
            for agent, estimate, low, high in rows
        ]
    )  # fmt: skip
    summaries = pd.DataFrame(
        [
            {"map": "m", "preset": "thesis", "agent": agent, "seed": seed}
            for agent in ("Q", *(row[0] for row in rows))
            for seed in range(6)
        ]
    )
    return comparisons, summaries


def test_the_verdict_leads_with_the_thesis_agent_not_the_largest_estimate() -> None:
    comparisons, summaries = _table(("D", 9.0, 6.0, 12.0), ("F", 3.0, 2.0, 4.5))
    line = verdict_text(comparisons, summaries, THREE)
    assert line.startswith("Verdict: F converges 3.0× faster than Q (significant: 95% interval "
                           "[2.0, 4.5], 6 seeds;"), line  # fmt: skip
    assert "9.0" not in line and line.endswith("faster in 2, slower in 0, of 2 comparisons "
                                               "(agent × cell).")  # fmt: skip


def test_the_verdict_leads_with_the_configured_headline() -> None:
    comparisons, summaries = _table(("D", 2.0, 1.5, 2.5), ("F", 3.0, 2.0, 4.5))
    chosen = dataclasses.replace(THREE, headline="D")
    assert verdict_text(comparisons, summaries, chosen).startswith("Verdict: D converges 2.0×")
    with pytest.raises(ValueError, match="headline"):
        dataclasses.replace(THREE, headline="Q")  # the baseline is no headline
    with pytest.raises(ValueError, match="headline"):
        dataclasses.replace(THREE, headline="nobody")


def test_a_bound_near_one_shows_its_side_of_one() -> None:
    comparisons, summaries = _table(("F", 1.8, 1.004, 3.2))
    line = verdict_text(comparisons, summaries, THREE)
    assert "(significant: 95% interval [1.004, 3.2]" in line, line
    comparisons, summaries = _table(("F", 1.8, 0.996, 3.2))
    line = verdict_text(comparisons, summaries, THREE)
    assert "(not significant: 95% interval [0.996, 3.2]" in line, line
    assert "significantly faster in 0," in line


def test_a_speed_up_under_one_is_said_as_slower() -> None:
    comparisons, summaries = _table(("D", 5.0, 3.0, 8.0), ("F", 0.2, 0.1, 0.5))
    line = verdict_text(comparisons, summaries, THREE)
    assert line.startswith("Verdict: F converges 5.0× slower than Q (significant: 95% interval "
                           "[2.0, 10.0], 6 seeds;"), line  # fmt: skip
    assert "0.2×" not in line and "faster in 1, slower in 1, of 2" in line


def test_an_interval_containing_one_is_not_significant() -> None:
    comparisons, summaries = _table(("F", 1.6, 0.7, 2.9))
    line = verdict_text(comparisons, summaries, THREE)
    assert "F converges 1.6× faster than Q (not significant: 95% interval [0.7, 2.9]" in line
    assert "significantly faster in 0, slower in 0, of 1 comparison" in line


def test_two_seeds_give_a_caveat_instead_of_an_interval() -> None:
    summaries = _summaries()
    line = _verdict(summaries[summaries["seed"] < 2])
    assert "(2 seeds: too few for an interval;" in line
    assert "interval [" not in line and "significantly" not in line


def test_one_agent_or_no_convergence_is_said_in_words() -> None:
    summaries = _summaries()
    assert "no speed-up to report" in _verdict(summaries[summaries["agent"] == "Q"])
    summaries["converged"] = 0.0  # every run censored at its time
    assert "unknown" in _verdict(summaries) and "nan" not in _verdict(summaries)


def test_run_prints_the_verdict_of_the_report(
    serial_results: Path, tiny_config_file: Path, tmp_path: Path
) -> None:
    out = tmp_path / "results"
    shutil.copytree(serial_results, out)  # finished: the run only prints
    result = subprocess.run(
        cli_command("run", str(tiny_config_file), "--out", str(out), "--backend", "serial"),
        capture_output=True, text=True, env=cli_env(), timeout=120,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("8 runs in ") and lines[1].startswith("Verdict: ")
    from skidnav.experiments.report.verdict import experiment_verdict

    assert lines[1] == experiment_verdict(out)


def test_a_kinematic_model_comparison_leads_with_the_value_of_learning() -> None:
    arms = tuple(agent for agent in VALUE_CONFIG.agents if agent.name == "dyna-full")
    config = dataclasses.replace(VALUE_CONFIG, agents=arms, baseline=arms[0].label)
    summaries = value_summaries()
    summaries["driving_seconds"] = 1000.0
    prior = summaries["agent"] == "dyna-full[kinematic_model=prior]"
    summaries.loc[prior & (summaries["seed"] < 7), "seconds_to_success90"] = math.nan
    line = verdict_text(pd.DataFrame(), summaries, config)  # no convergence to compare
    match = re.fullmatch(
        r"Verdict: value of learning the kinematic model of dyna-full, learned − prior \(paired "
        r"by world, m · thesis\): driving to sustained ≥ 90 % greedy success, Kaplan–Meier "
        r"median (\d+) s against ∞ \(12 of 12 and 5 of 12 runs got there\); success rate "
        r"\S+ \S+ \S+ \(not significant: 95% interval, 12 worlds\); learned − prior clear of 0 "
        r"in (\d), no difference measured in (\d), of 7 comparisons \(metric × cell\)\.",
        line,
    )
    assert match is not None, line
    # The first success comes 30 s sooner in every world: one clear difference at least.
    assert 100 <= int(match[1]) <= 200 and int(match[2]) >= 1
    assert int(match[2]) + int(match[3]) == 7  # the driving over all episodes too
    # With another agent beside the arms the experiment is about that agent again.
    comparisons = pd.DataFrame([{
        "map": "m", "preset": "thesis", "agent": arms[0].label, "speedup": 2.0,
        "speedup_low": 1.5, "speedup_high": 3.0, "speedup_bound": "",
    }])  # fmt: skip
    mixed = verdict_text(comparisons, summaries, VALUE_CONFIG)
    assert mixed.startswith(f"Verdict: {arms[0].label} converges 2.0× faster than q"), mixed
