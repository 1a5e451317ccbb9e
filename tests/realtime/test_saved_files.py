"""Hostile real-time configs and checkpoints end in one line (exit 2) before anything is written;
checkpoints are written all-or-nothing."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skidnav.agents.tabular.registry import load_agent, make_agent
from skidnav.cli import main
from skidnav.errors import CorruptFileError
from skidnav.realtime.config import load_config
from skidnav.realtime.control.checkpoint import LATEST, Checkpoints
from skidnav.realtime.control.run_folder import mark_run_folder
from tests.realtime.realtime_helpers import write_config
from tests.saved_file_support import listing, write_checkpoint

REALTIME = Path(__file__).resolve().parents[2] / "configs" / "realtime.toml"
DEEP = 5000
RUN = ["robot", "run", "--quiet", "--driver", "sim", "--agent", "q-learning"]

PRESET = '\n[presets.p.sim]\nslip = "rough"\n'
"""A preset ``p`` (chosen by the commands below), so that the other tables are read."""
CONFIG_CASES: dict[str, tuple[str, str]] = {
    # name: (config text, message; {config} is the config's path)
    "nested arrays": (
        "x = " + "[" * DEEP + "]" * DEEP,
        "{config}: malformed TOML: nested too deeply",
    ),
    "nested inline tables": (
        "x = " + "{ a = " * DEEP + "1" + " }" * DEEP,
        "{config}: malformed TOML: nested too deeply",
    ),
    "nested dotted keys": (
        "[presets.p]\nrun" + ".x" * DEEP + " = 1",
        f"{{config}}: malformed TOML: nested too deeply ({DEEP + 3} levels, at most 32)",
    ),
    "nested table header": (
        "[presets.p" + ".x" * DEEP + "]",
        "{config}: malformed TOML: nested too deeply",
    ),
    "5000-digit integer": (
        "[run]\nepisodes = " + "1" * DEEP,
        "{config}: malformed TOML: Exceeds the limit",
    ),
    "malformed": ("[run]\nepisodes = = 2", "{config}:2:12: malformed TOML: Invalid value"),
    "not UTF-8": ("[run]\nreset = '\udcff'", "{config}: cannot read config (UnicodeDecodeError)"),
    "run not a table": ("run = 3" + PRESET, "[run]: expected a table, got 3"),
    "presets not a table": ("presets = 3", "[presets]: expected a table, got 3"),
    "agents not tables": (
        "[agents]\nq-learning = 3" + PRESET,
        "[agents.q-learning]: expected a table, got 3",
    ),
    "long reset": (
        '[run]\nreset = "' + "x" * 10_000 + '"' + PRESET,
        "expected reset 'auto' or 'manual', got \"'xxxx",
    ),
    "long unknown table": ("[" + "t" * 10_000 + "]" + PRESET, "unknown key \"'tttt"),
}


def _one_error_line(stderr: str) -> str:
    """The one ``skidnav: error:`` line of ``stderr`` (no traceback, no second error)."""
    errors = [line for line in stderr.splitlines() if line.startswith("skidnav: error: ")]
    assert len(errors) == 1 and "Traceback" not in stderr, stderr[-2000:]
    return errors[0]


@pytest.mark.parametrize("command", ["run", "study"])
@pytest.mark.parametrize("case", CONFIG_CASES)
def test_a_hostile_config_is_one_line_and_writes_nothing(
    case: str, command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text, message = CONFIG_CASES[case]
    config = tmp_path / "realtime.toml"
    config.write_bytes(text.encode("utf-8", errors="surrogateescape"))
    message = message.format(config=config)
    before = listing(tmp_path)
    args = RUN if command == "run" else ["robot", "study", "--quiet"]
    preset = ["--preset", "p"] if command == "run" else ["--presets", "p"]
    code = main([*args, *preset, "--config", str(config), "--out", str(tmp_path / "out")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1, lines
    assert lines[0].startswith("skidnav: error: ") and message in lines[0], lines
    assert len(lines[0]) < len(str(config)) + 250  # an excerpt of a long value, not all of it
    assert "t" * 100 not in lines[0]
    assert listing(tmp_path) == before


@pytest.mark.parametrize("command", ["run", "study"])
def test_a_device_as_config_is_refused_without_reading_it(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = RUN if command == "run" else ["robot", "study", "--quiet"]
    assert main([*args, "--config", "/dev/zero", "--out", str(tmp_path / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [
        "skidnav: error: /dev/zero: cannot read config file (a character device, not a regular "
        "file)"
    ]
    assert list(tmp_path.iterdir()) == []


def test_a_study_table_that_is_not_a_table_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path, "study = 3\n")
    assert main(["robot", "study", "--config", str(config), "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.strip() == (
        f"skidnav: error: {config}: [study]: expected a table, got 3"
    )


NESTED_JSON = "[" * DEEP + "]" * DEEP
CHECKPOINT_CASES: dict[str, tuple[dict[str, str], str, str]] = {
    # name: (files changed, the file named, message)
    "nested pointer": (
        {"pointer": '{"episode": ' + "[" * 1500 + "]" * 1500 + "}"},
        "latest.json",
        "JSON nested 1501 deep",
    ),
    "pointer outside": (
        {"pointer": '{"episode": 0, "directory": "../../.."}'},
        "latest.json",
        "expected directory 'ep-00000' for episode 0, got '../../..'",
    ),
    "pointer to another episode": (
        {"pointer": '{"episode": 3, "directory": "ep-00000"}'},
        "latest.json",
        "expected directory 'ep-00003' for episode 3",
    ),
    "boolean episode": (
        {"pointer": '{"episode": true, "directory": "ep-00000"}'},
        "latest.json",
        "expected an episode >= 0, got True",
    ),
    "long directory": (
        {"pointer": '{"episode": 0, "directory": "' + "d" * 3000 + '"}'},
        "latest.json",
        "got \"'dddd",
    ),
    "pointer not an object": ({"pointer": "[0]"}, "latest.json", "expected a JSON object"),
    "nested loop state": (
        {"loop_state": '{"results": ' + NESTED_JSON + "}"},
        "loop.json",
        f"JSON nested {DEEP + 1} deep",
    ),
    "NaN statistics": (
        {"loop_state": '{"results": [], "wheel_speed_stats": [[NaN, 1]]}'},
        "loop.json",
        "non-finite number NaN",
    ),
    "ragged statistics": (
        {"loop_state": '{"results": [], "wheel_speed_stats": [[1, 2], [3]]}'},
        "loop.json",
        "wheel_speed_stats is not a table of finite numbers",
    ),
    "text statistics": (
        {
            "loop_state": '{"results": [], "wheel_speed_stats": [], "icr_sums": ["'
            + "s" * 10_000
            + '"]}'
        },
        "loop.json",
        "icr_sums is not a table of finite numbers",
    ),
    "empty loop state": ({"loop_state": "{}"}, "loop.json", "unusable loop state (no 'results')"),
    "no statistics": (
        {"loop_state": '{"results": []}'},
        "loop.json",
        "unusable loop state (no 'wheel_speed_stats')",
    ),
    "results not a list": (
        {"loop_state": '{"results": {"episode": 0}}'},
        "loop.json",
        "expected 'results' to be a list of episode results",
    ),
    "result of the wrong type": (
        {"loop_state": '{"results": [{"episode": 0, "actions": "many"}]}'},
        "loop.json",
        "expected actions to be an integer >= 0, got 'many'",
    ),
    "unknown result field": (
        {"loop_state": '{"results": [{"episode": 0, "' + "k" * 10_000 + '": 1}]}'},
        "loop.json",
        "unusable loop state (unexpected episode result field",
    ),
}


@pytest.mark.parametrize("case", CHECKPOINT_CASES)
def test_a_hostile_checkpoint_ends_the_resume_in_one_line(
    case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    files, named, message = CHECKPOINT_CASES[case]
    out = tmp_path / "run"
    write_checkpoint(out, **files)
    mark_run_folder(out, load_config(REALTIME))  # a run of this config: its checkpoint is read
    before = listing(out)
    code = main([*RUN, "--config", str(REALTIME), "--resume", "--out", str(out)])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1, lines
    assert lines[0].startswith(f"skidnav: error: {out / 'checkpoints'}"), lines
    assert named in lines[0] and message in lines[0], lines
    assert len(lines[0]) < len(str(out)) + 200  # at most an excerpt of the file
    assert listing(out) == before  # nothing written, nothing left behind


def test_a_pointer_through_a_device_is_refused_and_a_long_one_cut(tmp_path: Path) -> None:
    root = write_checkpoint(tmp_path).parent
    (root / LATEST).unlink()
    (root / LATEST).symlink_to("/dev/zero")
    with pytest.raises(CorruptFileError, match=r"checkpoint pointer \(a character device"):
        Checkpoints(root).latest()
    (root / LATEST).unlink()
    (root / LATEST).write_text(" " * 4097)
    with pytest.raises(CorruptFileError, match="checkpoint pointer larger than 4,096 bytes"):
        Checkpoints(root).latest()


def _dead_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_a_failed_checkpoint_leaves_the_previous_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    checkpoints = Checkpoints(tmp_path / "checkpoints", keep=3)
    agent = make_agent("q-learning", 54, 4, {}, np.random.default_rng(0))
    agent.q[:] = 1.0
    checkpoints.save(0, agent, {"results": [], "wheel_speed_stats": [], "episodes_done": 1})
    stale = checkpoints.root / f".{LATEST}.{_dead_pid()}-0123abcd.tmp"
    stale.write_text("left by a killed run")
    replace = os.replace

    def disk_full_at_the_pointer(source: Any, target: Any) -> None:
        if Path(target).name == LATEST:
            raise OSError(errno.ENOSPC, "No space left on device")
        replace(source, target)

    monkeypatch.setattr(os, "replace", disk_full_at_the_pointer)
    agent.q[:] = 2.0
    with pytest.raises(OSError, match="No space left"):
        checkpoints.save(1, agent, {"results": [], "wheel_speed_stats": [], "episodes_done": 2})
    monkeypatch.undo()
    latest = checkpoints.latest()
    assert latest is not None and latest[0] == 0 and latest[2]["episodes_done"] == 1
    assert np.all(load_agent(latest[1] / "agent").q == 1.0)
    names = sorted(p.name for p in checkpoints.root.iterdir())
    assert names == ["ep-00000", "ep-00001", LATEST]  # stale temporary gone, no new one
    assert not [p for p in checkpoints.root.rglob("*.tmp")]
    checkpoints.save(1, agent, {"results": [], "wheel_speed_stats": [], "episodes_done": 2})
    latest = checkpoints.latest()
    assert latest is not None and latest[0] == 1 and np.all(load_agent(latest[1] / "agent").q == 2)
