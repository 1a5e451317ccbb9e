"""Run an experiment grid on one of three backends, resumably.

Backends (all give identical numbers, since a run is a pure function of its spec and seeds):

* ``serial``: one run after the other in this process.
* ``process``: a pool of ``jobs`` local worker processes (``spawn`` start method); the first run
  of each algorithm runs in this process first, to compile and cache the kernels once.
* ``dask``: a ``dask.distributed`` Client on the scheduler at ``scheduler``; without an address,
  a local cluster of ``jobs`` worker processes on 127.0.0.1.

Workers only compute; this process writes every finished run atomically as it arrives
(:class:`~skidnav.experiments.store.ResultStore`). Started again on the same directory, the
runner skips the runs already written, so a sweep killed by Ctrl-C or SIGKILL resumes with none
lost and none duplicated. At the end the tidy tables and ``metadata.json`` are (re)written.
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing
import os
import signal
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, NamedTuple

from tqdm import tqdm

from skidnav._jit import jit_disabled
from skidnav.errors import UserError
from skidnav.experiments.config import ExperimentConfig, config_to_dict
from skidnav.experiments.provenance import git_commit, package_versions
from skidnav.experiments.runs import RunSpec, expand_runs
from skidnav.experiments.store import ResultStore, TrialResult

logger = logging.getLogger(__name__)

BACKENDS = ("serial", "process", "dask")
TrialFunction = Callable[[RunSpec], TrialResult]


class RunOutcome(NamedTuple):
    """What :func:`run_experiment` did."""

    out_dir: Path
    n_runs: int
    skipped: int
    executed: int
    wall_time: float


def _ignore_sigint() -> None:
    """Worker initializer: Ctrl-C is handled by the parent, which cancels the pool."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _serial(runs: Sequence[RunSpec], trial: TrialFunction) -> Iterator[TrialResult]:
    for spec in runs:
        yield trial(spec)


def _process(runs: Sequence[RunSpec], trial: TrialFunction, jobs: int) -> Iterator[TrialResult]:
    if not runs:
        return
    jobs = min(jobs, len(runs))
    context = multiprocessing.get_context("spawn")
    executor = ProcessPoolExecutor(jobs, mp_context=context, initializer=_ignore_sigint)
    try:
        futures = [executor.submit(trial, spec) for spec in runs]
        for future in as_completed(futures):
            yield future.result()
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def _dask(
    runs: Sequence[RunSpec], trial: TrialFunction, jobs: int, scheduler: str | None
) -> Iterator[TrialResult]:
    from distributed import Client, LocalCluster
    from distributed import as_completed as dask_completed

    cluster = None
    if scheduler is None:
        cluster = LocalCluster(
            n_workers=jobs,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
        )
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout="15s")
        except OSError as error:
            raise UserError(f"cannot connect to Dask scheduler {scheduler!r}: {error}") from None
    try:
        keys = [f"skidnav-{spec.config.fingerprint()[:12]}-{spec.run_id}" for spec in runs]
        futures = client.map(trial, runs, key=keys, pure=False)
        for future in dask_completed(futures):
            yield future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def warm_up_first(runs: Sequence[RunSpec]) -> tuple[list[RunSpec], list[RunSpec]]:
    """(first run of each algorithm, the others). The process backend runs the first ones here,
    so the compiled kernels are built once and cached on disk before the workers start, instead
    of being compiled by every worker at the same time."""
    seen: set[str] = set()
    first: list[RunSpec] = []
    rest: list[RunSpec] = []
    for spec in runs:
        (rest if spec.agent.name in seen else first).append(spec)
        seen.add(spec.agent.name)
    return first, rest


def execute(
    runs: Sequence[RunSpec],
    trial: TrialFunction,
    backend: str,
    jobs: int,
    scheduler: str | None = None,
) -> Iterator[TrialResult]:
    """Results of ``runs`` in completion order on ``backend``."""
    if not runs:
        return iter(())
    if backend == "serial" or (backend == "process" and min(jobs, len(runs)) == 1):
        return _serial(runs, trial)
    if backend == "process":
        first, rest = warm_up_first(runs)
        return itertools.chain(_serial(first, trial), _process(rest, trial, jobs))
    return _dask(runs, trial, jobs, scheduler)


