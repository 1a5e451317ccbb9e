"""Experiment configs read by their loaders within limits: a nested, huge or non-text config is
one line (exit 2) for ``skidnav run`` and ``skidnav tune``, long values are quoted in part, and a
config is read once (a pipe works)."""

from __future__ import annotations

import os
import re
import subprocess
import threading
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.experiments.configfile import load_config, load_config_and_text
from skidnav.studies.tuning.config import load_tune_config
from tests.experiments.exp_support import TINY_TOML, cli_command, cli_env

DEEP = 5000
TUNE = (
    "\n[tune]\ntrials = 2\nseeds = 2\n\n[tune.space.q-learning]\n"
    "alpha = { low = 0.05, high = 1.0 }\n"
)
"""A ``[tune]`` table for :data:`TINY_TOML` (so that ``skidnav tune`` reads the agents)."""
PARAMS = "params = { planning_steps = 5 }"

CASES: dict[str, tuple[str, str]] = {
    # name: (config text, message)
    "nested dotted keys": (
        TINY_TOML.replace(PARAMS, "params" + ".x" * DEEP + " = 1"),
        "malformed TOML: nested too deeply (5003 levels, at most 32)",
    ),
    "nested inline tables": (
        TINY_TOML.replace(PARAMS, "params = " + "{ x = " * DEEP + "1" + " }" * DEEP),
        "malformed TOML: nested too deeply",
    ),
    "nested table headers": (
        TINY_TOML + "\n[env" + ".x" * DEEP + "]\n",
        "malformed TOML: nested too deeply",
    ),
    "5000-digit integer": (
        TINY_TOML.replace("episodes = 6", "episodes = " + "6" * DEEP),
        "malformed TOML: Exceeds the limit (4300 digits)",
    ),
    "long presets": (
        TINY_TOML.replace('presets = ["rough", "slippery"]', f'presets = "{"p" * 10_000}"'),
        "expected presets to be a list of strings, got \"'pppp",
    ),
    "long unknown key": (
        TINY_TOML.replace("episodes = 6", f"{'k' * 10_000} = 6"),
        "unknown key \"'kkkk",
    ),
    "a generated map whose oracle does not fit": (
        TINY_TOML.replace(
            'kind = "free"', 'kind = "free"\noptions = { shape = [1000, 1000] }'
        ).replace("oracle_samples = 4", "oracle_samples = 64"),
        "map 'free': its oracle would need 19.1 GiB (20,000,000 states × 4 actions × 64 samples",
    ),
    "an optimum grid whose oracle does not fit": (
        TINY_TOML.replace(
            "eval_rollouts = 2", "optimum_grids = [[1000, 1000, 5]]\noptimum_samples = 1000"
        ),
        "optimum grid [1000, 1000, 5]: its oracle would need 74.5 GiB",
    ),
    "a bool for a number": (
        TINY_TOML.replace(PARAMS, "params = { planning_steps = 5, alpha = true }"),
        "expected alpha to be a number, got True in {config}: agent 'dyna-q'",
    ),
    "an unknown env option": (
        TINY_TOML + "\n[env]\nbogus_key = 3\n",
        "environment or map options: SkidSteerNavEnv.__init__() got an unexpected keyword "
        "argument 'bogus_key'",
    ),
    "long map file": (
        TINY_TOML.replace('kind = "free"', f'file = "{"m" * 10_000}.txt"'),
        "no such map file \"'mmmm",
    ),
}


@pytest.mark.parametrize("command", ["run", "tune"])
@pytest.mark.parametrize("case", CASES)
def test_a_hostile_config_is_one_line_and_writes_nothing(
    case: str, command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text, message = CASES[case]
    config = tmp_path / "hostile.toml"
    config.write_text(text + (TUNE if command == "tune" else ""))
    out = tmp_path / "out"
    assert main([command, str(config), "--out", str(out), "--backend", "serial"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skidnav: error: ") and str(config) in lines[0]
    assert message.replace("{config}", str(config)) in lines[0], lines
    assert not re.search(r"(.)\1{40}", lines[0])  # an excerpt of a long value, not all of it
    assert sorted(tmp_path.iterdir()) == [config]


def test_a_tuning_map_whose_oracle_does_not_fit_is_refused_when_read(tmp_path: Path) -> None:
    config = tmp_path / "tune.toml"
    big = '\n[[tune.maps]]\nkind = "free"\nlabel = "big"\noptions = { shape = [1000, 1000] }\n'
    config.write_text(TINY_TOML.replace("oracle_samples = 4", "oracle_samples = 64") + TUNE + big)
    with pytest.raises(UserError, match=r"\[\[tune.maps\]\] 'big': its oracle would need 19.1 GiB"):
        load_tune_config(config)


def test_the_oracle_refuses_a_world_beyond_the_budget_before_allocating(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The last guard, for a world no config check saw (here: a budget made tiny)."""
    import gymnasium

    from skidnav.experiments import memory
    from skidnav.experiments.reference.oracle import compute_oracle

    monkeypatch.setattr(memory, "MEMORY_BUDGET", 2**20)
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free")
    with pytest.raises(
        UserError, match=r"^the world: its oracle would need 0.0 GiB \(12,500 states"
    ):
        compute_oracle(env, 64, 0, [0], 10)


def test_a_tuning_table_without_seeds_is_named_not_a_constructor_error(tmp_path: Path) -> None:
    config = tmp_path / "tune.toml"
    config.write_text(TINY_TOML + TUNE.replace("seeds = 2\n", ""))
    refused = r"^missing key 'seeds' in \S*tune\.toml: \[tune\] \(tuning seeds per trial\)$"
    with pytest.raises(UserError, match=refused):
        load_tune_config(config)


def test_the_loaders_bound_their_own_reads(tmp_path: Path) -> None:
    huge = tmp_path / "huge.toml"
    huge.write_bytes(b"#" * 4_000_001)
    for load in (load_config, load_tune_config, load_config_and_text):
        with pytest.raises(UserError, match=r"^/dev/zero: cannot read config file \(a character"):
            load("/dev/zero")
        with pytest.raises(UserError, match=r"huge.toml: config file larger than 4,000,000"):
            load(huge)
    config = tmp_path / "tiny.toml"
    config.write_text(TINY_TOML)
    loaded, text = load_config_and_text(config)
    assert text == TINY_TOML and loaded == load_config(config) and loaded.name == "tiny"


def test_tune_reads_its_config_once_so_a_pipe_works(tmp_path: Path) -> None:
    pipe = tmp_path / "config.toml"
    os.mkfifo(pipe)

    def feed() -> None:  # one writer: a second open for reading would wait forever
        with open(pipe, "w", encoding="utf-8") as stream:
            stream.write(TINY_TOML)

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    out = tmp_path / "out"
    try:
        result = subprocess.run(
            cli_command("tune", str(pipe), "--out", str(out)),
            env=cli_env(), capture_output=True, text=True, timeout=60,
        )  # fmt: skip
    finally:
        if writer.is_alive():  # release the writer if the command never opened the pipe
            os.close(os.open(pipe, os.O_RDONLY | os.O_NONBLOCK))
        writer.join(5)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-2000:]
    assert lines[0] == f"skidnav: error: {pipe}: no [tune] table (see docs/tuning.md)"
    assert not out.exists()
