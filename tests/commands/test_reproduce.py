"""The Sutton & Barto (2018) ch. 8 checks as a study (``kind = "sutton-barto-checks"``): the
book's criteria met by a small config run by ``skidnav run``, the same numbers on the serial and
the process backend, bad configs and flags as one line, and the shortcut ``skidnav study
reproduce sutton-barto``: the shipped config's defaults, the same tables as the config, its CSV
and PNG files, resumable."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from skidnav.cli import build_parser, main
from skidnav.commands.reproduce import checks_from_flags
from skidnav.experiments.store import ResultStore
from skidnav.studies.loading import load_grid
from skidnav.studies.sutton_barto.grid import LAYOUT, TextbookChecks
from skidnav.studies.sutton_barto.report import summary_text
from skidnav.studies.sutton_barto.results import (
    NEAR_OPTIMAL,
    changing_curves,
    dyna_maze_steps,
    first_episode_below,
    median_updates,
    read_results,
    sweeping_updates,
)
from skidnav.studies.sutton_barto.trial import cumulative_reward, episodes_of
from tests.cli_support import exit_code

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
SMALL = 'kind = "sutton-barto-checks"\nruns = 10\n'
"""Every check, 10 runs, root seed 0. Of the root seeds 0–29 with 10 runs each, every one met
the Dyna-Q+ and prioritized-sweeping criteria below (Dyna-Q+ ahead after the change by ≥ 18
rewards in the blocking maze, ≥ 30 in the shortcut maze; prioritized sweeping ≥ 21× fewer
updates); n = 50's last-10 mean ranged 16.0–18.0 actions and its first mean ≤ 18 came at
episode 3–7 (root seed 0: 16.8 and 3). One run is not enough: Dyna-Q finds the new path of the
blocking maze in about half of the runs."""
TINY = 'kind = "sutton-barto-checks"\nruns = 2\nplanning_steps = [5]\nscales = [1]\n'
"""Every example, 2 runs: 7 checks × 2 runs."""
SHORTCUT = ["study", "reproduce", "sutton-barto", "--runs", "2", "--no-progress"]


def run_config(text: str, folder: Path, *options: str) -> Path:
    """``skidnav run`` of the config ``text`` into ``folder/out``; the results directory."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "checks.toml").write_text(text)
    out = folder / "out"
    arguments = ["run", str(folder / "checks.toml"), "--out", str(out), "--no-progress"]
    assert main([*arguments, *options]) == 0
    return out


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The results of :data:`SMALL` run by ``skidnav run --backend serial``."""
    return run_config(SMALL, tmp_path_factory.mktemp("small"), "--backend", "serial")


def test_dyna_q_plans_its_way_to_a_near_optimal_path_in_fewer_episodes(small: Path) -> None:
    steps = dyna_maze_steps(read_results(small))
    assert sorted(steps) == [0, 5, 50] and all(s.shape == (10, 50) for s in steps.values())
    first = {n: first_episode_below(s.mean(axis=0)) for n, s in steps.items()}
    assert 0 < first[50] <= 5 and first[50] <= first[5] < first[0]  # book: ≈ 3, 5, 25
    assert first[0] >= 20
    assert steps[50][:, -10:].mean() <= NEAR_OPTIMAL == 18
    assert steps[50][:, 0].mean() > 5 * NEAR_OPTIMAL  # the first episode has no model to plan with


@pytest.mark.parametrize(("example", "change"), [("blocking-maze", 1000), ("shortcut-maze", 3000)])
def test_dyna_q_plus_gathers_more_reward_after_the_maze_changes(
    small: Path, example: str, change: int
) -> None:
    curves = changing_curves(read_results(small), example)
    assert sorted(curves) == ["dyna-q", "dyna-q-plus"]
    gained = {name: (c[:, -1] - c[:, change - 1]).mean() for name, c in curves.items()}
    before = {name: c[:, change - 1].mean() for name, c in curves.items()}
    assert gained["dyna-q-plus"] > gained["dyna-q"] + 10
    assert min(before.values()) > 10  # both had learned the first path


def test_prioritized_sweeping_needs_several_times_fewer_updates(small: Path) -> None:
    updates = sweeping_updates(read_results(small))
    medians = {(check.agent, check.scale): median_updates(runs) for check, runs in updates.items()}
    assert len(medians) == 6 and all(len(runs) == 10 for runs in updates.values())
    for scale in (1, 2, 3):
        assert 5 * medians[("prioritized-sweeping", scale)] < medians[("dyna-q", scale)]


def test_episodes_give_back_the_cumulative_reward_of_every_step() -> None:
    cumulative = np.array([0.0, 0, 1, 1, 1, 2, 2, 3, 3, 3])  # goals at steps 3, 6 and 8
    steps, reward = episodes_of(cumulative)
    assert steps.tolist() == [3, 3, 2, 2] and reward.tolist() == [1, 1, 1, 0]
    np.testing.assert_array_equal(cumulative_reward(steps, reward), cumulative)
    steps, reward = episodes_of(cumulative[:8])  # the last goal at the last step
    assert steps.tolist() == [3, 3, 2] and reward.tolist() == [1, 1, 1]


def _tables(out: Path) -> list[pd.DataFrame]:
    episodes, summaries = ResultStore(out, LAYOUT).load_tables()
    return [
        frame.sort_values(keys).reset_index(drop=True)
        for frame, keys in ((episodes, ["run_id", "episode"]), (summaries, ["run_id"]))
    ]


def test_one_run_file_per_run_the_same_on_both_backends(tmp_path: Path) -> None:
    serial = run_config(TINY, tmp_path / "serial", "--backend", "serial")
    assert sorted(path.name for path in (serial / "runs").iterdir()) == [
        f"run-{index:06d}.npz" for index in range(14)
    ]
    summaries = _tables(serial)[1]
    assert summaries["agent"].tolist()[::2] == [
        "dyna-maze dyna-q n=5", "blocking-maze dyna-q", "blocking-maze dyna-q-plus",
        "shortcut-maze dyna-q", "shortcut-maze dyna-q-plus", "prioritized-sweeping dyna-q x1",
        "prioritized-sweeping prioritized-sweeping x1",
    ]  # fmt: skip
    assert summaries["seed"].tolist() == [0, 1] * 7
    process = run_config(TINY, tmp_path / "process", "--backend", "process", "--jobs", "2")
    for in_serial, in_process in zip(_tables(serial), _tables(process), strict=True):
        pd.testing.assert_frame_equal(in_serial, in_process)


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (
            "runz = 2",
            "unknown key 'runz' in {config} (did you mean 'runs'? expected one of kind, name, "
            "examples, runs, root_seed",
        ),
        ("runs = 0", "expected runs to be an integer in [1, 1000], got 0 in {config}\n"),
        ('examples = ["dyna-maze", "cliff"]', "expected examples to be distinct names among"),
        (
            "planning_steps = [5, 5]",
            "expected planning_steps to be distinct integers, got [5, 5] in {config}\n",
        ),
        ("scales = [0]", "expected scales to be an integer in [1, 10], got 0 in {config}\n"),
        ("root_seed = -1", "expected root_seed to be an integer in [0, "),
    ],
)
def test_a_bad_config_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], line: str, message: str
) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(f'kind = "sutton-barto-checks"\n{line}\n')
    assert exit_code(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and error.startswith("skidnav: error: "), error
    assert error.removeprefix("skidnav: error: ").startswith(message.format(config=config)), error
    assert error.rstrip().endswith(str(config)) or f" in {config} (" in error, error
    assert not (tmp_path / "out").exists()


def test_the_shortcut_runs_the_shipped_config_by_default() -> None:
    arguments = build_parser().parse_args(["study", "reproduce", "sutton-barto"])
    assert checks_from_flags(arguments) == load_grid(CONFIGS / "sutton-barto-checks.toml").grid
    assert checks_from_flags(arguments) == TextbookChecks()


def _header(path: Path) -> list[str]:
    with path.open(newline="") as handle:
        return next(csv.reader(handle))


def test_the_shortcut_is_the_config_writes_its_files_and_resumes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shipped = (CONFIGS / "sutton-barto-checks.toml").read_text().replace("runs = 30", "runs = 2")
    by_config = run_config(shipped, tmp_path / "config", "--backend", "serial")
    capsys.readouterr()
    out = tmp_path / "shortcut"
    assert main([*SHORTCUT, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    table = summary_text(read_results(by_config))
    assert table in printed and "wrote CSV and PNG files" in printed
    assert "first episode with mean ≤ 18" in table and "prioritized sweeping [updates]" in table
    assert ResultStore(out, LAYOUT).config() == ResultStore(by_config, LAYOUT).config()
    for in_shortcut, in_config in zip(_tables(out), _tables(by_config), strict=True):
        pd.testing.assert_frame_equal(in_shortcut, in_config)
    columns = {
        "dyna_maze": ["planning_steps", "run", "episode", "steps"],
        "blocking_maze": ["agent", "step", "mean_cumulative_reward"],
        "shortcut_maze": ["agent", "step", "mean_cumulative_reward"],
        "prioritized_sweeping": ["agent", "n_states", "run", "updates"],
    }
    for name, header in columns.items():
        assert _header(out / f"{name}.csv") == header, name
        assert (out / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    rows = pd.read_csv(out / "dyna_maze.csv")
    assert len(rows) == 3 * 2 * 50 and sorted(set(rows["planning_steps"])) == [0, 5, 50]
    assert len(pd.read_csv(out / "shortcut_maze.csv")) == 2 * 6000
    assert main([*SHORTCUT, "--out", str(out)]) == 0  # resumed: nothing left to run
    again = capsys.readouterr().out
    assert "(0 run now, 26 already done)" in again and table in again


def test_the_report_has_every_examples_table_and_plot(small: Path) -> None:
    assert main(["report", str(small)]) == 0
    page = (small / "report.html").read_text()
    for title in ("Dyna Maze (Example 8.1)", "Blocking maze", "Shortcut maze", "Example 8.4"):
        assert title in page
    assert page.count("<img") == 4 and "130 of 130 runs finished" in page


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--runs", "0"], "expected --runs to be an integer in [1, 1000], got 0"),
        (["--root-seed", "-3"], "expected --root-seed to be an integer in [0, "),
    ],
)
def test_bad_flags_give_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], message: str
) -> None:
    out = tmp_path / "out"
    assert exit_code(["study", "reproduce", "sutton-barto", *flags, "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines
    assert not out.exists()