def _check_backend(backend: str, jobs: int, scheduler: str | None) -> None:
    if backend not in BACKENDS:
        raise UserError(f"unknown backend {backend!r}; expected one of {', '.join(BACKENDS)}")
    if jobs < 1:
        raise UserError(f"--jobs must be >= 1, got {jobs}")
    if scheduler is not None and backend != "dask":
        raise UserError("--scheduler needs --backend dask")


def default_jobs() -> int:
    """Local cores available to this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def run_experiment(
    config: ExperimentConfig,
    out_dir: Path | str,
    *,
    backend: str = "process",
    jobs: int | None = None,
    scheduler: str | None = None,
    trial: TrialFunction | None = None,
    source_text: str = "",
    progress: bool = False,
) -> RunOutcome:
    """Run (or resume) every run of ``config`` into ``out_dir``.

    Args:
        config: the experiment.
        out_dir: results directory (created, or reopened to resume the same config).
        backend: one of :data:`BACKENDS`.
        jobs: worker processes (default: local cores).
        scheduler: Dask scheduler address (``tcp://host:port``), only with ``backend="dask"``.
        trial: the run function (default :func:`skidnav.experiments.trial.run_trial`); it must be
            importable by worker processes.
        source_text: the config file's text, saved as ``config.toml``.
        progress: show a progress bar with ETA on stderr.
    """
    jobs = default_jobs() if jobs is None else jobs
    _check_backend(backend, jobs, scheduler)
    if trial is None:
        from skidnav.experiments.trial import check_config, run_trial

        check_config(config)
        trial = run_trial
    started = time.time()
    store = ResultStore.open(out_dir, config, source_text)
    runs = expand_runs(config)
    done = store.finished()
    pending = [spec for spec in runs if spec.run_id not in done]
    logger.info("%d runs, %d already done, %d to run", len(runs), len(done), len(pending))
    with tqdm(
        total=len(runs),
        initial=len(runs) - len(pending),
        file=sys.stderr,
        unit="run",
        disable=not progress,
        dynamic_ncols=True,
        desc=config.name,
    ) as bar:
        for result in execute(pending, trial, backend, jobs, scheduler):
            store.write_run(result)
            bar.update(1)
    store.consolidate()
    wall_time = time.time() - started
    store.write_metadata(_metadata(config, runs, backend, jobs, scheduler, started, wall_time))
    return RunOutcome(store.root, len(runs), len(runs) - len(pending), len(pending), wall_time)


def _metadata(
    config: ExperimentConfig,
    runs: Sequence[RunSpec],
    backend: str,
    jobs: int,
    scheduler: str | None,
    started: float,
    wall_time: float,
) -> dict[str, Any]:
    return {
        "config": config_to_dict(config),
        "fingerprint": config.fingerprint(),
        "versions": package_versions(),
        "git_commit": git_commit(),
        "numba_jit_disabled": jit_disabled(),
        "backend": backend,
        "jobs": jobs,
        "scheduler": scheduler,
        "last_session": {
            "started": datetime.fromtimestamp(started, UTC).isoformat(),
            "wall_time_s": wall_time,
        },
        "seeds": {
            "root_seed": config.root_seed,
            "scheme": "SeedSequence(root).spawn(2) -> (world root, run root); "
            "world root.spawn(n_worlds)[world index], run root.spawn(n_runs)[run index]",
            "runs": [
                {
                    "run_id": spec.run_id,
                    "agent": spec.agent.label,
                    "map": spec.map.label,
                    "preset": spec.preset,
                    "seed": spec.seed,
                    "world_seed": {
                        "entropy": spec.world_seed.entropy,
                        "spawn_key": list(spec.world_seed.spawn_key),
                    },
                    "run_seed": {
                        "entropy": spec.run_seed.entropy,
                        "spawn_key": list(spec.run_seed.spawn_key),
                    },
                }
                for spec in runs
            ],
        },
    }
