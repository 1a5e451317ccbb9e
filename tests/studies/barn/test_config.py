"""A BARN config: its keys and values checked before anything runs, a bad one refused in one
line naming the file and the key (exit code 2); the world range form; the shipped configs."""

from __future__ import annotations

from pathlib import Path

import pytest

from skidnav.agents.catalog import agent_names
from skidnav.studies.barn.grid import BarnGrid, expand_worlds, quintile
from skidnav.studies.loading import parse_grid
from tests.cli_support import exit_code

CONFIGS = Path(__file__).parents[3] / "configs"
GOOD = """kind = "barn"
[barn]
worlds = [0, 1]
{extra}
[[agents]]
name = "goal-tracker"
{agent}
"""


def grid(extra: str = "", agent: str = "") -> BarnGrid:
    text = GOOD.format(extra=extra, agent=agent)
    if extra.startswith("worlds"):
        text = text.replace("worlds = [0, 1]\n", "", 1)
    parsed = parse_grid(text, Path("barn-test.toml")).grid
    assert isinstance(parsed, BarnGrid)
    return parsed


def test_defaults_and_the_runs_of_the_grid() -> None:
    parsed = grid('floors = ["nominal", "ice-physics"]\nseeds = 2')
    assert parsed.name == "barn-test" and parsed.protocol == "zero-shot"
    assert parsed.episodes == 1 and parsed.lidar_rays == 271 and parsed.dynamics == "kinematic"
    assert [spec.label for spec in parsed.maps] == ["world-0", "world-1"]
    assert parsed.presets == ("nominal", "ice-physics") and parsed.n_runs == 8
    assert BarnGrid.from_dict(parsed.to_dict()) == parsed


def test_the_discrete_action_duration_is_whole_periods_and_kept_out_of_old_fingerprints() -> None:
    default = grid()
    assert default.discrete_action_duration == 0.1 and default.action_periods == 1
    assert "discrete_action_duration" not in default.to_dict()  # the results of old configs
    longer = grid("discrete_action_duration = 1")
    assert longer.discrete_action_duration == 1.0 and longer.action_periods == 10
    assert BarnGrid.from_dict(longer.to_dict()) == longer
    assert longer.fingerprint() != default.fingerprint()
    assert grid("discrete_action_duration = 0.3").action_periods == 3


def test_worlds_as_a_range() -> None:
    assert grid("worlds = { start = 10, stop = 300, step = 145 }").worlds == (10, 155)
    assert expand_worlds({"stop": 3}) == (0, 1, 2)
    assert [quintile(world) for world in (0, 59, 60, 179, 240, 299)] == [0, 0, 1, 2, 4, 4]


@pytest.mark.parametrize(
    ("extra", "agent", "message"),
    [
        (
            "seedz = 2",
            "",
            "bad.toml: [barn] (did you mean 'seeds'? expected one of name, ",
        ),
        ('protocol = "few-shot"', "", "expected protocol one of zero-shot, learning"),
        ("episodes = 3", "", "expected episodes = 1 with protocol zero-shot, got 3"),
        ('protocol = "learning"\nepisodes = 0', "", "expected episodes to be an integer in [1"),
        ("worlds = [0, 300]", "", "expected each of worlds to be an integer in [0, 299], got 300"),
        ("worlds = [4, 4]", "", "expected distinct worlds, got [4, 4]"),
        ("worlds = []", "", "expected worlds to be a non-empty list or a range"),
        ("worlds = { start = 0 }", "", "expected worlds to have a stop"),
        (
            "worlds = { stop = 9, stride = 2 }",
            "",
            "bad.toml: [barn]: worlds (did you mean 'step'?",
        ),
        ("worlds = { stop = 5, step = 0 }", "", "expected worlds.step to be an integer in [1"),
        ('floors = ["ice"]', "", "expected floors to be distinct names among"),
        ('dynamics = "gazebo"', "", "expected dynamics one of kinematic, mujoco"),
        ("lidar_rays = 5000", "", "expected lidar_rays to be an integer in [0, 1024]"),
        ("root_seed = -1", "", "expected root_seed to be an integer >= 0"),
        ("discrete_action_duration = 0.05", "", "to be a finite number in [0.1, 10], got 0.05"),
        ("discrete_action_duration = 0.25", "", "a whole number of the benchmark's 0.1 s periods"),
        ("discrete_action_duration = 10.5", "", "discrete_action_duration to be a finite number "),
        ('discrete_action_duration = "0.5"', "", "discrete_action_duration to be a finite number"),
        ("seeds = 1.5", "", "expected seeds to be an integer in [1, 1,000]"),
        ("", "params = { turn_gain = -1 }", "expected turn_gain to be a finite number > 0, got -1"),
        ("", "params = { lidar_rays = 8 }", "lidar_rays is the study's laser (271)"),
        ("", "colour = 3", "bad.toml: [[agents]] #1 (expected one of name, label, params)"),
    ],
)
def test_a_bad_config_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: str, agent: str, message: str
) -> None:
    config = tmp_path / "bad.toml"
    text = GOOD.format(extra="", agent=agent)
    config.write_text(text.replace("worlds = [0, 1]", extra or "worlds = [0, 1]"))
    assert exit_code(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and str(config) in error and message in error, error
    assert not (tmp_path / "out").exists()


def test_an_unknown_agent_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(GOOD.format(extra="", agent="").replace("goal-tracker", "pilot"))
    assert exit_code(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "unknown agent 'pilot'" in error, error


@pytest.mark.parametrize(
    ("name", "protocol", "n_worlds", "floors", "episodes", "duration"),
    [
        ("barn-zero-shot", "zero-shot", 300, ("nominal",), 1, 0.1),
        ("barn-ice-learning", "learning", 30, ("ice-physics",), 5, 0.1),
        ("barn-dyna-full-learning", "learning", 30, ("nominal",), 1000, 0.5),
        ("barn-smoke", "zero-shot", 2, ("nominal",), 1, 0.1),
        ("barn-mujoco-zero-shot", "zero-shot", 30, ("nominal",), 1, 0.1),
        ("barn-mujoco-ice-zero-shot", "zero-shot", 30, ("ice-physics",), 1, 0.1),
        ("barn-mujoco-learning", "learning", 30, ("nominal",), 3, 0.1),
    ],
)
def test_the_shipped_configs(
    name: str, protocol: str, n_worlds: int, floors: tuple[str], episodes: int, duration: float
) -> None:
    path = CONFIGS / f"{name}.toml"
    if "classical" in path.read_text() and "classical" not in agent_names():
        pytest.skip("the classical agent is not registered in this tree")
    parsed = parse_grid(path.read_text(), path).grid
    assert isinstance(parsed, BarnGrid) and parsed.name == name
    assert parsed.protocol == protocol and len(parsed.worlds) == n_worlds
    assert parsed.floors == floors and parsed.episodes == episodes
    assert parsed.discrete_action_duration == duration
    assert parsed.dynamics == ("mujoco" if "mujoco" in name else "kinematic")
