"""The hardware-in-the-loop study through the experiment runner: real-time runs against the sim
server, the store's tables, resume after an interruption, seeds, the markdown tables."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.experiments.runs import RunSpec, expand_runs
from skidnav.experiments.store import ResultStore
from skidnav.realtime.control.loop import EXIT_INTERRUPTED
from skidnav.realtime.control.records import EpisodeResult
from skidnav.studies.hardware.report import markdown_report
from skidnav.studies.hardware.study import (
    STUDY_LAYOUT,
    grid_from_dict,
    grid_to_dict,
    load_study,
    run_study,
)
from skidnav.studies.hardware.trial import RealtimeOutcome, run_config
from tests.realtime.realtime_helpers import write_config
from tests.realtime.test_run import small_room_map

AGENTS = ("q-learning", "dyna-q")
PRESETS = ("rough-stationary", "slippery-drifting")


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


def summaries_of(out: Path) -> pd.DataFrame:
    return pd.read_csv(out / "summaries.csv")


def test_study_runs_through_the_runner_and_skips_finished_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config, out = study_config(tmp_path), tmp_path / "study"
    argv = ["robot", "study", "--config", str(config), "--episodes", "2", "--quiet"]
    assert main([*argv, "--out", str(out)]) == 0
    assert "4 of 4 runs finished (4 run now, 0 done before)" in capsys.readouterr().out
    summaries = summaries_of(out)
    assert {(r.agent, r.preset, r.seed) for r in summaries.itertuples()} == {
        (agent, preset, 0) for agent in AGENTS for preset in PRESETS
    }
    episodes = pd.read_parquet(out / "episodes.parquet")
    for row in summaries.itertuples():
        assert row.episodes == 2 and 0 <= row.successes <= 2 and row.exit_code == 0
        assert row.success_rate == pytest.approx(row.successes / 2)
        assert 1 <= row.mean_length <= 15 and row.aborted == 0
        lengths = episodes[episodes["run_id"] == row.run_id]["length"]
        assert lengths.mean() == pytest.approx(row.mean_length)
        logs = out / "runs" / row.agent / row.preset / "seed-0"
        transitions = (logs / "run.jsonl").read_text().count('"event": "transition"')
        assert transitions == lengths.sum()  # the stored episodes are the loop's
        assert (logs / "sim-server.jsonl").exists() and (logs / "checkpoints").is_dir()
    metadata = json.loads((out / "metadata.json").read_text())
    assert [s["completed"] for s in metadata["sessions"]] == [True]
    assert json.loads((out / "config.json").read_text())["kind"] == "robot-study"
    report = (out / "study.md").read_text()
    assert "| q-learning | slippery-drifting | 1 | 2 |" in report
    assert "| dyna-q | rough | 1 |" in report and "| dyna-q | slippery | 1 |" in report
    assert "no floor pair" in report  # rough-stationary vs slippery-drifting: no pair

    # a second call skips the finished runs (no server, logs untouched) and rewrites the tables
    kept = out / "runs" / "q-learning" / "rough-stationary" / "seed-0" / "run.jsonl"
    before = kept.read_bytes()
    (out / "study.md").unlink()
    assert main([*argv, "--out", str(out)]) == 0
    assert "4 of 4 runs finished (0 run now, 4 done before)" in capsys.readouterr().out
    assert kept.read_bytes() == before
    pd.testing.assert_frame_equal(summaries_of(out), summaries)
    assert (out / "study.md").read_text() == report
    metadata = json.loads((out / "metadata.json").read_text())
    assert [s["runs_done"] for s in metadata["sessions"]] == [4, 0]


def test_the_study_is_a_config_that_skidnav_run_runs_resumes_and_reports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    config, out, calls = study_config(tmp_path), tmp_path / "study", []
    monkeypatch.setattr("skidnav.studies.hardware.trial.realtime_run", fake_realtime(calls))
    argv = ["robot", "study", "--config", str(config), "--agents", "q-learning", "--quiet"]
    assert main([*argv, "--episodes", "2", "--out", str(out)]) == 0
    assert len(calls) == 2
    saved = out / "config.toml"  # the shortcut's config, as skidnav run saves a config
    assert 'kind = "robot-study"' in saved.read_text()
    capsys.readouterr()
    # skidnav run on it (serially, this study's only backend) finds every run done
    assert main(["run", str(saved), "--out", str(out), "--no-progress", "--report"]) == 0
    assert f"2 runs in {out} (0 run now, 2 already done)" in capsys.readouterr().out
    assert len(calls) == 2
    report = (out / "report.html").read_text()
    assert "<h1>skidnav robot-study: robot-study</h1>" in report
    assert "<h2>Hardware-in-the-loop study</h2>" in report
    assert "<td>q-learning</td><td>rough-stationary</td><td>1</td><td>2</td>" in report
    assert main(["run", str(saved), "--out", str(out), "--backend", "process"]) == 2
    error = capsys.readouterr().err.strip()
    assert error.endswith("a robot-study study runs only with --backend serial, not process")
    # the same study written out in one file (the real-time tables inline) is the same grid
    inline = tmp_path / "inline" / "study.toml"
    inline.parent.mkdir()
    study = 'agents = ["q-learning"]\nepisodes = 2'
    text = config.read_text().replace('agents = ["q-learning", "dyna-q"]', study)
    inline.write_text('kind = "robot-study"\n' + text)
    assert main(["run", str(inline), "--out", str(out), "--no-progress"]) == 0
    assert "(0 run now, 2 already done)" in capsys.readouterr().out
    # a config with [study] config takes no real-time table of its own
    mixed = tmp_path / "mixed.toml"
    mixed.write_text(f'kind = "robot-study"\n[study]\nconfig = "{config}"\n[sim]\nslip = "rough"\n')
    assert main(["run", str(mixed), "--out", str(tmp_path / "mixed")]) == 2
    error = capsys.readouterr().err
    assert error.startswith(
        "skidnav: error: expected config to be the name of a real-time config and no other "
        "table here, got "
    )
    assert error.endswith(f" and sim in {mixed}: [study]\n"), error


FakeRun = Callable[[RunSpec[Any], Path, Callable[[str], None]], RealtimeOutcome]


def fake_realtime(calls: list[str], interrupt_at: int = 0) -> FakeRun:
    """A stand-in for ``realtime_run``: episodes that depend on the run's seeds only (goal every
    other episode from a phase of the world seed), a file in the run's folder, and an
    interruption at the ``interrupt_at``-th call (1-based; 0: never)."""

    def run(spec: RunSpec[Any], out: Path, progress: Callable[[str], None]) -> RealtimeOutcome:
        calls.append(spec.run_id)
        (out / "run.jsonl").write_text("{}\n")
        config = run_config(spec)
        phase = config.run.seed % 2
        results = [
            EpisodeResult(e, actions=5 + e, reached_goal=(e + phase) % 2 == 0, wall_time=0.1)
            for e in range(config.run.episodes)
        ]
        if len(calls) == interrupt_at:
            return RealtimeOutcome(EXIT_INTERRUPTED, results[:1], {})
        return RealtimeOutcome(0, results, {})

    return run


def test_an_interrupted_study_resumes_with_no_run_lost_or_repeated(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    grid, text = load_study(study_config(tmp_path), {"seeds": 2, "episodes": 3})
    out, calls = tmp_path / "study", []
    monkeypatch.setattr("skidnav.studies.hardware.trial.realtime_run", fake_realtime(calls, 3))
    first = run_study(grid, out, source_text=text)
    assert first == (EXIT_INTERRUPTED, 8, 2, 2)
    store = ResultStore(out, STUDY_LAYOUT)
    assert store.finished() == {"run-000000", "run-000001"}
    assert "| q-learning | rough-stationary | 2 | 6 |" in (out / "study.md").read_text()
    interrupted = out / "runs" / "q-learning" / "slippery-drifting" / "seed-0"
    assert (interrupted / "run.jsonl").exists()  # unfinished: no run file

    monkeypatch.setattr("skidnav.studies.hardware.trial.realtime_run", fake_realtime(calls))
    second = run_study(grid, out, source_text=text)
    assert second == (0, 8, 8, 6)
    assert calls[3:] == [f"run-{i:06d}" for i in range(2, 8)]  # the interrupted run again
    assert store.finished() == {f"run-{i:06d}" for i in range(8)}
    sessions = json.loads((out / "metadata.json").read_text())["sessions"]
    assert [(s["runs_done"], s["completed"]) for s in sessions] == [(2, False), (6, True)]
    summaries = summaries_of(out)
    assert len(summaries) == 8 and set(summaries["episodes"]) == {3}


def test_runs_meet_the_worlds_of_the_runner_seeds(tmp_path: Path) -> None:
    grid, _ = load_study(study_config(tmp_path), {"seeds": 2})
    runs = expand_runs(grid)
    assert len(runs) == grid.n_runs == 8
    seeds = {(s.agent.name, s.preset, s.seed): run_config(s).run.seed for s in runs}
    # every agent meets the same world (arena and sim server seed) of a (preset, seed) ...
    for preset in PRESETS:
        for seed in range(2):
            assert seeds[("q-learning", preset, seed)] == seeds[("dyna-q", preset, seed)]
    # ... and the worlds differ between presets and seeds; the agents' own streams all differ
    assert len({seeds[("q-learning", p, s)] for p in PRESETS for s in range(2)}) == 4
    assert len({spec.run_seed for spec in runs}) == 8
    config = run_config(runs[-1])
    assert config.sim.slip == "slippery" and config.sim.drift == 0.5
    assert config.run.map == str(tmp_path / "room.txt") and config.run.episodes == 5
    assert grid_from_dict(json.loads(json.dumps(grid_to_dict(grid)))) == grid
    assert grid.conditions() == {PRESETS[0]: ("rough", False), PRESETS[1]: ("slippery", True)}


def study_row(
    agent: str, preset: str, seed: int, successes: int, late: int, length: float = 50.0
) -> dict[str, object]:
    """A summaries row of 20 episodes, ``late`` of the ``successes`` in the last 10."""
    return {
        "agent": agent,
        "algorithm": agent,
        "map": "room",
        "preset": preset,
        "seed": seed,
        "episodes": 20,
        "successes": successes,
        "success_rate": successes / 20,
        "late_episodes": 10,
        "late_successes": late,
        "success_rate_last_half": late / 10,
        "mean_length": length,
        "aborted": 0,
    }


SETTINGS = SimpleNamespace(
    root_seed=0,
    agent_labels=["q-learning", "dyna-q"],
    baseline="q-learning",
    bootstrap_samples=2000,
    confidence=0.95,
)
CONDITIONS = {
    "r": ("rough", False),
    "s": ("slippery", False),
    "d": ("rough", True),
    "e": ("slippery", True),
}


def _cells(report: str, start: str) -> list[str]:
    line = next(x for x in report.splitlines() if x.startswith(start))
    return [cell.strip() for cell in line.strip("|").split("|")]


def _bounds(cell: str) -> tuple[float, float, float]:
    low, high = (float(v) for v in cell.split("[")[1].rstrip("]").split(","))
    return float(cell.split()[0]), low, high


def test_report_estimates_are_seed_means_with_paired_comparisons() -> None:
    rows = [
        study_row("q-learning", "r", 0, 4, 4, 80.0),
        study_row("q-learning", "r", 1, 8, 6, 60.0),
        study_row("q-learning", "s", 0, 2, 2),
        study_row("q-learning", "s", 1, 2, 2),
        study_row("q-learning", "d", 0, 2, 2),
        study_row("q-learning", "e", 0, 4, 4),
        study_row("dyna-q", "r", 0, 12, 8, 40.0),
        study_row("dyna-q", "r", 1, 12, 8, 40.0),
        study_row("dyna-q", "s", 0, 0, 0),
        study_row("dyna-q", "d", 0, 0, 0),
        study_row("dyna-q", "e", 0, 0, 0),
    ]
    report = markdown_report(pd.DataFrame(rows), SETTINGS, CONDITIONS)
    # q-learning on r: success 20 % and 40 % → 30 %; last half 40 %, 60 % → 50 %; length 70
    cells = _cells(report, "| q-learning | r |")
    assert cells[2:4] == ["2", "40"] and cells[-1] == "0"
    for cell, estimate, values in zip(
        cells[4:7], (30.0, 50.0, 70.0), ((20, 40), (40, 60), (60, 80)), strict=True
    ):
        mean, low, high = _bounds(cell)  # the interval lies within the two seeds' values
        assert mean == estimate and values[0] <= low <= mean <= high <= values[1]
    assert "| dyna-q | s | 1 | 20 | 0.0 | 0.0 | 50.0 | 0 |" in report  # one seed: no interval
    # rough / slippery, unpaired, on the last half: (40 + 60) / 2 over 20
    ratio = _cells(report, "| q-learning | stationary |")
    assert ratio[2:5] == ["2, 2", "50.0", "20.0"] and ratio[5].startswith("2.50 [")
    assert "| q-learning | drifting | 1, 1 | 20.0 | 40.0 | 0.50 |" in report
    pooled = _cells(report, "| q-learning | both |")  # (40 + 60 + 20) / 3 over (20 + 20 + 40) / 3
    assert pooled[2:5] == ["3, 3", "40.0", "26.7"] and pooled[5].startswith("1.50 [")
    assert "| dyna-q | stationary | 2, 1 | 80.0 | 0.0 | ∞ (slippery 0) |" in report
    assert "| dyna-q | drifting | 1, 1 | 0.0 | 0.0 | undefined (both 0) |" in report
    # a floor pair of one slip condition only: no pooled row
    without_drift = {k: v for k, v in CONDITIONS.items() if k != "e"}
    summaries = pd.DataFrame([r for r in rows if r["preset"] != "e"])
    assert "| q-learning | both |" not in markdown_report(summaries, SETTINGS, without_drift)
    # dyna-q minus q-learning on the rough floor, paired by (preset, seed): r0, r1, d0
    rough = _cells(report, "| dyna-q | rough |")
    assert rough[2] == "3"
    for cell, differences in zip(
        rough[3:6], ((40, 20, -10), (40, 20, -20), (-40, -20, 0)), strict=True
    ):
        mean, low, high = _bounds(cell)
        assert mean == pytest.approx(np.mean(differences), abs=0.05)
        assert min(differences) <= low <= mean <= high <= max(differences)
    # on the slippery floor the runs differ (s1 only for q-learning): compared unpaired
    slippery = _cells(report, "| dyna-q | slippery |")
    assert slippery[2] == "2 (unpaired)" and slippery[5] == "+0.0 [+0.0, +0.0]"
    assert slippery[3].startswith("-13.3 [") and slippery[4].startswith("-26.7 [")


def test_study_settings_and_one_line_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    config = study_config(tmp_path)
    grid, study_text = load_study(config, {"seeds": 3, "agents": "dyna-q", "episodes": None})
    assert grid.agent_labels == ["dyna-q"] and grid.presets == PRESETS and grid.seeds == 3
    assert "episodes" not in study_text and f'config = "{config}"' in study_text
    with pytest.raises(UserError, match="seeds"):
        load_study(config, {"seeds": 0})
    with pytest.raises(UserError, match="expected one or more distinct agent names"):
        load_study(config, {"agents": "dyna-q,dyna-q"})
    out = tmp_path / "out"
    argv = ["robot", "study", "--config", str(config), "--out", str(out)]
    cases = {
        "--agents=dyna-nope": "unknown agent 'dyna-nope'",
        "--presets=nope": "unknown preset 'nope'",
        "--episodes=0": "expected episodes to be an integer in [1, 10,000,000], got 0",
    }
    for option, message in cases.items():
        assert main([*argv, option]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], lines
    text = config.read_text()
    broken = {
        f"expected no [run] map, seed or reset in {config}: [presets.rough-stationary] (a "
        "study runs every preset on the [run] map": (
            text + '\n[presets.rough-stationary.run]\nmap = "free"\n'
        ),
        f"got -1 in {config}: agent 'dyna-q'": text.replace(
            "planning_steps = 5", "planning_steps = -1"
        ),
        "expected [run] seed to be an integer >= 0, got -1": text.replace(
            "[run]\n", "[run]\nseed = -1\n"
        ),
    }
    for message, broken_text in broken.items():
        config.write_text(broken_text)
        assert main(argv) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], lines
    assert not out.exists()

    config.write_text(text)
    monkeypatch.setattr("skidnav.studies.hardware.trial.realtime_run", fake_realtime([]))
    assert main([*argv, "--episodes", "2", "--agents", "q-learning"]) == 0
    assert main([*argv, "--episodes", "3", "--agents", "q-learning"]) == 2
    assert (
        capsys.readouterr()
        .err.strip()
        .endswith(
            f"skidnav: error: {out}: holds results of a different config; choose another --out"
        )
    )
    assert main(["report", str(out), "--study"]) == 2  # an experiment's study tables
    assert f"{out}: holds 'robot-study' results, not 'experiment' results" in (
        capsys.readouterr().err
    )
    earlier = tmp_path / "earlier"
    earlier.mkdir()
    (earlier / "study.csv").write_text("agent,preset\n")
    assert main([*argv[:-1], str(earlier)]) == 2
    assert "holds a study in an earlier format" in capsys.readouterr().err
