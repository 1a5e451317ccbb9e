"""The generalisation study: seeded splits of maps, training on a map set, evaluation on both
sides; the study as a config run by ``skidnav run``, and ``skidnav study generalise``."""

from __future__ import annotations

import csv
import math
import subprocess
import sys
from dataclasses import astuple
from pathlib import Path

import numpy as np
import pytest

from skidnav.cli import main
from skidnav.studies.agent_grid import study_results
from skidnav.studies.generalisation import evaluation as generalisation
from skidnav.studies.generalisation.evaluation import (
    GoalSeeker,
    evaluate_on,
    generalisation_run,
    references,
    split_worlds,
)
from skidnav.studies.generalisation.report import results_of, summary_text
from skidnav.studies.generalisation.study import STUDY
from tests.experiments.study_support import (
    check_bad_key_is_one_line,
    check_serial_and_process_agree,
    run_config,
    shipped_config_grid_and_defaults,
)

TINY = {"dimensions": [4, 5, 6], "tiles": [3]}
TINY_CONFIG = """
kind = "generalisation"

[generalisation]
seeds = 2
training_maps = 2
held_out_maps = 1
episodes = 8
max_steps = 40
map_kind = "free"
rollouts = 2
eval_epsilon = 0.2
root_seed = 3

[[agents]]
name = "linear-q"
params = { dimensions = [4, 5], tiles = [3] }
"""
"""1 agent × 2 seeds = 2 runs of 8 short episodes on 2 free maps."""
SHORTCUT = ["study", "generalise", "--agent", "linear-q", "--seeds", "2", "--training-maps", "2",
            "--held-out-maps", "1", "--episodes", "8", "--max-steps", "40", "--map-kind", "free",
            "--rollouts", "2", "--eval-epsilon", "0.2", "--root-seed", "3",
            "--params", 'linear-q={"dimensions": [4, 5], "tiles": [3]}']  # fmt: skip
"""The flags of :data:`TINY_CONFIG` (named ``generalisation``, as the shortcut names it)."""


def test_split_is_seeded_disjoint_and_sized() -> None:
    split = split_worlds(3, 4, 2, 3)
    assert split == split_worlds(3, 4, 2, 3)
    assert len(split.training) == 4 and len(split.held_out) == 2 and len(split.evaluation) == 3
    assert not set(split.training) & set(split.held_out)
    assert split_worlds(4, 4, 2, 3).training != split.training


def test_a_held_out_map_equal_to_a_training_map_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(generalisation, "seed_int", lambda _: 7)  # every world the same
    with pytest.raises(ValueError, match="has the map of a training world"):
        split_worlds(0, 2, 1, 1)


class Spinner:
    def greedy_action(self, observation: np.ndarray) -> int:
        return 2


def test_evaluation_tells_a_goal_seeker_from_a_spinner() -> None:
    split = split_worlds(0, 3, 3, 2, {"map_kind": "free"})
    options = {"map_kind": "free", "slip": "thesis", "observation": "features"}
    seeker = evaluate_on(GoalSeeker(), split.held_out, split.evaluation, 300, **options)
    spinner = evaluate_on(Spinner(), split.held_out, split.evaluation, 300, **options)
    assert seeker[0] >= 0.8 and 0 < seeker[1] < 300
    assert spinner[0] == 0.0 and math.isnan(spinner[1])


def test_same_seed_same_run_and_shares_are_shares() -> None:
    split = split_worlds(1, 2, 1, 2)
    runs = [
        generalisation_run("linear-q", 0, split, 4, root_seed=1, params=TINY, max_steps=40).result
        for _ in range(2)
    ]
    np.testing.assert_equal(astuple(runs[0]), astuple(runs[1]))  # NaN equals NaN here
    assert runs[0].episodes == 4 and 4 <= runs[0].steps <= 160
    for share in (runs[0].success_training_maps, runs[0].success_held_out_maps):
        assert share in (0.0, 0.25, 0.5, 0.75, 1.0)  # 2 maps x 2 rollouts, 1 map x 2


def test_dqn_trains_on_a_map_set() -> None:
    pytest.importorskip("stable_baselines3")
    split = split_worlds(2, 2, 1, 1)
    params = {"learning_starts": 10, "buffer_size": 100, "hidden": [8]}
    run, log = generalisation_run("dqn", 0, split, 2, root_seed=2, params=params, max_steps=20)
    assert run.episodes == 2 and run.steps <= 40 and run.steps == int(np.sum(log.lengths))


def test_command_writes_one_row_per_agent_and_seed(tmp_path: Path) -> None:
    out = tmp_path / "generalisation"
    done = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "study", "generalise", "--agent", "linear-q",
        "--seeds", "2",
         "--training-maps", "2", "--held-out-maps", "1", "--episodes", "2", "--max-steps", "20",
         "--rollouts", "1", "--params", 'linear-q={"dimensions": [4, 5], "tiles": [2]}',
         "--out", str(out), "--backend", "serial"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader((out / "generalisation.csv").open()))
    assert [(row["agent"], row["seed"]) for row in rows] == [("linear-q", "0"), ("linear-q", "1")]
    assert "held-out − training" in done.stdout and "reference goal-seeker" in done.stdout
    assert sorted(path.name for path in (out / "runs").iterdir()) == [
        "run-000000.npz", "run-000001.npz"
    ]  # fmt: skip


