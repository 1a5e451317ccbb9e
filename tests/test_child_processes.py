"""Every Python child skidnav starts imports nothing from the current directory: a ``json.py``,
``numpy.py`` or ``pickle.py`` planted in the folder a command runs from never runs (the robot's
sim server, the workers of ``skidnav run --jobs 2``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from skidnav.childprocess import SAFE_PATH_VARIABLE, child_environment, safe_path_children
from skidnav.cli import main

PLANTED = ("json", "numpy", "pickle", "socket", "signal", "threading", "copyreg", "struct")
"""Modules a child imports early: the ones a spawned worker imports before it takes its
parent's ``sys.path`` are among them."""


def plant(folder: Path, marker: Path) -> Path:
    """Modules in ``folder`` that append their name to ``marker`` when imported."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in PLANTED:
        (folder / f"{name}.py").write_text(
            f"open({str(marker)!r}, 'a').write({name + ' '!r})\n", encoding="utf-8"
        )
    return folder


def test_child_environment_turns_safe_path_on_and_drops_empty_entries() -> None:
    environment = child_environment({"PYTHONPATH": ":/a::", "HOME": "/h"})
    assert environment[SAFE_PATH_VARIABLE] == "1" and environment["HOME"] == "/h"
    assert "" not in environment["PYTHONPATH"].split(os.pathsep)[1:]


def test_safe_path_children_sets_and_restores_the_environment(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.delenv(SAFE_PATH_VARIABLE, raising=False)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(tmp_path), ""]))
    monkeypatch.chdir(plant(tmp_path / "cwd", tmp_path / "ran"))
    probe = [sys.executable, "-c", "import sys; print('' in sys.path, sys.flags.safe_path)"]
    with safe_path_children():
        inside = subprocess.run(probe, capture_output=True, text=True, check=True)
    assert inside.stdout.split() == ["False", "True"]
    assert SAFE_PATH_VARIABLE not in os.environ
    assert os.environ["PYTHONPATH"] == os.pathsep.join([str(tmp_path), ""])
    assert not (tmp_path / "ran").exists()


def test_the_sim_server_ignores_modules_in_the_current_directory(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    marker = tmp_path / "ran"
    config = tmp_path / "realtime.toml"
    config.write_text(
        '[run]\nepisodes = 1\nmax_actions = 3\ntime_scale = 50.0\nmap = "free"\n'
        '[sim]\nslip = "rough"\nlockstep = true\n',
        encoding="utf-8",
    )
    monkeypatch.chdir(plant(tmp_path / "cwd", marker))
    argv = ["robot", "run", "--quiet", "--out", str(tmp_path / "out"), "--driver", "sim"]
    assert main([*argv, "--agent", "q-learning", "--config", str(config)]) == 0
    assert not marker.exists(), marker.read_text()


def test_run_workers_ignore_modules_in_the_current_directory(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Three runs on two jobs: the first in this process, two in spawned workers (whose
    ``python -c`` start put the current directory first)."""
    marker = tmp_path / "ran"
    config = tmp_path / "tiny.toml"
    config.write_text(
        '[experiment]\nname = "planted"\nepisodes = 2\nmax_steps = 20\nseeds = 3\n'
        "eval_rollouts = 1\noracle_samples = 2\n"
        '[[maps]]\nkind = "free"\n[[agents]]\nname = "q-learning"\n',
        encoding="utf-8",
    )
    monkeypatch.chdir(plant(tmp_path / "cwd", marker))
    argv = ["run", str(config), "--out", str(tmp_path / "out"), "--jobs", "2", "--no-progress"]
    assert main(argv) == 0, capsys.readouterr().err
    assert "3 runs" in capsys.readouterr().out
    assert not marker.exists(), marker.read_text()
