"""Absurd numbers in a config are refused up front with one line, before any run starts."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from skidnav.errors import UserError
from skidnav.experiments.configfile import parse_config
from tests.experiments.exp_support import cli_command, cli_env

BASE = """
[experiment]
name = "bounds"
episodes = 10
seeds = 2
{extra}

[[maps]]
kind = "free"

[[agents]]
name = "dyna-q"
params = {{ planning_steps = {planning} }}
"""


@pytest.mark.parametrize(
    ("extra", "planning", "message"),
    [
        ("seeds = 1000000", 5, "seeds"),
        ("bootstrap_samples = 1000000000000", 5, "bootstrap_samples"),
        ("drift_amplitude = inf", 5, "drift_amplitude"),
        ("drift_period = nan", 5, "drift_period"),
        ("max_steps = 1000000000", 5, "max_steps"),
        ("", 10**15, "planning_steps"),
    ],
)
def test_out_of_range_numbers_are_refused(extra: str, planning: int, message: str) -> None:
    text = BASE.format(extra=extra, planning=planning).replace("seeds = 2\nseeds", "seeds")
    with pytest.raises(UserError, match=message) as error:
        config = parse_config(text)
        from skidnav.experiments.config_checks import check_config

        check_config(config)
    assert "\n" not in str(error.value)


def test_absurd_total_work_is_refused() -> None:
    text = BASE.format(extra="", planning=5).replace("episodes = 10", "episodes = 9000000")
    text = text.replace("seeds = 2", "seeds = 5000")
    with pytest.raises(UserError, match="episodes in all"):
        parse_config(text)


def test_deeply_nested_toml_is_one_line(tmp_path: Path) -> None:
    config = tmp_path / "deep.toml"
    config.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    result = subprocess.run(
        cli_command("run", str(config), "--out", str(tmp_path / "out")),
        capture_output=True, text=True, env=cli_env(), timeout=120,
    )  # fmt: skip
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "nested too deeply" in lines[0], result.stderr
    assert not (tmp_path / "out").exists()
