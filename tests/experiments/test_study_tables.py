"""``skidnav report RUN_DIR --study``: the real-robot study's tables of an experiment."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.studies.hardware.experiment_tables import study_summaries


def test_study_tables_summarise_each_run_from_its_episodes(
    serial_results: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "study.md"
    assert main(["report", str(serial_results), "--study", "-o", str(output)]) == 0
    assert str(output) in capsys.readouterr().out
    text = output.read_text()
    episodes, _ = ResultStore(serial_results).load_tables()
    runs = episodes.groupby("run_id")
    assert text.startswith(f"{runs.ngroups} runs, {len(episodes)} episodes")
    for (agent, preset), cell in episodes.groupby(["agent", "preset"]):
        per_run = cell.groupby("run_id")
        success = 100 * per_run["success"].mean().mean()
        length = per_run["length"].mean().mean()
        row = re.search(rf"^\| {re.escape(agent)} \| {preset} \| 2 \| 12 \| (.*)$", text, re.M)
        assert row is not None, (agent, preset)
        cells = row.group(1).split(" | ")
        assert cells[0].startswith(f"{success:.1f}")
        assert cells[2].startswith(f"{length:.1f}")
    assert "## Rough vs slippery floor" in text and "## Minus q-learning" in text


def test_the_last_half_is_the_second_half_of_each_run(serial_results: Path) -> None:
    episodes, _ = ResultStore(serial_results).load_tables()
    summaries = study_summaries(episodes).set_index("run_id")
    for run_id, run in episodes.groupby("run_id"):
        late = run.sort_values("episode")["success"].to_numpy()[len(run) // 2 :]
        assert summaries.loc[run_id, "success_rate_last_half"] == pytest.approx(late.mean())
        assert summaries.loc[run_id, "aborted"] == 0


def test_a_missing_results_directory_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["report", str(tmp_path / "none"), "--study"]) == 2
    error = capsys.readouterr().err.strip()
    assert "no such results directory" in error and "\n" not in error
