"""Run an experiment grid on one of three backends, resumably.

Backends (all give identical numbers, since a run is a pure function of its spec and seeds):

* ``serial``: one run after the other in this process.
* ``process``: a pool of ``jobs`` local worker processes (``spawn`` start method); the first run
  of each algorithm runs in this process first, to compile and cache the kernels once. The
  workers end when this process dies, even by SIGKILL (:mod:`skidnav.experiments.workers`).
* ``dask``: a ``dask.distributed`` Client on the scheduler at ``scheduler``; without an address,
  a local cluster of ``jobs`` worker processes on 127.0.0.1, reachable only with its own TLS
  credentials and serving no HTTP (:mod:`skidnav.experiments.dask_backend`). The client
  connects before the results directory is created, so a scheduler that cannot be reached
  leaves nothing behind. Dask is the ``distributed`` extra: without it the backend is refused
  in one line.

Local worker processes import nothing from the current directory
(:func:`skidnav.childprocess.safe_path_children`).

Workers only compute; this process writes every finished run atomically as it arrives
(:class:`~skidnav.experiments.store.ResultStore`), with the version of the code that produced it,
holding the directory's lock (:func:`~skidnav.experiments.store.directory_lock`): a second run on
the same directory is refused while the first lives.
Started again on the same directory, the runner skips the runs already written, so a sweep killed
by Ctrl-C or SIGKILL resumes with none lost and none duplicated; finished runs produced by other
code are reused with a warning (:mod:`skidnav.experiments.sessions`). At the end the tidy tables
and ``metadata.json`` (with the list of sessions) are (re)written. A run that raises is logged in
one line and the others go on; the sweep then ends in
:class:`~skidnav.errors.RunsFailedError`, its finished runs kept for a resume
(:mod:`skidnav.experiments.failures`).

The grid is an :class:`~skidnav.experiments.config.ExperimentConfig` trained by
:func:`skidnav.experiments.trial.run_trial`, or any other :class:`~skidnav.experiments.runs.Grid`
with its own trial function and :class:`~skidnav.experiments.store.RunLayout` (the
hardware-in-the-loop study, :mod:`skidnav.studies.hardware.study`): the same expansion, seeds,
store, lock, resume and metadata for both.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import logging
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed, wait
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, NamedTuple

from tqdm import tqdm

from skidnav._jit import jit_disabled
from skidnav.childprocess import safe_path_children
from skidnav.errors import Interrupted, RunsFailedError, UserError
from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.dask_backend import dask_client, distributed_module
from skidnav.experiments.failures import RunFailure, attempt, failed_runs_message
from skidnav.experiments.lock import directory_lock
from skidnav.experiments.provenance import CODE_KEYS, code_version, package_versions
from skidnav.experiments.runs import Grid, RunSpec, expand_runs, select_runs
from skidnav.experiments.sessions import mixed_code_message, other_code, update_sessions
from skidnav.experiments.store import EXPERIMENT_LAYOUT, ResultStore, RunLayout, TrialResult
from skidnav.experiments.workers import init_worker
from skidnav.extras import require

logger = logging.getLogger(__name__)

BACKENDS = ("serial", "process", "dask")
TrialFunction = Callable[[RunSpec[Any]], TrialResult]
"""One run of the grid: its spec in, its results out (a pure function of the spec for an
experiment)."""
RunObserver = Callable[[TrialResult], None]
"""Told of each finished run in the runner's process (:func:`run_experiment`'s ``on_run``)."""


class RunOutcome(NamedTuple):
    """What :func:`run_experiment` did."""

    out_dir: Path
    n_runs: int
    skipped: int
    executed: int
    wall_time: float
    grid_runs: int
    """Runs of the whole grid (``n_runs`` of them were asked for)."""


Outcome = TrialResult | RunFailure
"""What a run gives the runner: its results, or the one line of its failure."""


def _serial(runs: Sequence[RunSpec[Any]], trial: TrialFunction) -> Iterator[Outcome]:
    for spec in runs:
        yield attempt(spec, functools.partial(trial, spec))


@contextlib.contextmanager
def process_pool(jobs: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of ``jobs`` local worker processes (``spawn``, without the current directory on
    their path, ending with this process: :mod:`skidnav.experiments.workers`), shut down with its
    pending runs cancelled on exit. A caller that executes many batches of runs (a search's
    trials) passes it to :func:`execute` for each, so its workers start once."""
    context = multiprocessing.get_context("spawn")
    with safe_path_children():
        executor = ProcessPoolExecutor(
            jobs, mp_context=context, initializer=init_worker, initargs=(os.getpid(),)
        )
        try:
            yield executor
        except KeyboardInterrupt:
            stop_workers(executor)
            executor.shutdown(wait=True)  # the broken pool fails every future at once
            raise
        except BaseException:
            executor.shutdown(wait=True, cancel_futures=True)
            raise
        executor.shutdown(wait=True, cancel_futures=True)


