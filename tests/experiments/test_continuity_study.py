"""The continuity study as a config of the one runner (``kind = "continuity"``): the numbers of
the comparison run in one go on every backend, run files that survive a SIGKILL, the shortcut's
config and resume, the report by kind, one-line config errors."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.experiments.runs import expand_runs
from skidnav.experiments.store import ResultStore
from skidnav.seeding import seed_int
from skidnav.studies.continuity.comparison import run_comparison, run_seed
from skidnav.studies.continuity.results import read_results
from skidnav.studies.continuity.runfile import CONTINUITY_LAYOUT
from skidnav.studies.continuity.traces import comparison_table
from skidnav.studies.continuity.worlds import markdown as markdown_of_worlds
from skidnav.studies.continuity.worlds import pooled, world_rows
from tests.experiments.exp_support import cli_command, cli_env

TINY = Path(__file__).with_name("continuity-tiny.toml")
"""q-learning, dyna-full, cmaes, mppi-kinematic and the goal tracker × 2 seeds on the free map:
10 runs."""


def rollouts(out: Path) -> pd.DataFrame:
    """Every rollout's row of a continuity results directory (no wall times), in run order."""
    episodes, _ = ResultStore(out, CONTINUITY_LAYOUT).load_tables()
    return episodes.sort_values(["run_id", "episode"]).reset_index(drop=True)


@pytest.fixture(scope="module")
def serial_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("continuity") / "serial"
    assert main(["run", str(TINY), "--out", str(out), "--backend", "serial", "--no-progress"]) == 0
    return out


def test_every_backend_gives_the_numbers_of_the_comparison_in_one_go(
    serial_run: Path, tmp_path: Path
) -> None:
    out = tmp_path / "process"
    argv = ["run", str(TINY), "--out", str(out), "--backend", "process", "--jobs", "2"]
    assert main([*argv, "--no-progress"]) == 0
    pd.testing.assert_frame_equal(rollouts(out), rollouts(serial_run))
    serial = read_results(serial_run)
    pd.testing.assert_frame_equal(read_results(out).table, serial.table)
    # the comparison in one go: the same rollouts, so the same table
    runs = run_comparison(serial.config)
    traces = {
        name: [trace for run in runs if run.learner == name for trace in run.traces]
        for name in serial.config.learners
    }
    table = comparison_table(traces, np.random.default_rng(serial.config.root_seed))
    pd.testing.assert_frame_equal(table, serial.table)
    # run k of every learner trains from the runner's world stream k (metadata.json's seeds)
    for spec in expand_runs(serial.config):
        assert seed_int(spec.world_seed.sequence()) % 2**31 == run_seed(serial.config, spec.seed)
    # the goal tracker learns nothing: its two runs are alike, the tables count one
    assert list(serial.runs["learner"]).count("goal-tracker") == 1
    tracker = serial.table[serial.table["policy"] == "goal-tracker"]
    assert set(tracker[tracker["metric"] == "success"]["n"]) == {serial.config.rollouts}


