"""A run that raises never ends a sweep in a traceback: one line names it (agent, preset, map,
seed) and the error, the other runs finish and are kept, the sweep exits with code 1, and the
same command then runs only the failed runs (serial and process backends)."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.errors import EXIT_RUNS_FAILED, RunsFailedError
from skidnav.experiments import trial
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import ResultStore, TrialResult
from tests.experiments.exp_support import TINY_TOML

FAILING = "run-000005 (agent dyna-q-5, preset rough, map free, seed 1)"
"""The run :func:`fail_one_run` fails."""
RUN_TRIAL = trial.run_trial


def fail_one_run(spec: RunSpec) -> TrialResult:  # type: ignore[type-arg]
    """:func:`~skidnav.experiments.trial.run_trial`, but run-000005 divides by zero (as the
    evidence loop of the kinematic refit once did). Importable by spawned workers."""
    if spec.run_id == "run-000005":
        raise ZeroDivisionError("float division by zero")
    return RUN_TRIAL(spec)


@pytest.mark.parametrize(("backend", "jobs"), [("serial", 1), ("process", 2)])
def test_a_failed_run_is_one_line_and_the_others_are_kept(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, backend: str, jobs: int
) -> None:
    config = parse_config(TINY_TOML)
    with caplog.at_level(logging.ERROR), pytest.raises(RunsFailedError) as failed:
        run_experiment(config, tmp_path, backend=backend, jobs=jobs, trial=fail_one_run)
    message = str(failed.value)
    assert message.startswith(f"1 of 8 runs failed: {FAILING} failed: ZeroDivisionError: float")
    assert "\n" not in message and str(tmp_path) in message
    assert [record.getMessage() for record in caplog.records if record.levelname == "ERROR"] == [
        f"{FAILING} failed: ZeroDivisionError: float division by zero"
    ]
    assert sorted(ResultStore(tmp_path).finished()) == [
        f"run-{index:06d}" for index in range(8) if index != 5
    ]
    outcome = run_experiment(config, tmp_path, backend="serial")  # the same command, fixed
    assert (outcome.skipped, outcome.executed) == (7, 1)


def test_the_cli_exits_with_code_1_and_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    config = tmp_path / "tiny.toml"
    config.write_text(TINY_TOML)
    monkeypatch.setattr(trial, "run_trial", fail_one_run)  # the CLI's default trial
    argv = ["run", str(config), "--out", str(tmp_path / "out"), "--backend", "serial"]
    assert main([*argv, "--no-progress"]) == EXIT_RUNS_FAILED == 1
    captured = capsys.readouterr()
    assert captured.out == "" and "Traceback" not in captured.err
    assert captured.err.splitlines()[-1].startswith(
        f"skidnav: error: 1 of 8 runs failed: {FAILING}"
    )
