"""Pre-training in the simulator before the robot (``[study] sim_episodes``): both arms of a
(preset, seed) meet the same world, the pre-trained one has learned before its first robot
episode; the settings' one-line errors; the fingerprint of a study without pre-training; the
tables of robot episodes to success."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.studies.hardware import trial
from skidnav.studies.hardware.speed import speed_report
from skidnav.studies.hardware.study import (
    grid_from_dict,
    grid_to_dict,
    load_study,
    study_config_text,
)
from skidnav.studies.hardware.trial import run_summary
from tests.cli_support import exit_code
from tests.realtime.realtime_helpers import write_config
from tests.realtime.test_study import _cells

STUDY = """
[study]
agents = ["dyna-full"]
presets = ["rough"]
sim_episodes = [0, 5]
episodes = 2

[run]
max_actions = 15
time_scale = 30.0
map = "obstacles"
seed = 3
reconnect_timeout = 2.0

[sim]
lockstep = true

[agents.dyna-full]
planning_steps = 5

[presets.rough.sim]
slip = "rough"
"""


def test_the_pretrained_arm_learned_in_the_simulator_before_the_robot_on_the_same_world(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    config, out = write_config(tmp_path, STUDY), tmp_path / "study"
    seen: dict[str, Any] = {}
    drive = trial.drive

    def watched(name: str, agent: Any, grid_map: Any, run: Any, where: Path, **kw: Any) -> Any:
        label = where.relative_to(out / "runs").parts[0]
        seen[label] = (agent.q.copy(), run.run.seed, grid_map.occupancy.copy(), grid_map.goal)
        return drive(name, agent, grid_map, run, where, **kw)

    monkeypatch.setattr(trial, "drive", watched)
    argv = ["robot", "study", "--config", str(config), "--out", str(out), "--quiet"]
    assert main(argv) == 0
    scratch, pretrained = seen["dyna-full"], seen["dyna-full+sim5"]
    assert len(np.unique(scratch[0])) == 1  # a new agent's Q table: one initial value
    assert len(np.unique(pretrained[0])) > 1  # learned in the simulator before driving
    assert scratch[1] == pretrained[1]  # the same sim server seed ...
    assert np.array_equal(scratch[2], pretrained[2]) and scratch[3] == pretrained[3]  # ... map
    summaries = pd.read_csv(out / "summaries.csv").set_index("agent")
    assert summaries.loc["dyna-full+sim5", "sim_episodes"] == 5
    for column in ("sim_success_last10", "sim_greedy_success"):
        assert 0 <= summaries.loc["dyna-full+sim5", column] <= 1
    assert summaries.loc["dyna-full", "sim_episodes"] == 0
    assert math.isnan(summaries.loc["dyna-full", "sim_greedy_success"])
    assert set(summaries["episodes"]) == {2} and set(summaries["driving_seconds"]) <= {
        float(n) for n in range(2, 31)
    }  # two episodes of 1 to 15 one-second actions
    assert (out / "runs" / "dyna-full+sim5" / "rough" / "seed-0" / "run.jsonl").exists()
    report = (out / "study.md").read_text()
    assert "| dyna-full+sim5 | rough | 1 | 5 |" in report  # the pre-training table
    assert "| dyna-full+sim5 | dyna-full | rough | 1 |" in report  # against its scratch arm


def test_sim_episodes_errors_are_one_line_and_the_fingerprint_unchanged_without(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path, STUDY)
    grid, _ = load_study(config, {})
    assert [a.label for a in grid.agents] == ["dyna-full", "dyna-full+sim5"]
    assert [grid.pretraining(a.label) for a in grid.agents] == [0, 5]
    assert grid.references() == {"dyna-full+sim5": "dyna-full"}
    saved = json.loads(json.dumps(grid_to_dict(grid)))
    assert saved["sim_episodes"] == [0, 5] and saved["agents"] == ["dyna-full"]
    assert grid_from_dict(saved) == grid
    plain, _ = load_study(config, {"sim_episodes": [0]})
    assert "sim_episodes" not in grid_to_dict(plain)  # a study without keeps its fingerprint
    assert plain.fingerprint() != grid.fingerprint() and plain.references() == {}
    for bad in ([], [0, 0], [-1], [1.5], [True], "5"):
        with pytest.raises(UserError, match="expected sim_episodes to be one or more distinct"):
            load_study(config, {"sim_episodes": bad})
    config.write_text(STUDY + "\n[presets.rough.run]\nsubsteps = 5\n")
    assert main(["robot", "study", "--config", str(config), "--out", str(tmp_path / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [
        "skidnav: error: expected [run] period × substeps to be 1 s, got 0.5 s "
        f"in {config}: [presets.rough] (sim_episodes pre-trains on the simulator's actions of 1 s)"
    ], lines
    assert not (tmp_path / "out").exists()


def test_the_command_line_takes_sim_episodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path, STUDY)
    assert "sim_episodes = [0, 200]" in study_config_text(config, {"sim_episodes": [0, 200]})
    argv = ["robot", "study", "--config", str(config), "--out", str(tmp_path / "out")]
    assert exit_code([*argv, "--sim-episodes", "0,x"]) == 2
    line = capsys.readouterr().err.strip()
    assert line.endswith("argument --sim-episodes: expected comma-separated integers, got '0,x'")
    assert exit_code([*argv, "--sim-episodes", "0,0"]) == 2
    assert "expected sim_episodes to be one or more distinct" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_run_summary_counts_episodes_and_driving_to_success() -> None:
    success = np.array([0, 0, 0] + [1] * 9 + [0, 1], dtype=bool)
    episodes = {
        "return": np.zeros(14), "length": np.full(14, 20), "success": success,
        "collisions": np.zeros(14, int), "aborted": np.zeros(14, bool), "wall_time": np.ones(14),
    }  # fmt: skip
    summary = run_summary(episodes, 0, 0.5)
    # the first 10 consecutive episodes with 9 goals are episodes 3 … 12
    assert summary["episodes_to_first_success"] == 4 and summary["episodes_to_success90"] == 12
    assert summary["seconds_to_first_success"] == 40 and summary["seconds_to_success90"] == 120
    assert summary["driving_seconds"] == 140
    late = run_summary(episodes | {"success": np.roll(success, 3)}, 0, 0.5)
    assert math.isnan(late["episodes_to_success90"]) and math.isnan(late["seconds_to_success90"])


def _speed_row(agent: str, seed: int, first: float, success90: float) -> dict[str, object]:
    """A summary row of 50 episodes of 10 one-second actions (NaN: not reached)."""
    return {
        "agent": agent, "algorithm": "dyna-full", "map": "m", "preset": "rough", "seed": seed,
        "episodes": 50, "driving_seconds": 500.0, "collisions_per_episode": 1.0,
        "episodes_to_first_success": first, "seconds_to_first_success": 10 * first,
        "episodes_to_success90": success90, "seconds_to_success90": 10 * success90,
        "sim_episodes": 0.0 if agent == "dyna-full" else 200.0, "sim_success_last10": 0.9,
        "sim_episodes_to_success90": 30.0 + seed, "sim_greedy_success": 1.0,
    }  # fmt: skip


def test_speed_tables_are_kaplan_meier_medians_and_paired_restricted_means(
    tmp_path: Path,
) -> None:
    grid, _ = load_study(write_config(tmp_path, STUDY.replace("[0, 5]", "[0, 200]")), {})
    nan = math.nan
    rows = [_speed_row("dyna-full", s, f, t) for s, (f, t) in enumerate(
        [(5, 30), (8, 40), (20, nan), (30, nan)])]  # fmt: skip
    rows += [_speed_row("dyna-full+sim200", s, 1, t) for s, t in enumerate([10, 12, 15, 20])]
    report = speed_report(pd.DataFrame(rows), grid)
    scratch = _cells(report, "| dyna-full | rough |")
    # KM median to >= 90 %: 30, 40, then two censored at 50 -> S = 0.75, 0.5 -> 40
    assert scratch[2:5] == ["4", "4/4", "2/4"] and scratch[7].startswith("40 [")
    assert scratch[8].startswith("400 [")  # seconds of driving: 10 per episode
    pretrained = _cells(report, "| dyna-full+sim200 | rough |")
    assert pretrained[2:5] == ["4", "4/4", "4/4"] and pretrained[5] == "1 [1, 1]"
    assert pretrained[7].startswith("12 [")
    compared = _cells(report, "| dyna-full+sim200 | dyna-full | rough |")
    assert compared[3] == "4" and compared[7].startswith("3.3× [")  # 40 / 12
    # restricted means: (10 + 12 + 15 + 20) / 4 - (30 + 40 + 50 + 50) / 4 = -28.25
    low, high = (float(v) for v in compared[8].split("[")[1].rstrip("]").split(","))
    assert compared[8].startswith("-28 [") and low <= -28.25 <= high
    assert "| dyna-full+sim200 | rough | 4 | 200 | 90.0 | 4/4 | 32 | 100.0 | 4/4 |" in report
    assert speed_report(pd.DataFrame(rows).drop(columns="episodes_to_success90"), grid) == ""
