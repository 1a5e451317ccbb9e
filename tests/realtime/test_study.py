"""The hardware-in-the-loop study: runs against the sim server, CSV/markdown, resume, tables."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from realtime_helpers import write_config
from test_run import small_room_map

from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.realtime.study import load_study
from skidnav.realtime.study_report import markdown_report


def study_config(tmp_path: Path) -> Path:
    room = small_room_map(tmp_path / "room.txt")
    return write_config(
        tmp_path,
        f"""
[study]
agents = ["q-learning", "dyna-q"]
presets = ["rough-stationary", "slippery-drifting"]

[run]
episodes = 5
max_actions = 15
time_scale = 30.0
map = "{room}"
reconnect_timeout = 2.0

[agents.dyna-q]
planning_steps = 5

[presets.rough-stationary.sim]
slip = "rough"

[presets.slippery-drifting.sim]
slip = "slippery"
drift = 0.5
drift_period = 30.0
""",
    )


def test_study_writes_tables_and_skips_finished_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config, out = study_config(tmp_path), tmp_path / "study"
    argv = ["robot", "study", "--config", str(config), "--episodes", "2", "--quiet"]
    assert main([*argv, "--out", str(out)]) == 0
    assert "4 runs finished" in capsys.readouterr().out
    with (out / "study.csv").open(encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))
    assert {(r["agent"], r["preset"], r["seed"]) for r in rows} == {
        (agent, preset, "0")
        for agent in ("q-learning", "dyna-q")
        for preset in ("rough-stationary", "slippery-drifting")
    }
    for row in rows:
        episodes, successes = int(row["episodes"]), int(row["successes"])
        assert episodes == 2 and 0 <= successes <= episodes
        assert float(row["success_rate"]) == pytest.approx(successes / episodes, abs=1e-4)
        assert 1 <= float(row["mean_episode_actions"]) <= 15
        assert 0 <= int(row["aborted"]) <= episodes
        run = out / "runs" / row["agent"] / row["preset"] / "seed-0"
        summary = json.loads((run / "result.json").read_text())
        assert summary["successes"] == successes
        transitions = (run / "run.jsonl").read_text().count('"event": "transition"')
        assert transitions == pytest.approx(episodes * float(row["mean_episode_actions"]))
    report = (out / "study.md").read_text()
    assert "| q-learning | slippery-drifting | 1 | 2 |" in report
    assert "| dyna-q | rough | 1 |" in report and "| dyna-q | slippery | 1 |" in report
    assert "no floor pairs" in report  # rough-stationary vs slippery-drifting: no pair

    # a second call skips the finished runs (no server, logs untouched) and rewrites the tables
    kept = out / "runs" / "q-learning" / "rough-stationary" / "seed-0" / "run.jsonl"
    before = kept.read_bytes()
    (out / "study.csv").unlink()
    assert main([*argv, "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.err.count("skipped") == 4 and "4 runs finished" in captured.out
    assert kept.read_bytes() == before
    with (out / "study.csv").open(encoding="utf-8") as stream:
        assert list(csv.DictReader(stream)) == rows
    assert (out / "study.md").read_text() == report


def study_row(
    agent: str, preset: str, seed: int, successes: int, late: int, length: float = 50.0
) -> dict[str, object]:
    """A study.csv row of 20 episodes, ``late`` of the ``successes`` in the last 10."""
    return {
        "agent": agent,
        "preset": preset,
        "seed": seed,
        "episodes": 20,
        "successes": successes,
        "success_rate": successes / 20,
        "mean_episode_actions": length,
        "aborted": 0,
        "late_episodes": 10,
        "late_successes": late,
    }


def test_report_estimates_are_seed_means_with_paired_comparisons() -> None:
    conditions = {"r": ("rough", False), "s": ("slippery", False), "d": ("rough", True)}
    rows = [
        study_row("q-learning", "r", 0, 4, 4, 80.0),
        study_row("q-learning", "r", 1, 8, 6, 60.0),
        study_row("q-learning", "s", 0, 2, 2),
        study_row("q-learning", "s", 1, 2, 2),
        study_row("dyna-q", "r", 0, 12, 8, 40.0),
        study_row("dyna-q", "r", 1, 12, 8, 40.0),
        study_row("dyna-q", "s", 0, 0, 0),
        study_row("dyna-q", "d", 0, 0, 0),
    ]
    report = markdown_report(rows, conditions)
    # q-learning on r: success 20 % and 40 % → 30 %; last half 40 %, 60 % → 50 %; length 70
    line = next(x for x in report.splitlines() if x.startswith("| q-learning | r |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[2:4] == ["2", "40"] and cells[-1] == "0"
    assert cells[4].startswith("30.0 [") and cells[5].startswith("50.0 [")
    assert cells[6].startswith("70.0 [")
    for cell in cells[4:7]:  # the interval lies within the two seeds' values
        low, high = (float(v) for v in cell.split("[")[1].rstrip("]").split(","))
        assert low <= float(cell.split()[0]) <= high
    # one seed: no interval
    assert "| dyna-q | s | 1 | 20 | 0.0 | 0.0 | 50.0 | 0 |" in report
    # rough / slippery, paired by seed, on the last half: (40 + 60) / 2 over 20
    assert "| q-learning | stationary | 2 | 50.0 | 20.0 | 2.50 [" in report
    assert "| dyna-q | stationary | 1 | 80.0 | 0.0 | ∞ (slippery 0) |" in report
    assert "| dyna-q | drifting |" not in report  # no slippery drifting run
    # dyna-q minus q-learning on the rough floor: pairs (r, 0), (r, 1); (d, 0) has no partner
    assert "| dyna-q | rough | 2 | +30.0 [+20.0, +40.0] | +30.0 [+20.0, +40.0] |" in report
    assert "+30.0 [+20.0, +40.0] | -30.0 [-40.0, -20.0] |" in report
    assert "| dyna-q | slippery | 1 | -10.0 | -20.0 | +0.0 |" in report


def test_study_settings_from_table_and_overrides(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = study_config(tmp_path)
    tables, settings = load_study(config, {"seeds": 3, "agents": "dyna-q", "episodes": None})
    assert "study" not in tables and settings.agents == ("dyna-q",)
    assert settings.presets == ("rough-stationary", "slippery-drifting") and settings.seeds == 3
    with pytest.raises(UserError, match="seeds"):
        load_study(config, {"seeds": 0})
    out = tmp_path / "out"
    argv = ["robot", "study", "--config", str(config), "--agents", "dyna-nope", "--out", str(out)]
    assert main(argv) == 2
    assert "unknown agent 'dyna-nope'" in capsys.readouterr().err
    assert not out.exists()
