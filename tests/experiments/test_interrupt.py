"""Ctrl-C and SIGTERM on ``skidnav run`` with the process backend: the sweep stops at once (its
workers terminated, not awaited), says how many runs were saved and the command that resumes,
leaves no "leaked semaphore" warning, and the same command then resumes from the saved runs."""

from __future__ import annotations

import re
import signal
import subprocess
import time
from pathlib import Path

import pytest

from tests.experiments.exp_support import TINY_TOML, cli_command, cli_env

STOP_WITHIN_S = 5.0
"""Generous bound on the time from the signal to the exit, for a loaded machine (it takes well
under a second on an idle one; before workers were terminated it took a whole run or more)."""
COMPILE_WAIT_S = 600.0
"""Longest wait for the first saved run (the parent compiles the kernels first)."""
LONG_RUNS = TINY_TOML.replace("episodes = 6", "episodes = 400").replace("seeds = 2", "seeds = 4")
"""16 runs of 400 episodes: each lasts seconds, so the workers are mid-run at the signal."""
INTERRUPTED = re.compile(
    r"skidnav: interrupted: (\d+) of 16 runs saved in (.+); resume with: skidnav (.+)"
)


def _first_run_saved(out: Path, process: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + COMPILE_WAIT_S
    while not any((out / "runs").glob("*.npz")):
        assert process.poll() is None and time.monotonic() < deadline, "no run saved"
        time.sleep(0.2)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_sweep_at_once_and_the_same_command_resumes(
    signum: signal.Signals, tmp_path: Path
) -> None:
    config, out = tmp_path / "long.toml", tmp_path / "results"
    config.write_text(LONG_RUNS)
    arguments = ["run", str(config), "--out", str(out), "--jobs", "2", "--no-progress"]
    process = subprocess.Popen(
        cli_command(*arguments), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env=cli_env(),
    )  # fmt: skip
    _first_run_saved(out, process)
    time.sleep(1.0)  # the pool's workers are now in their first runs
    sent = time.monotonic()
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=60)
    took = time.monotonic() - sent
    assert process.returncode == 130 and took < STOP_WITHIN_S, (took, stderr)
    assert "leaked semaphore" not in stderr and "Traceback" not in stderr, stderr
    match = INTERRUPTED.search(stderr.strip().splitlines()[-1])
    assert match is not None, stderr
    saved, where, command = int(match.group(1)), match.group(2), match.group(3)
    assert Path(where) == out and command.split() == arguments
    assert saved == len(list((out / "runs").glob("*.npz"))) and 1 <= saved < 16
    if signum != signal.SIGINT:
        return
    resumed = subprocess.run(
        cli_command(*arguments), capture_output=True, text=True, env=cli_env(), timeout=900
    )
    assert resumed.returncode == 0, resumed.stderr
    assert f"({16 - saved} run now, {saved} already done)" in resumed.stdout, resumed.stdout
