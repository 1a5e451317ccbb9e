"""The report's one-line verdict: the headline speed-up with its interval, the caveat over too
few seeds, and the same line from ``skidnav run`` as in the report."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pandas as pd

from skidnav.experiments.report.analysis import compare_to_baseline
from skidnav.experiments.report.verdict import verdict_text
from tests.experiments.exp_support import cli_command, cli_env
from tests.experiments.test_analysis import CONFIG, _summaries


def _verdict(summaries: pd.DataFrame) -> str:
    return verdict_text(compare_to_baseline(summaries, CONFIG), summaries, CONFIG)


def test_the_verdict_names_the_largest_speed_up_with_its_interval() -> None:
    summaries = _summaries()
    slower = (summaries["agent"] == "D") & (summaries["preset"] == "slippery")
    summaries.loc[slower, "convergence_episode"] *= 2.0  # D: 4× on rough, 2× on slippery
    line = _verdict(summaries)
    match = re.fullmatch(
        r"Verdict: D converges (\d+\.\d)× faster than Q \(95% interval \[(\d+\.\d), (\d+\.\d)\], "
        r"30 seeds; median convergence episode, m · rough\); significantly faster in 2 of 2 "
        r"comparisons \(agent × cell\)\.",
        line,
    )
    assert match is not None, line
    estimate, low, high = (float(group) for group in match.groups())
    assert estimate == 4.0 and low <= estimate <= high


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
