"""Identical numbers on every backend, and resuming after SIGKILL loses and duplicates nothing."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pandas as pd
import pytest
from exp_support import TINY_TOML, cli_command, cli_env, comparable

from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment


def test_process_pool_matches_serial(serial_results: Path, tmp_path: Path) -> None:
    outcome = run_experiment(parse_config(TINY_TOML), tmp_path, backend="process", jobs=2)
    assert outcome.executed == 8
    pd.testing.assert_frame_equal(comparable(tmp_path), comparable(serial_results))


def test_dask_local_cluster_matches_serial(serial_results: Path, tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        outcome = run_experiment(
            parse_config(TINY_TOML), tmp_path, backend="dask", scheduler=cluster.scheduler_address
        )
        assert outcome.executed == 8
    pd.testing.assert_frame_equal(comparable(tmp_path), comparable(serial_results))


def _finished(out: Path) -> list[Path]:
    runs = out / "runs"
    return sorted(runs.glob("run-*.npz")) if runs.is_dir() else []


def test_sigkill_mid_sweep_then_resume(serial_results: Path, tmp_path: Path) -> None:
    config = tmp_path / "tiny.toml"
    config.write_text(TINY_TOML)
    out = tmp_path / "out"
    args = cli_command(
        "run", str(config), "--out", str(out), "--backend", "serial", "--no-progress"
    )
    process = subprocess.Popen(
        args, env=cli_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    deadline = time.monotonic() + 120
    while len(_finished(out)) < 2 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGKILL)
    process.wait(timeout=30)
    done_before = {path.name: path.read_bytes() for path in _finished(out)}
    assert 2 <= len(done_before) < 8, "the sweep should have been killed mid-way"
    assert not (out / "episodes.parquet").exists()

    resumed = subprocess.run(args, env=cli_env(), capture_output=True, text=True, timeout=180)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{8 - len(done_before)} run now, {len(done_before)} already done" in resumed.stdout
    after = _finished(out)
    assert len(after) == 8
    for path in after:  # runs written before the kill were kept, not redone
        if path.name in done_before:
            assert path.read_bytes() == done_before[path.name]
    assert not list((out / "runs").glob(".*.tmp"))
    records = comparable(out)
    assert not records.duplicated(["run_id", "episode"]).any()
    pd.testing.assert_frame_equal(records, comparable(serial_results))