def test_the_shortcut_saves_the_config_it_runs_and_resumes_it(
    serial_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "cmp"
    argv = [
        "study", "continuity", "--map", "free", "--max-steps", "40", "--seeds", "2",
        "--learners", "q-learning,dyna-full,cmaes,mppi-kinematic,goal-tracker", "--episodes", "8",
        "--generations", "3", "--population", "6", "--rollouts", "2", "--backend", "serial",
        "--no-progress", "--out", str(out),
    ]  # fmt: skip
    assert main(argv) == 0
    assert "10 runs in" in capsys.readouterr().out
    assert 'kind = "continuity"' in (out / "config.toml").read_text()
    # the tiny config's study under another name: the same runs, numbers and table
    pd.testing.assert_frame_equal(rollouts(out), rollouts(serial_run))
    expected = read_results(serial_run).table.to_csv(index=False)
    assert (out / "table.csv").read_text() == expected
    assert list(pd.read_csv(out / "runs.csv")["learner"]).count("cmaes") == 2
    assert (out / "table.md").read_text().count("\n| ") == 6
    assert (out / "trajectories.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # again, or through skidnav run on its saved config: nothing to run
    assert main(argv) == 0
    assert "(0 run now, 10 already done)" in capsys.readouterr().out
    saved = ["run", str(out / "config.toml"), "--out", str(out), "--no-progress"]
    assert main(saved) == 0
    assert "(0 run now, 10 already done)" in capsys.readouterr().out


def test_the_report_is_the_study_s_in_the_report_page(serial_run: Path, tmp_path: Path) -> None:
    output = tmp_path / "report.html"
    assert main(["report", str(serial_run), "-o", str(output)]) == 0
    page = output.read_text()
    assert page.startswith("<!DOCTYPE html>") and "<title>skidnav: continuity-tiny</title>" in page
    assert "<h1>skidnav continuity: continuity-tiny</h1><h2>What continuity buys</h2>" in page
    assert "<td>goal-tracker</td><td>1</td><td>0</td><td>– (0)</td><td>100.00" in page
    assert page.count("data:image/png;base64,") == 1  # the trajectories
    assert "<h2>Config (resolved)</h2>" in page and "<h2>Provenance</h2>" in page


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            'learners = ["q-learning",',
            'learners = ["dqn",',
            "expected learners from q-learning, dyna-full, cmaes, ppo, sac, mppi-kinematic, "
            "goal-tracker, got ['dqn'] in {config}: [continuity]",
        ),
        ("seeds = 2", "seeds = 2\nepisods = 3", "bad.toml: [continuity] (did"),
        ("seeds = 2", "seeds = 0", "expected seeds to be an integer in [1, 1000], got 0"),
        ('kind = "continuity"', 'kind = "continuty"', "expected kind to be one of"),
        ("[continuity]", "[extra]\n[continuity]", "bad.toml: top level (expected"),
    ],
)
def test_a_bad_study_config_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], old: str, new: str, message: str
) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(TINY.read_text().replace(old, new, 1))
    assert main(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skidnav: error: ") and str(config) in lines[0]
    assert message.replace("{config}", str(config)) in lines[0], lines
    assert not (tmp_path / "out").exists()


KILLED = {
    'learners = ["q-learning", "dyna-full", "cmaes", "mppi-kinematic", "goal-tracker"]': (
        'learners = ["q-learning", "cmaes"]'
    ),
    "seeds = 2": "seeds = 3",
    "generations = 3": "generations = 60",
    "population = 6": "population = 12",
}
"""The tiny study with three CMA-ES runs of about a second after three quick Q-learning runs."""


def _run_files(out: Path) -> dict[str, tuple[bytes, int]]:
    return {path.name: (path.read_bytes(), path.stat().st_mtime_ns) for path in _paths(out)}


def _paths(out: Path) -> list[Path]:
    runs = out / "runs"
    return sorted(runs.glob("run-*.npz")) if runs.is_dir() else []


def test_a_sigkilled_study_resumes_without_running_a_finished_run_again(tmp_path: Path) -> None:
    text = TINY.read_text()
    for old, new in KILLED.items():
        text = text.replace(old, new, 1)
    config, out, reference = tmp_path / "kill.toml", tmp_path / "out", tmp_path / "reference"
    config.write_text(text)
    argv = cli_command(
        "run", str(config), "--out", str(out), "--backend", "serial", "--no-progress"
    )
    study = subprocess.Popen(
        argv, env=cli_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    deadline = time.monotonic() + 120
    while not _paths(out) and study.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    os.kill(study.pid, signal.SIGKILL)
    assert study.wait(timeout=30) == -signal.SIGKILL  # not finished before the kill
    killed = _run_files(out)
    print(f"killed after {len(killed)} of 6 runs")  # shown with pytest -s
    assert 1 <= len(killed) < 6, "the study should have been killed mid-way"
    assert not (out / "episodes.parquet").exists()

    resumed = subprocess.run(argv, env=cli_env(), capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert f"({6 - len(killed)} run now, {len(killed)} already done)" in resumed.stdout
    after = _run_files(out)
    assert len(after) == 6 and all(after[name] == killed[name] for name in killed)
    assert not list(out.rglob("*.tmp"))
    _, summaries = ResultStore(out, CONTINUITY_LAYOUT).load_tables()
    assert sorted(summaries["run_id"]) == [f"run-{index:06d}" for index in range(6)]
    sessions = json.loads((out / "metadata.json").read_text())["sessions"]
    assert [(s["runs_done"], s["completed"]) for s in sessions] == [
        (len(killed), False),
        (6 - len(killed), True),
    ]
    # the numbers of the same study run without a kill
    assert main(["run", str(config), "--out", str(reference), "--backend", "serial"]) == 0
    pd.testing.assert_frame_equal(rollouts(out), rollouts(reference))
    pd.testing.assert_frame_equal(read_results(out).table, read_results(reference).table)


def test_studies_of_several_worlds_pool_learner_by_learner(serial_run: Path) -> None:
    rows = world_rows([serial_run, serial_run])  # the same world twice: two alike worlds
    serial = read_results(serial_run)
    assert len(rows) == 2 * len(serial.config.learners)
    successes = serial.table[serial.table["metric"] == "success"].set_index("policy")["mean"]
    for row in rows.to_dict("records"):
        assert row["success"] == pytest.approx(successes[row["learner"]])
        runs = serial.runs[serial.runs["learner"] == row["learner"]]
        assert row["learned"] == runs["episodes_to_learn"].notna().sum()
    table = pooled(rows, np.random.default_rng(0)).set_index("learner")
    assert (table["worlds"] == 2).all() and table.loc["goal-tracker", "runs"] == 2
    tracker = table.loc["goal-tracker"]
    assert tracker["success"] == 1.0 and tracker["worlds_good"] == 2
    assert table.loc["cmaes", "episodes_used"] == 36
    text = markdown_of_worlds(rows, pooled(rows, np.random.default_rng(0)))
    assert text.count("\n| ") == len(rows) + 1 + len(table)  # the rows, the second header
