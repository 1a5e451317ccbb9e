"""A tiny BARN study end to end: ``skidnav run`` of two worlds with the goal tracker writes one
run file per world, the table of scored runs with their stored trajectories, and the report;
a partial run resumes with nothing finished run again; the learning protocol scores after
every episode and counts the seconds of driving; a discrete agent's longer actions are the
scored env's 0.1-s actions held, judged every 0.1 s."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.experiments.runs import expand_runs
from skidnav.experiments.store import ResultStore
from skidnav.studies.barn.grid import LAYOUT, BarnGrid
from skidnav.studies.barn.rules import score_trajectory
from skidnav.studies.barn.trial import barn_env, scored_run, training_actions
from skidnav.studies.loading import parse_grid
from skidnav.world.barn import barn_score, load_barn_world

SMOKE = Path(__file__).parents[3] / "configs" / "barn-smoke.toml"
LEARNING = """kind = "barn"
[barn]
protocol = "learning"
episodes = 2
worlds = [120]
discrete_action_duration = {duration}
[[agents]]
name = "q-learning"
"""


def run(config: Path, out: Path) -> None:
    arguments = ["run", str(config), "--out", str(out), "--backend", "serial", "--no-progress"]
    assert main(arguments) == 0


@pytest.fixture(scope="module")
def smoke(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The results of configs/barn-smoke.toml, with its report."""
    out = tmp_path_factory.mktemp("barn") / "smoke"
    run(SMOKE, out)
    assert main(["report", str(out)]) == 0
    return out


def test_one_row_per_scored_run_with_the_benchmarks_columns(smoke: Path) -> None:
    episodes, summaries = ResultStore(smoke, LAYOUT).load_tables()
    assert list(episodes["map"]) == ["world-0", "world-299"]
    assert list(episodes["world"]) == [0, 299] and list(episodes["quintile"]) == [0, 4]
    assert (episodes["preset"] == "nominal").all() and (episodes["agent"] == "goal-tracker").all()
    ended = episodes[["success", "collision", "timeout"]].astype(int).sum(axis=1)
    assert (ended == 1).all()  # every run ends one way
    for row in episodes.itertuples():
        world = load_barn_world(int(row.world))
        assert row.optimal_time == world.optimal_time
        assert row.metric == barn_score(bool(row.success), row.time, world.optimal_time)
        assert row.driving_seconds == 0 and row.training_actions == 0
    assert list(summaries["world"]) == [0, 299]


def test_the_stored_trajectory_is_the_run_the_rules_scored(smoke: Path) -> None:
    store = ResultStore(smoke, LAYOUT)
    episodes = store.load_tables()[0]
    for row in episodes.itertuples():
        result = store.read_run(str(row.run_id))
        poses, counts = result.arrays["poses"], result.arrays["pose_counts"]
        assert poses.dtype == np.float32 and counts.tolist() == [row.scored_actions + 1]
        world = load_barn_world(int(row.world))
        collisions = np.zeros(len(poses) - 1, bool)
        collisions[-1] = bool(row.collision)
        again = score_trajectory(
            poses[:, :2].astype(float), collisions, world.goal, world.goal_radius,
            world.optimal_time, control_period=0.1,
        )  # fmt: skip
        assert (again.success, again.collision, again.timeout) == (
            row.success, row.collision, row.timeout
        )  # fmt: skip
        assert again.actions == row.scored_actions
        assert again.time == pytest.approx(row.time, abs=1e-9)


def test_the_report_has_every_section(smoke: Path) -> None:
    text = (smoke / "report.html").read_text()
    for heading in ("BARN, zero-shot", "Scores", "By difficulty", "Paired differences", "Worlds"):
        assert heading in text
    assert "worlds 0–59" in text and "worlds 240–299" in text
    assert "data:image/png;base64," in text


def test_a_partial_run_resumes_without_running_a_finished_run_again(
    smoke: Path, tmp_path: Path
) -> None:
    out = tmp_path / "partial"
    shutil.copytree(smoke, out)
    for name in ("episodes.parquet", "summaries.parquet", "summaries.csv", "report.html"):
        (out / name).unlink()
    (out / "runs" / "run-000001.npz").unlink()  # killed before its second run was written
    kept = (out / "runs" / "run-000000.npz").read_bytes()
    run(SMOKE, out)
    assert (out / "runs" / "run-000000.npz").read_bytes() == kept
    sessions = ResultStore(out, LAYOUT).metadata()["sessions"]
    assert sessions[-1]["runs_done"] == 1
    pd.testing.assert_frame_equal(
        ResultStore(out, LAYOUT).load_tables()[1],
        ResultStore(smoke, LAYOUT).load_tables()[1],
    )


@pytest.mark.parametrize("duration", [0.1, 0.5])
def test_the_learning_protocol_scores_after_every_episode(tmp_path: Path, duration: float) -> None:
    config = tmp_path / "learning.toml"
    config.write_text(LEARNING.format(duration=duration))
    run(config, tmp_path / "out")
    episodes = ResultStore(tmp_path / "out", LAYOUT).load_tables()[0]
    assert list(episodes["episode"]) == [1, 2] and (episodes["world"] == 120).all()
    actions = episodes["training_actions"].to_numpy()
    assert (actions >= 1).all() and (actions <= training_actions(duration)).all()
    assert training_actions(duration) == round(100 / duration)
    np.testing.assert_allclose(episodes["driving_seconds"], np.cumsum(actions) * duration)


class Forward:
    """A greedy policy that drives ahead and counts its choices."""

    def __init__(self) -> None:
        self.choices = 0

    def greedy_action(self, state: object) -> int:
        self.choices += 1
        return 0


@pytest.mark.parametrize("floor", ["nominal", "ice-physics"])  # ice: the noise's draws too
def test_a_long_action_is_the_scored_envs_short_actions_held(tmp_path: Path, floor: str) -> None:
    config = tmp_path / "long.toml"
    text = LEARNING.format(duration=0.5).replace("[120]", f'[0]\nfloors = ["{floor}"]')
    config.write_text(text)
    spec = expand_runs(parse_grid(config.read_text(), config).grid)[0]
    assert spec.preset == floor
    assert isinstance(spec.config, BarnGrid) and spec.config.action_periods == 5
    world = load_barn_world(0)
    long_env, short_env = barn_env(spec, world, 7, 0.5), barn_env(spec, world, 7)
    long_env.reset(seed=3)
    short_env.reset(seed=3)
    for action in (0, 2, 0, 3, 0, 0, 0):  # ahead, turns, ahead until world 0's cylinders
        state, _, _, _, info = long_env.step(action)
        for _ in range(5):
            short_state, _, _, _, short_info = short_env.step(action)
            if short_info["collision"]:
                break
        np.testing.assert_allclose(short_info["pose"], info["pose"], atol=1e-12)
        assert short_state == state and short_info["collision"] == info["collision"]
    if floor == "ice-physics":
        return
    assert info["collision"]  # the last action ran into a cylinder, at the same sub-step
    policy = Forward()
    outcome, poses = scored_run(policy, short_env, world, seed=3, periods=5)
    assert outcome.collision and outcome.actions == len(poses) - 1
    assert policy.choices == -(-outcome.actions // 5)  # one choice every 5 periods of 0.1 s
