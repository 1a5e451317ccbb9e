"""Identical numbers on every backend; after SIGKILL no worker survives, and resuming loses and
duplicates nothing."""

from __future__ import annotations

import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import psutil
import pytest

from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment
from tests.experiments.exp_support import TINY_TOML, cli_command, cli_env, comparable


def test_process_pool_matches_serial(serial_results: Path, tmp_path: Path) -> None:
    outcome = run_experiment(parse_config(TINY_TOML), tmp_path, backend="process", jobs=2)
    assert outcome.executed == 8
    pd.testing.assert_frame_equal(comparable(tmp_path), comparable(serial_results))


def test_dask_tcp_scheduler_matches_serial_with_one_warning(
    serial_results: Path, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A plain ``tcp://`` scheduler (the TLS ones: tests/experiments/test_dask_security.py)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tcp://")
        with caplog.at_level(logging.WARNING, logger="skidnav.experiments.dask_backend"):
            outcome = run_experiment(
                parse_config(TINY_TOML), tmp_path, backend="dask", scheduler=address
            )
        assert outcome.executed == 8
    pd.testing.assert_frame_equal(comparable(tmp_path), comparable(serial_results))
    warnings = [r.getMessage() for r in caplog.records if r.name.endswith("dask_backend")]
    assert warnings == [
        f"Dask scheduler {address}: the link is unauthenticated and unencrypted (whoever "
        "reaches the scheduler can run code on its workers and read the runs); use a tls:// "
        "scheduler"
    ]


def _finished(out: Path) -> list[Path]:
    runs = out / "runs"
    return sorted(runs.glob("run-*.npz")) if runs.is_dir() else []


def _alive(process: psutil.Process) -> bool:
    try:
        return process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def _workers(pid: int) -> list[psutil.Process]:
    """Every process started by ``pid`` (pool workers, multiprocessing's resource tracker)."""
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def _command_line(child: psutil.Process) -> list[str]:
    """``child``'s command line; empty for one that has just ended (a zombie not yet reaped, or
    gone: short-lived children such as ``git`` for the provenance come and go)."""
    try:
        return child.cmdline()
    except (psutil.ZombieProcess, psutil.NoSuchProcess, psutil.AccessDenied):
        return []


def _started(process: subprocess.Popen[bytes], out: Path, backend: str) -> list[psutil.Process]:
    """Wait until the sweep is mid-way: two runs written and, on the process backend, both pool
    workers alive (the first run of each algorithm runs in the parent before the pool starts).
    Returns the processes the sweep started."""
    deadline = time.monotonic() + 180
    while process.poll() is None and time.monotonic() < deadline:
        children = _workers(process.pid)
        workers = [c for c in children if "spawn_main" in " ".join(_command_line(c))]
        if len(_finished(out)) >= 2 and (backend == "serial" or len(workers) == 2):
            return children
        time.sleep(0.02)
    raise AssertionError("the sweep did not reach the point where it should be killed")


LONGER_TOML = TINY_TOML.replace("seeds = 2", "seeds = 6")
"""The tiny config with 24 runs: a sweep long enough to be killed mid-way even when runs are
fast (the first two finish long before the last)."""
N_LONGER = 24


@pytest.fixture(scope="module")
def longer_serial_results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("longer-serial")
    run_experiment(parse_config(LONGER_TOML), out, backend="serial")
    return out


@pytest.mark.parametrize("backend", ["serial", "process"])
def test_sigkill_mid_sweep_then_resume(
    longer_serial_results: Path, tmp_path: Path, backend: str
) -> None:
    config = tmp_path / "longer.toml"
    config.write_text(LONGER_TOML)
    out = tmp_path / "out"
    args = cli_command(
        "run", str(config), "--out", str(out), "--backend", backend, "--jobs", "2", "--no-progress"
    )
    process = subprocess.Popen(
        args, env=cli_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    children = _started(process, out, backend)
    os.kill(process.pid, signal.SIGKILL)
    process.wait(timeout=30)
    done_before = {path.name: path.read_bytes() for path in _finished(out)}
    assert 2 <= len(done_before) < N_LONGER, "the sweep should have been killed mid-way"
    assert not (out / "episodes.parquet").exists()
    deadline = time.monotonic() + 10
    while any(_alive(child) for child in children) and time.monotonic() < deadline:
        time.sleep(0.1)
    survivors = [child for child in children if _alive(child)]
    commands = [" ".join(_command_line(child)) for child in survivors]
    for child in survivors:  # do not leave them behind when the check fails
        child.kill()
    assert not survivors, f"processes of the killed sweep still alive: {commands}"

    resumed = subprocess.run(args, env=cli_env(), capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{N_LONGER - len(done_before)} run now, {len(done_before)} already done" in (
        resumed.stdout
    )
    after = _finished(out)
    assert len(after) == N_LONGER
    for path in after:  # runs written before the kill were kept, not redone
        if path.name in done_before:
            assert path.read_bytes() == done_before[path.name]
    assert not list((out / "runs").glob(".*.tmp"))
    records = comparable(out)
    assert not records.duplicated(["run_id", "episode"]).any()
    pd.testing.assert_frame_equal(records, comparable(longer_serial_results))


WATCHED = """
import os, sys, time
from skidnav.experiments.workers import set_parent_death_signal, watch_parent
print(set_parent_death_signal(), flush=True)
watch_parent(os.getppid() + int(sys.argv[1]), interval=0.05)  # a parent it does not have
time.sleep(30)
"""


def test_worker_watchdog_ends_an_orphaned_worker() -> None:
    started = time.monotonic()
    result = subprocess.run(
        [sys.executable, "-c", WATCHED, "1"],
        env=cli_env(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == -signal.SIGTERM, result.stderr
    assert time.monotonic() - started < 25
    assert result.stdout.strip() == str(sys.platform.startswith("linux"))


def worker_pid(spec: object) -> int:
    """A trial that answers which process ran it (importable by spawned workers)."""
    time.sleep(0.05)  # long enough for both workers to take runs
    return os.getpid()


def test_batches_on_one_process_pool_run_in_the_same_workers() -> None:
    """A search passes one pool to every trial's batch: its workers start once, not per trial
    (so a search killed between trials leaves no freshly starting worker behind). The first run
    of each algorithm of a batch runs in this process (to compile once)."""
    from skidnav.experiments.runner import execute, process_pool
    from skidnav.experiments.runs import expand_runs

    runs = expand_runs(parse_config(TINY_TOML))
    here = {os.getpid()}
    with process_pool(2) as pool:
        first = set(execute(runs[:4], worker_pid, "process", 2, None, pool)) - here
        second = set(execute(runs[4:], worker_pid, "process", 2, None, pool)) - here
        stopped = execute(runs, worker_pid, "process", 2, None, pool)
        next(stopped)
        del stopped  # a pruned trial: pending runs cancelled, the pool stays usable
        again = set(execute(runs[:4], worker_pid, "process", 2, None, pool)) - here
    assert first and second <= first and again <= first
