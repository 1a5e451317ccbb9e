"""Code that builds the env gets its action limit from Gymnasium's ``TimeLimit``: the experiment
runs (config ``max_steps`` or ``[env] max_episode_steps``, else the registered 500) and
``skidnav world simulate`` (the length of its script or ``--random N``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import skidnav  # noqa: F401  (registers the env)
from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.experiments import config_checks, trial
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runs import expand_runs
from skidnav.world.grid import GridMap, border_walls

CONFIG = """
[experiment]
name = "limits"
episodes = 2
{limit}
env_id = "{env_id}"

[[maps]]
kind = "free"

[[agents]]
name = "q-learning"
{env}
"""


def _limit(env_id: str, limit: str = "", env: str = "") -> tuple[int, int | None]:
    """(action limit of the run, spec's max_episode_steps of the made env)."""
    config = parse_config(CONFIG.format(env_id=env_id, limit=limit, env=env))
    spec = expand_runs(config)[0]
    grid_map = GridMap(border_walls((6, 6)), start=(1, 1), goal=(3, 1))
    made = trial.trial_env(spec, grid_map, 0)
    assert made.unwrapped.spec.max_episode_steps is None  # the env itself never truncates
    return trial.action_limit(made), made.spec.max_episode_steps


@pytest.mark.parametrize(
    ("limit", "env", "expected"),
    [
        ("", "", 500),
        ("max_steps = 120", "", 120),
        ("", "[env]\nmax_episode_steps = 70", 70),
        ("max_steps = 120", "[env]\nmax_episode_steps = 70", 120),
    ],
)
def test_run_limit_of_the_navigation_env(limit: str, env: str, expected: int) -> None:
    assert _limit("skidnav/SkidSteerNav-v0", limit, env) == (expected, expected)


def test_run_limit_of_a_maze_registered_without_one() -> None:
    assert _limit("skidnav/DynaMaze-v0") == (10_000, None)
    assert _limit("skidnav/DynaMaze-v0", env="[env]\nmax_episode_steps = 40") == (40, 40)


def test_a_bad_env_limit_is_one_line() -> None:
    config = parse_config(
        CONFIG.format(
            env_id="skidnav/SkidSteerNav-v0", limit="", env='[env]\nmax_episode_steps = "x"'
        )
    )
    with pytest.raises(UserError, match="max_episode_steps to be an integer >= 1"):
        config_checks.check_config(config)


def test_a_run_on_the_unwrapped_env_truncates_at_the_limit() -> None:
    config = parse_config(CONFIG.format(env_id="skidnav/SkidSteerNav-v0", limit="", env=""))
    result = trial.run_trial(expand_runs(config)[0])
    assert result.summary["action_limit"] == 500.0
    assert int(np.max(result.episodes["length"])) <= 500


def test_simulate_runs_past_the_registered_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    table = tmp_path / "t.csv"
    backwards = " ".join(["b"] * 620)  # into the wall behind the start: never the goal
    arguments = ["world", "simulate", "--map-kind", "free", "--actions", backwards]
    assert main([*arguments, "--out", str(tmp_path / "t.png"), "--csv", str(table)]) == 0
    assert capsys.readouterr().out.startswith("620 actions")
    assert len(table.read_text().splitlines()) == 1 + 1 + 620
