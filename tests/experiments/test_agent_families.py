"""Tabular, linear and deep agents through one runner: same worlds, same records, one report."""

from __future__ import annotations

from pathlib import Path

import pytest

from skidnav.errors import UserError
from skidnav.experiments.config_checks import check_config
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.report.html import build_report
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import ResultStore

FAMILIES = """
[experiment]
name = "families"
episodes = 5
max_steps = 40
seeds = 1
root_seed = 5
presets = ["rough"]
bootstrap_samples = 100
convergence_window = 2
eval_rollouts = 2
oracle_samples = 4

[env]
observation = "{observation}"

[[maps]]
kind = "free"

[[agents]]
name = "q-learning"

[[agents]]
name = "linear-q"
{linear_params}

[[agents]]
name = "dqn"
params = {{ learning_starts = 50, buffer_size = 1000, hidden = [16] }}
"""


def families(observation: str = "pose", linear_params: str = "") -> str:
    return FAMILIES.format(observation=observation, linear_params=linear_params)


def test_every_family_runs_on_the_same_worlds_and_reports(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    config = parse_config(families())
    check_config(config)
    run_experiment(config, tmp_path, backend="serial")
    episodes, summaries = ResultStore(tmp_path).load_tables()
    assert sorted(summaries["agent"]) == ["dqn", "linear-q", "q-learning"]
    assert len(episodes) == 3 * 5
    assert episodes["length"].between(1, 40).all()
    assert episodes["greedy_success"].between(0, 1).all()  # every agent evaluated greedily
    assert summaries["oracle_length"].nunique() == 1  # one world, one oracle for all three
    html = build_report(tmp_path)
    assert "linear-q" in html and "dqn" in html and "value maps" in html


def test_a_continuous_agent_over_the_discrete_state_is_refused_in_one_line() -> None:
    with pytest.raises(UserError, match="'linear-q' learns over a Box observation"):
        check_config(parse_config(families(observation="discrete")))


def test_bad_parameters_of_a_continuous_agent_are_refused_before_any_run() -> None:
    bad = families(linear_params="params = { n_tilings = 0 }")
    with pytest.raises(UserError, match="agent 'linear-q'"):
        check_config(parse_config(bad))