def stop_workers(executor: ProcessPoolExecutor) -> None:
    """End the workers of ``executor`` now (SIGTERM), their runs unfinished: on Ctrl-C the
    sweep stops at once instead of awaiting the runs in progress (a run is written only by this
    process, once finished, so a resume starts them again). The pool is then broken and fails
    every future not done; none may be cancelled meanwhile (Python 3.11's executor then dies on
    setting the cancelled future's exception, and whoever waits for the others waits forever)."""
    for process in list(executor._processes.values()):  # no public way before Python 3.14
        process.terminate()


def _submitted(
    executor: ProcessPoolExecutor, runs: Sequence[RunSpec[Any]], trial: TrialFunction
) -> Iterator[Outcome]:
    """Outcomes of ``runs`` on ``executor`` as they finish; when the caller stops early, the
    pending runs are cancelled and the running ones awaited, so the pool is free again."""
    futures = {executor.submit(trial, spec): spec for spec in runs}
    interrupted = False
    try:
        for future in as_completed(futures):
            yield attempt(futures[future], future.result)
    except KeyboardInterrupt:
        interrupted = True
        stop_workers(executor)  # not awaited: their runs are lost, the finished ones written
        raise
    finally:
        if not interrupted:  # after stop_workers the broken pool fails them all, uncancelled
            for future in futures:
                future.cancel()
        wait(futures)


def _process(
    runs: Sequence[RunSpec[Any]],
    trial: TrialFunction,
    jobs: int,
    executor: ProcessPoolExecutor | None = None,
) -> Iterator[Outcome]:
    if not runs:
        return
    if executor is not None:
        yield from _submitted(executor, runs, trial)
        return
    with process_pool(min(jobs, len(runs))) as own:
        yield from _submitted(own, runs, trial)


def _dask(runs: Sequence[RunSpec[Any]], trial: TrialFunction, client: Any) -> Iterator[Outcome]:
    keys = [f"skidnav-{spec.config.fingerprint()[:12]}-{spec.run_id}" for spec in runs]
    futures = client.map(trial, runs, key=keys, pure=False)
    by_key = dict(zip(keys, runs, strict=True))
    for future in distributed_module().as_completed(futures):
        yield attempt(by_key[future.key], future.result)


def warm_up_first(runs: Sequence[RunSpec[Any]]) -> tuple[list[RunSpec[Any]], list[RunSpec[Any]]]:
    """(first run of each algorithm, the others). The process backend runs the first ones here,
    so the compiled kernels are built once and cached on disk before the workers start, instead
    of being compiled by every worker at the same time."""
    seen: set[str] = set()
    first: list[RunSpec[Any]] = []
    rest: list[RunSpec[Any]] = []
    for spec in runs:
        (rest if spec.agent.name in seen else first).append(spec)
        seen.add(spec.agent.name)
    return first, rest


def execute(
    runs: Sequence[RunSpec[Any]],
    trial: TrialFunction,
    backend: str,
    jobs: int,
    client: Any = None,
    executor: ProcessPoolExecutor | None = None,
) -> Iterator[Outcome]:
    """Results of ``runs`` in completion order on ``backend`` (``dask`` needs the ``client`` of
    :func:`dask_client`; ``process`` uses ``executor``, a :func:`process_pool`, when given, or a
    pool of its own); a run that raised gives its :class:`RunFailure` instead
    (:mod:`skidnav.experiments.failures`)."""
    if not runs:
        return iter(())
    if backend == "serial" or (backend == "process" and min(jobs, len(runs)) == 1):
        return _serial(runs, trial)
    if backend == "process":
        first, rest = warm_up_first(runs)
        return itertools.chain(_serial(first, trial), _process(rest, trial, jobs, executor))
    assert client is not None, "the dask backend needs a client"
    return _dask(runs, trial, client)


