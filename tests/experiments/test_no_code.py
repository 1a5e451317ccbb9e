"""A config names environments by registered id only: nothing named in it is ever called."""

from __future__ import annotations

import subprocess
from pathlib import Path

from tests.experiments.exp_support import cli_command, cli_env

CONFIG = """
[experiment]
name = "hostile"
env_id = "{env_id}"
episodes = 2
seeds = 1

[env]
command = "touch {marker}"

[[agents]]
name = "q-learning"
"""


def _run(tmp_path: Path, env_id: str) -> tuple[subprocess.CompletedProcess[str], Path]:
    marker = tmp_path / "ran"
    config = tmp_path / "hostile.toml"
    config.write_text(CONFIG.format(env_id=env_id, marker=marker))
    result = subprocess.run(
        cli_command("run", str(config), "--out", str(tmp_path / "out")),
        capture_output=True, text=True, env=cli_env(), timeout=120,
    )  # fmt: skip
    return result, marker


def test_a_callable_named_in_a_config_is_not_called(tmp_path: Path) -> None:
    for env_id in ("os:system", "subprocess:getoutput"):
        result, marker = _run(tmp_path, env_id)
        assert result.returncode == 2, result.stderr
        assert not marker.exists()
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and env_id in lines[0], result.stderr
        assert not (tmp_path / "out").exists()


def test_the_mazes_are_registered_ids() -> None:
    import gymnasium

    import skidnav  # noqa: F401

    for env_id in ("skidnav/DynaMaze-v0", "skidnav/BlockingMaze-v0", "skidnav/ShortcutMaze-v0"):
        assert gymnasium.make(env_id).unwrapped.shortest_path_length() > 0