def test_references_are_measured_on_the_split() -> None:
    split = split_worlds(0, 2, 2, 2, {"map_kind": "free"})
    random, seeker = references(split, 300, {"map_kind": "free"})
    assert (random.policy, seeker.policy) == ("random", "goal-seeker")
    assert seeker.success_held_out_maps >= 0.75 > random.success_held_out_maps


@pytest.mark.parametrize(
    "arguments, message",
    [
        (["--seeds", "0"], "expected seeds to be an integer in [1, 1,000], got 0"),
        (["--eval-epsilon", "nan"], "expected eval_epsilon in [0, 1], got nan"),
        (["--params", "linear-q"], "AGENT=JSON"),
        (["--params", "linear-q={"], "not JSON"),
        (["--params", "linear-q=[1]"], "JSON object"),
        (["--agent", "nobody"], "unknown agent"),
        (["--agent", "linear-q", "--params", 'linear-q={"tiles": [0]}'], "linear-q"),
    ],
)
def test_bad_arguments_are_one_line(arguments: list[str], message: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "study", "generalise", *arguments, "--out", "x"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert message in done.stderr


def test_epsilon_greedy_evaluation_is_seeded_and_noisy() -> None:
    split = split_worlds(0, 1, 2, 2, {"map_kind": "free"})
    options = {"map_kind": "free", "slip": "thesis", "observation": "features"}
    noisy = [evaluate_on(GoalSeeker(), split.held_out, split.evaluation, 300, 0.3, **options)
             for _ in range(2)]  # fmt: skip
    assert noisy[0] == noisy[1]
    greedy = evaluate_on(GoalSeeker(), split.held_out, split.evaluation, 300, **options)
    assert noisy[0][1] != greedy[1]  # the random actions lengthen the paths
    policy = generalisation.EpsilonGreedy(Spinner(), 1.0, np.random.default_rng(0))
    assert {policy.greedy_action(np.zeros(15)) for _ in range(50)} == {0, 1, 2, 3}


def test_exploration_does_not_draw_the_rollout_s_slip_noise(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The ε draws of a rollout reset with seed s do not come from ``default_rng(s)``, the
    stream the env's reset draws the slip noise from (exploration repeated the noise)."""
    states: list[dict[str, object]] = []  # each policy's generator as it was given
    original = generalisation.EpsilonGreedy

    def recording(agent: object, epsilon: float, rng: np.random.Generator) -> object:
        states.append(rng.bit_generator.state)
        return original(agent, epsilon, rng)  # type: ignore[arg-type]

    monkeypatch.setattr(generalisation, "EpsilonGreedy", recording)
    split = split_worlds(0, 1, 1, 1, {"map_kind": "free"})
    options = {"map_kind": "free", "slip": "thesis", "observation": "features"}
    evaluate_on(GoalSeeker(), split.held_out, split.evaluation, 20, 0.3, **options)
    env_streams = [np.random.default_rng(int(s)).bit_generator.state for s in split.evaluation]
    assert states and all(a != b for a, b in zip(states, env_streams, strict=True))


def test_a_config_run_by_skidnav_run_gives_one_file_per_run_on_every_backend(
    tmp_path: Path,
) -> None:
    (tmp_path / "tiny.toml").write_text(TINY_CONFIG)
    check_serial_and_process_agree(tmp_path / "tiny.toml", tmp_path, 2)
    grid, summaries = study_results(tmp_path / "serial", STUDY.layout)
    assert grid.name == "tiny" and list(summaries["agent"]) == ["linear-q", "linear-q"]
    assert "<h2>Generalisation to maps never seen</h2>" in STUDY.report(tmp_path / "serial")


@pytest.mark.parametrize(
    "text, expected",
    [
        (TINY_CONFIG.replace("episodes =", "episods ="), "bad.toml: [generalisation] (did"),
        (TINY_CONFIG + "[extra]\n", "bad.toml: top level (expected"),
        (TINY_CONFIG.replace("params =", "parms ="), "bad.toml: [[agents]] #1 (did"),
        (TINY_CONFIG.replace('"free"', '"moon"'), "expected map_kind one of free, obstacles"),
        (
            TINY_CONFIG.replace("tiles = [3]", "tiles = [0]"),
            "expected tiles as a non-empty list of integers >= 1, got (0,) "
            "in {config}: [[agents]]: agent 'linear-q'",
        ),
        (
            TINY_CONFIG.replace('kind = "generalisation"', 'kind = "generalization"'),
            "expected kind to be one of",
        ),
    ],
)
def test_a_bad_config_is_one_line_naming_the_file_and_key(
    text: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    check_bad_key_is_one_line(tmp_path / "bad.toml", text, expected, capsys)


def test_the_shortcut_and_the_config_give_the_same_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shortcut = tmp_path / "shortcut"
    assert main([*SHORTCUT, "--out", str(shortcut), "--backend", "serial", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    (tmp_path / "generalisation.toml").write_text(TINY_CONFIG)  # named as the shortcut names it
    run_config(tmp_path / "generalisation.toml", tmp_path / "config", "--backend", "serial")
    table = summary_text(results_of(study_results(tmp_path / "config", STUDY.layout)[1]))
    assert table in printed and "linear-q" in table
    run_config(tmp_path / "generalisation.toml", shortcut)  # the same config: nothing to run
    assert "(0 run now, 2 already done)" in capsys.readouterr().out


def test_the_shipped_config_is_the_command_s_defaults() -> None:
    shipped, defaults = shipped_config_grid_and_defaults("generalise", "generalisation.toml")
    assert shipped == defaults and shipped.fingerprint() == defaults.fingerprint()