def _check_backend(backend: str, jobs: int, scheduler: str | None) -> None:
    if backend not in BACKENDS:
        raise UserError(f"unknown backend {backend!r}; expected one of {', '.join(BACKENDS)}")
    if jobs < 1:
        raise UserError(f"--jobs must be >= 1, got {jobs}")
    if scheduler is not None and backend != "dask":
        raise UserError("--scheduler needs --backend dask")
    if backend == "dask":
        require("distributed", "--backend dask")


def default_jobs() -> int:
    """Local cores available to this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def run_experiment(
    config: Grid,
    out_dir: Path | str,
    *,
    backend: str = "process",
    jobs: int | None = None,
    scheduler: str | None = None,
    trial: TrialFunction | None = None,
    source_text: str = "",
    config_path: Path | str | None = None,
    progress: bool = False,
    layout: RunLayout = EXPERIMENT_LAYOUT,
    on_run: RunObserver | None = None,
    only: str | None = None,
) -> RunOutcome:
    """Run (or resume) every run of ``config`` into ``out_dir``, or those ``only`` names.

    Args:
        config: the experiment (or another grid, with its ``trial`` and ``layout``).
        out_dir: results directory (created, or reopened to resume the same config).
        backend: one of :data:`BACKENDS`.
        jobs: worker processes (default: local cores).
        scheduler: Dask scheduler address (``tls://host:port``, with the TLS credentials of
            Dask's config, or ``tcp://host:port``, with a warning:
            :mod:`skidnav.experiments.dask_backend`), only with ``backend="dask"``.
        trial: the run function (default, for an experiment:
            :func:`skidnav.experiments.trial.run_trial`); with ``backend="process"`` or
            ``"dask"`` it must be importable by worker processes.
        source_text: the config file's text, saved as ``config.toml``.
        config_path: the config file, named in the errors of its agents, maps and env options.
        progress: show a progress bar with ETA on stderr.
        layout: what the run files hold and how the grid is saved (:class:`RunLayout`).
        on_run: called in this process with every finished run of the grid: those already in
            ``out_dir`` (a resume) first, then each new one once it is written (e.g. the
            TensorBoard log, :mod:`skidnav.experiments.tensorboard_log`).
        only: run only these runs of the grid (:func:`~skidnav.experiments.runs.select_runs`:
            ``"0:60,120:180"``), with the streams they have in the whole grid; the other runs
            can be run into the same ``out_dir`` later, or are missing from its results.

    Raises:
        UserError: bad backend options, or ``out_dir`` holds other results or is in use.
        RunsFailedError: at the end, when runs raised (each was logged in one line); the runs
            that finished are written, for a resume (:mod:`skidnav.experiments.failures`).
        Interrupted: a KeyboardInterrupt (Ctrl-C; SIGTERM in the ``skidnav`` command) with how
            many runs were written until then, which stay, for a resume; the workers are
            stopped at once (:func:`stop_workers`).
    """
    jobs = default_jobs() if jobs is None else jobs
    _check_backend(backend, jobs, scheduler)
    if trial is None:
        trial = _default_trial(config, config_path)
    started = time.time()
    grid = expand_runs(config)
    runs = grid if only is None else select_runs(grid, only)
    ResultStore(out_dir, layout).check(config)
    with contextlib.ExitStack() as locked:
        with contextlib.ExitStack() as stack:
            client = None
            unfinished = {spec.run_id for spec in runs} - ResultStore(out_dir, layout).finished()
            if backend == "dask" and unfinished:
                client = stack.enter_context(dask_client(jobs, scheduler))
            locked.enter_context(directory_lock(out_dir))  # held until the metadata is written
            store = ResultStore.open(out_dir, config, source_text, layout)
            session = _session(started, backend, jobs, scheduler, only)
            records = _resume_records(store, session)
            pending = [spec for spec in runs if spec.run_id not in records]
            if on_run is not None:
                for finished in store.iter_runs(records):
                    on_run(finished)
            execution = (trial, backend, jobs, client)
            try:
                done = len(runs) - len(pending)
                failures = _run_pending(
                    store, config, pending, records, done, session, execution, progress, on_run
                )
            except KeyboardInterrupt:
                written = sum(spec.run_id in records for spec in runs)
                raise Interrupted(written, len(runs), str(store.root)) from None
        if failures:
            raise RunsFailedError(failed_runs_message(failures, len(runs), store.root))
        store.consolidate()
        wall_time = time.time() - started
        session.update(wall_time_s=wall_time, completed=True)
        sessions = update_sessions(_previous_sessions(store.metadata()), records, session)
        store.write_metadata(_metadata(store, config, grid, session, sessions))
    return RunOutcome(
        store.root, len(runs), len(runs) - len(pending), len(pending), wall_time, len(grid)
    )


def _default_trial(config: Grid, config_path: Path | str | None) -> TrialFunction:
    """:func:`skidnav.experiments.trial.run_trial`, after checking the experiment ``config``
    (only an :class:`ExperimentConfig` has a default trial)."""
    from skidnav.experiments.config_checks import check_config
    from skidnav.experiments.trial import default_trial

    if not isinstance(config, ExperimentConfig):
        raise TypeError(f"a {type(config).__name__} grid needs its own trial function")
    check_config(config, config_path)
    return default_trial()


def _run_pending(
    store: ResultStore,
    config: Grid,
    pending: list[RunSpec[Any]],
    records: dict[str, dict[str, Any]],
    done: int,
    session: dict[str, Any],
    execution: tuple[TrialFunction, str, int, Any],
    progress: bool,
    on_run: RunObserver | None = None,
) -> list[RunFailure]:
    """Run ``pending`` on ``execution`` (trial, backend, jobs, Dask client), writing each result
    as it arrives (then handing it to ``on_run``) and noting its code record in ``records``
    (which holds every finished run of the directory, ``done`` of them among the runs asked
    for); returns the runs that failed (each logged as it failed)."""
    total = len(pending) + done
    logger.info("%d runs, %d already done, %d to run", total, done, len(pending))
    stamp = {key: session[key] for key in CODE_KEYS} | {"session": session["started"]}
    failures: list[RunFailure] = []
    with _progress(config, total, done, progress) as bar:
        for outcome in execute(pending, *execution):
            if isinstance(outcome, RunFailure):
                logger.error("%s", outcome.message)
                failures.append(outcome)
            else:
                store.write_run(outcome, stamp)
                records[outcome.run_id] = stamp
                if on_run is not None:
                    on_run(outcome)
            bar.update(1)
    return failures


def _progress(config: Grid, total: int, done: int, show: bool) -> tqdm[Any]:
    return tqdm(
        total=total,
        initial=done,
        file=sys.stderr,
        unit="run",
        disable=not show,
        dynamic_ncols=True,
        desc=config.name,
    )


def _session(
    started: float, backend: str, jobs: int, scheduler: str | None, only: str | None
) -> dict[str, Any]:
    """This session's entry of ``metadata.json`` (completed at the end of the run); ``runs``
    is its selection of the grid's runs (``--runs``), None for all of them."""
    return {
        "started": datetime.fromtimestamp(started, UTC).isoformat(),
        **code_version(),
        "backend": backend,
        "jobs": jobs,
        "scheduler": scheduler,
        "runs": only,
        "completed": False,
    }


