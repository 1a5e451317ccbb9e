"""``skidnav study continuity``: discrete agents and wheel-speed learners on one world, same
seeds (the study through the runner: tests/experiments/test_continuity_study.py)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.studies.continuity.comparison import (
    ComparisonConfig,
    evaluation_seeds,
    first_learned,
    mppi_params,
    run_comparison,
)

TINY = ComparisonConfig(map_kind="free", world_seed=3, max_steps=40, episodes=8, generations=3,
                        population=6, rollouts=2, seeds=2)  # fmt: skip


def test_every_learner_meets_the_same_evaluation_seeds_and_budgets() -> None:
    config = dataclasses.replace(TINY, learners=("q-learning", "cmaes", "goal-tracker"))
    runs = run_comparison(config)
    assert [run.learner for run in runs] == ["q-learning"] * 2 + ["cmaes"] * 2 + ["goal-tracker"]
    assert runs[0].seed != runs[1].seed and runs[0].seed == runs[2].seed  # paired by index
    assert [run.episodes_used for run in runs] == [8, 8, 36, 36, 0]
    tracker = runs[-1]
    assert all(trace.terminated for trace in tracker.traces)  # the free map: it gets there
    start = runs[0].traces[0].poses[0]
    assert all(np.array_equal(t.poses[0], start) for run in runs for t in run.traces)
    assert len(evaluation_seeds(config)) == 2
    again = run_comparison(config)
    assert [t.poses.tobytes() for r in runs for t in r.traces] == [
        t.poses.tobytes() for r in again for t in r.traces
    ]


def test_mppi_kinematic_plans_as_far_ahead_at_every_control_period_and_learns_in_a_few() -> None:
    assert mppi_params(TINY) == {"horizon": 4}  # 4 s at 1 s per action
    assert mppi_params(dataclasses.replace(TINY, control_period=0.1)) == {"horizon": 40}
    config = dataclasses.replace(TINY, learners=("mppi-kinematic",), seeds=1)
    run, again = (run_comparison(config)[0] for _ in range(2))
    assert run.episodes_used == 8 and 1 <= run.episodes_to_learn <= 8
    assert all(trace.terminated for trace in run.traces)  # 0.25 m away: its planner gets there
    # each rollout from the same seeded planner, its plan forgotten: the same on every run
    assert [t.commands.tobytes() for t in run.traces] == [
        t.commands.tobytes() for t in again.traces
    ]


def test_episodes_to_learn_is_the_first_check_with_every_rollout_at_the_goal() -> None:
    lengths = np.array([[-1, -1], [5, -1], [7, 6], [-1, 6]])
    assert first_learned(lengths) == 3.0
    assert math.isnan(first_learned(np.full((4, 2), -1)))


def test_the_command_writes_the_table_and_the_picture(tmp_path: Path) -> None:
    out = tmp_path / "cmp"
    code = main([
        "study", "continuity", "--map", "free", "--world-seed", "3", "--max-steps", "30",
        "--episodes", "4", "--generations", "2", "--population", "4", "--rollouts", "2",
        "--seeds", "1", "--learners", "dyna-full,ppo,sac,goal-tracker", "--out", str(out),
        "--backend", "serial", "--no-progress",
    ])  # fmt: skip
    assert code == 0
    assert 'learners = ["dyna-full", "ppo", "sac", "goal-tracker"]' in (
        (out / "config.toml").read_text()
    )
    runs = pd.read_csv(out / "runs.csv")
    assert list(runs["learner"]) == ["dyna-full", "ppo", "sac", "goal-tracker"]
    table = pd.read_csv(out / "table.csv")
    assert set(table["policy"]) == set(runs["learner"])
    tracker = table[(table["policy"] == "goal-tracker") & (table["metric"] == "success")]
    assert float(tracker["mean"].iloc[0]) == 1.0
    text = (out / "table.md").read_text()
    assert text.count("\n| ") == 5  # the header and one row per learner
    assert (out / "trajectories.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--learners", "dqn"], "expected learners from"),
        (["--seeds", "0"], "expected seeds to be an integer in [1, 1000]"),
        (["--control-period", "0.15"], "the env refuses these settings"),
        (["--control-period", "nan"], "the env refuses these settings"),
        (["--world-seed", "-1"], "expected world_seed to be an integer >= 0"),
        (["--root-seed", "-1"], "expected root_seed to be an integer >= 0"),
        (["--max-steps", "200000"], "expected max_steps to be an integer in [1, 100000]"),
        (["--learners", "cmaes", "--population", "1"], "population"),
    ],
)
def test_bad_arguments_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    assert main(["study", "continuity", "--out", str(tmp_path / "x"), *argv]) == 2
    error = capsys.readouterr().err.strip()
    assert message in error and "\n" not in error


def test_an_out_that_is_a_file_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "file").write_text("")
    assert (
        main(["study", "continuity", "--out", str(tmp_path / "file"), "--learners", "q-learning"])
        == 2
    )
    assert "not a directory" in capsys.readouterr().err


def test_a_discrete_agent_does_not_draw_the_env_s_numbers(monkeypatch: pytest.MonkeyPatch) -> None:
    """The agent's stream is not the one the env's episodes are reset from (both on
    ``default_rng(seed)``, exploration repeated the slip noise's numbers)."""
    from skidnav.agents.tabular import family

    states: list[dict[str, object]] = []  # each agent's generator as the family made it
    make_agent = family.make_agent

    def recording(*args: object, **kwargs: object) -> object:
        states.append(args[4].bit_generator.state)  # type: ignore[attr-defined]
        return make_agent(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(family, "make_agent", recording)
    config = dataclasses.replace(TINY, learners=("q-learning",), seeds=1, episodes=1)
    (run,) = run_comparison(config)
    env_stream = np.random.default_rng(run.seed).bit_generator.state
    assert states and states[0] != env_stream
