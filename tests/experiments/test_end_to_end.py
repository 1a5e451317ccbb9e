"""The tiny config end to end: records, summaries, metadata, figures, report."""

from __future__ import annotations

import base64
import html
import io
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from skidnav.errors import UserError
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import EPISODE_COLUMNS, GRID_COLUMNS, ResultStore
from tests.experiments.exp_support import cli_command, cli_env

SUMMARY_COLUMNS = (
    "convergence_episode",
    "converged",
    "optimality_gap",
    "oracle_length",
    "final_length_actions",
    "final_length_m",
    "success_rate",
    "success_rate_last10",
    "mean_return",
    "collisions_per_episode",
    "planning_updates",
    "wall_time",
)


def test_records_and_summaries(serial_results: Path) -> None:
    episodes, summaries = ResultStore(serial_results).load_tables()
    assert list(episodes.columns) == [*GRID_COLUMNS, "episode", *EPISODE_COLUMNS]
    assert len(episodes) == 8 * 6 and len(summaries) == 8
    assert not episodes.duplicated(["run_id", "episode"]).any()
    assert set(SUMMARY_COLUMNS) <= set(summaries.columns)
    assert set(summaries["agent"]) == {"q-learning", "dyna-q-5"}
    assert episodes["length"].between(1, 60).all()
    assert (episodes["success"] == (episodes["length"] < 60) | episodes["success"]).all()
    assert summaries["success_rate"].between(0, 1).all()
    assert summaries["convergence_episode"].between(1, 6).all()
    # Q-learning never plans; Dyna-Q plans 5 updates per real step once it has a model.
    q_rows = episodes[episodes["agent"] == "q-learning"]
    dyna_rows = episodes[episodes["agent"] == "dyna-q-5"]
    assert (q_rows["planning_updates"] == 0).all()
    assert (dyna_rows["planning_updates"] <= 5 * dyna_rows["length"]).all()
    assert dyna_rows["planning_updates"].sum() > 0
    reached = episodes["greedy_success"] > 0  # share of the evaluation's rollouts
    assert episodes["greedy_success"].between(0, 1).all()
    assert episodes.loc[reached, "greedy_length"].between(1, 60).all()
    assert episodes.loc[~reached, "greedy_length"].isna().all()
    assert (summaries["oracle_length"] > 1).all()
    assert episodes.loc[~reached, "greedy_cost"].isna().all()
    assert (summaries["oracle_cost"] > summaries["oracle_length"]).all()  # rough and slippery
    assert "oracle_rollout_cost" in summaries


def test_metadata_and_saved_config(serial_results: Path) -> None:
    metadata = json.loads((serial_results / "metadata.json").read_text())
    assert metadata["config"]["name"] == "tiny"
    assert metadata["versions"]["numpy"] == np.__version__
    assert len(metadata["seeds"]["runs"]) == 8
    assert "git_commit" in metadata and "git_dirty" in metadata
    assert metadata["sessions"][0]["runs_done"] == 8
    store = ResultStore(serial_results)
    assert store.config() == parse_config(_tiny_text())


def _tiny_text() -> str:
    from tests.experiments.exp_support import TINY_TOML

    return TINY_TOML


def test_resume_refuses_other_config(serial_results: Path) -> None:
    other = parse_config(_tiny_text().replace("root_seed = 11", "root_seed = 12"))
    with pytest.raises(UserError, match="different config"):
        run_experiment(other, serial_results, backend="serial")


def test_rerun_skips_finished_runs(serial_results: Path) -> None:
    before = {p.name: p.stat().st_mtime_ns for p in (serial_results / "runs").iterdir()}
    outcome = run_experiment(parse_config(_tiny_text()), serial_results, backend="serial")
    assert outcome.executed == 0 and outcome.skipped == 8
    after = {p.name: p.stat().st_mtime_ns for p in (serial_results / "runs").iterdir()}
    assert before == after


def test_report_cli_writes_one_self_contained_file(serial_results: Path, tmp_path: Path) -> None:
    output = tmp_path / "cli-report.html"
    result = subprocess.run(
        cli_command("report", str(serial_results), "-o", str(output)),
        capture_output=True,
        text=True,
        env=cli_env(),
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert "report: " in result.stderr and "step" in result.stderr  # its progress bar
    text = output.read_text()
    images = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', text)
    # Per map x preset cell (2 here): performance profiles, greedy lengths, learning curves,
    # metric strips, trajectories, value maps, policy maps; plus the rough / slippery ratio.
    assert len(images) == 2 * 7 + 1
    assert all(base64.b64decode(image)[:8] == b"\x89PNG\r\n\x1a\n" for image in images)
    assert 'src="http' not in text and "<script" not in text
    for needle in (
        "Thesis reproduction",
        "16×",
        "Convergence episode",
        "10%",
        "dyna-q-5",
        "&quot;root_seed&quot;: 11",
        'alt="policy maps"',
        "session started (UTC)",
    ):
        assert needle in text, needle
    # The page leads with the verdict the command printed; 2 seeds: a caveat, no interval.
    body = text.split("<body>", 1)[1]
    assert body.startswith("<h1>") and body.split("</h1>", 1)[1].startswith('<p id="verdict">')
    printed = result.stdout.splitlines()
    assert printed[0].startswith("Verdict: ") and printed[1] == f"report: {output}"
    assert "interval [" not in printed[0] and "Only 2 seeds per cell" in body
    verdict = re.search(r'<p id="verdict"><b>Verdict:</b> ([^<]*)</p>', text)
    assert verdict is not None and html.unescape(verdict.group(1)) == printed[0][9:]
    assert body.index("<details>") > body.index("<h2>Convergence</h2>")
    assert not re.search(r"\bnan\b", re.sub(r'src="data:[^"]*"', "", text))
    missing = subprocess.run(
        cli_command("report", str(tmp_path / "nothing")),
        capture_output=True,
        text=True,
        env=cli_env(),
        timeout=120,
    )
    assert missing.returncode == 2 and "nothing" in missing.stderr


def test_report_animates_one_greedy_trajectory_per_cell(serial_results: Path) -> None:
    from PIL import Image

    from skidnav.experiments.report.html import build_report
    from skidnav.physics.backend import offscreen_rendering

    text = build_report(serial_results)
    gifs = re.findall(r'src="data:image/gif;base64,([A-Za-z0-9+/=]+)"', text)
    assert len(gifs) == 2  # one per map x preset cell
    for encoded in gifs:
        movie = Image.open(io.BytesIO(base64.b64decode(encoded)))
        assert movie.format == "GIF" and movie.n_frames > 1
        assert movie.info.get("loop") == 0
    renderer = "MuJoCo offscreen renderer" if offscreen_rendering() == "" else "2-D renderer"
    captions = re.findall(r"<figcaption[^>]*>Final greedy trajectory of ([^<]*)</figcaption>", text)
    assert len(captions) == 2 and all(renderer in caption for caption in captions)