def _resume_records(store: ResultStore, session: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The code record of every finished run; warns (and notes in ``session``) how many came
    from other code than this session's."""
    records = {run_id: store.run_code(run_id) for run_id in sorted(store.finished())}
    foreign = other_code(records, session)
    session["runs_from_other_code"] = len(foreign)
    if foreign:
        message = mixed_code_message(records, foreign, session)
        logger.warning("%s: %s", store.root, message)
        session["warning"] = message
    return records


def _previous_sessions(metadata: dict[str, Any]) -> list[dict[str, Any]]:
    """The session list of an existing ``metadata.json`` (older files kept only the last one)."""
    sessions = metadata.get("sessions")
    if isinstance(sessions, list):
        return [entry for entry in sessions if isinstance(entry, dict)]
    last = metadata.get("last_session")
    if isinstance(last, dict):
        return [{**last, "commit": metadata.get("git_commit")}]
    return []


def _metadata(
    store: ResultStore,
    config: Grid,
    runs: Sequence[RunSpec[Any]],
    session: dict[str, Any],
    sessions: list[dict[str, Any]],
) -> dict[str, Any]:
    return {
        "config": store.layout.to_dict(config),
        "fingerprint": config.fingerprint(),
        "versions": package_versions(),
        "git_commit": session["commit"],
        "git_dirty": session["dirty"],
        "numba_jit_disabled": jit_disabled(),
        "backend": session["backend"],
        "jobs": session["jobs"],
        "scheduler": session["scheduler"],
        "sessions": sessions,
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
