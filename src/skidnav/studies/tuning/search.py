"""Hyperparameter search with Optuna: one resumable study per agent, on tuning worlds that are
never evaluation worlds (docs/tuning.md).

* **Objective** (minimized): the interquartile mean (:func:`skidnav.statistics.intervals.iqm`) over
a trial's
  tuning runs (tuning maps × slip presets × ``seeds``) of the summary's ``convergence_episode``;
  a run that never converged counts at its censoring time, which is the penalty.
* **Pruning**: runs are submitted seed-major; whenever every run of the first k seeds has
  finished, the IQM over them is reported as step k and the pruner may stop the trial (its
  unfinished runs are cancelled). Steps follow seed order, not completion order, so pruning
  decisions, and with them the whole study, are the same on every backend.
* **Runs** go through :func:`skidnav.experiments.runner.execute` (serial, process pool, Dask); a
  run that raises ends the search in one line (:class:`~skidnav.errors.RunsFailedError`). The
  process backend's pool is one for the whole search
  (:func:`~skidnav.experiments.runner.process_pool`): its workers start once, not at every trial.
* **Seeds**: a tuning run's world and run streams are those of the evaluation grid with the
  spawn key prefixed by :data:`~skidnav.studies.tuning.runs.TUNE_STREAM`:
  ``SeedSequence(root_seed).spawn(3)[2]`` takes the place of the root, whose children 0 and 1
  are the evaluation world and run roots. Every trial of every agent meets the same tuning
  worlds (paired comparisons); :func:`~skidnav.studies.tuning.runs.check_separation` checks
  that no tuning map equals an evaluation map. The sampler of each trial is seeded from
  the root seed, the agent label and the number of trials finished before it, so a study
  interrupted and resumed proposes what an uninterrupted one would have.
* **Storage**: Optuna's ``JournalStorage`` on one JSON-lines file, ``DIR/journal.log``; study
  name ``<experiment name>/<agent label>``. Trials cut short by Ctrl-C are marked failed (and do
  not count); one left running by a SIGKILL is marked failed when the search starts again. The
  first trial of a study evaluates the config's own hyperparameters when they lie in the space.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import logging
import math
import time
from collections.abc import Callable, Generator, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import optuna
from optuna.trial import FrozenTrial, TrialState

from skidnav.errors import RunsFailedError, UserError
from skidnav.experiments.config import (
    AgentSpec,
    ExperimentConfig,
    config_to_dict,
)
from skidnav.experiments.dask_backend import dask_client
from skidnav.experiments.failures import RunFailure
from skidnav.experiments.lock import directory_lock
from skidnav.experiments.runner import (
    TrialFunction,
    _check_backend,
    default_jobs,
    process_pool,
)
from skidnav.experiments.runner import execute as execute_runs
from skidnav.experiments.store import TrialResult
from skidnav.files.atomic import remove_stale_temporaries, write_atomic
from skidnav.statistics.intervals import iqm
from skidnav.studies.tuning.config import ParamRange, TuneConfig, check_tuning, default_point
from skidnav.studies.tuning.optuna_setup import make_pruner, make_sampler, open_storage
from skidnav.studies.tuning.runs import check_separation, trial_config, tuning_runs
from skidnav.studies.tuning.tuned_file import write_tuned

if TYPE_CHECKING:
    from skidnav.experiments.trial import ExperimentRun

logger = logging.getLogger(__name__)

OBJECTIVE_KEY = "convergence_episode"
CONVERGED_KEY = "converged"
JOURNAL = "journal.log"
FINISHED = (TrialState.COMPLETE, TrialState.PRUNED)
TrialCallback = Callable[[str, FrozenTrial, int, int], None]
"""Called after every trial with (agent label, the trial, finished trials, target)."""


class TuneOutcome(NamedTuple):
    """What :func:`tune_experiment` did."""

    out_dir: Path
    tuned: Path
    executed: int
    finished: dict[str, int]
    wall_time: float


@dataclasses.dataclass(frozen=True)
class _Plan:
    """One agent's study: its spec, ranges, study name, fingerprint and default point."""

    agent: AgentSpec
    space: tuple[ParamRange, ...]
    name: str
    fingerprint: str
    defaults: dict[str, Any] | None


@dataclasses.dataclass(frozen=True)
class _Context:
    """What every trial of one invocation shares."""

    config: ExperimentConfig
    tune: TuneConfig
    trial: TrialFunction
    backend: str
    jobs: int
    client: Any
    executor: ProcessPoolExecutor | None
    """The process backend's pool, shared by every trial (its workers start once)."""


def _plans(config: ExperimentConfig, tune: TuneConfig) -> list[_Plan]:
    plans = []
    for agent in config.agents:
        space = tune.space(agent.label)
        if not space:
            continue
        template = dataclasses.replace(trial_config(config, tune, agent, {}, ""), description="")
        document = {"experiment": config_to_dict(template), **tune.study_settings(agent.label)}
        text = json.dumps(document, sort_keys=True, separators=(",", ":"))
        fingerprint = hashlib.sha256(text.encode()).hexdigest()
        name = f"{config.name}/{agent.label}"
        plans.append(_Plan(agent, space, name, fingerprint, default_point(agent, space)))
    return plans


def _study(storage: optuna.storages.JournalStorage, plan: _Plan, create: bool) -> Any:
    """``plan``'s study in ``storage`` (created when ``create``), or None when absent.

    Raises:
        UserError: the study was made from a different config.
    """
    names = {study.study_name for study in storage.get_all_studies()}
    if plan.name not in names and not create:
        return None
    study = optuna.create_study(
        storage=storage, study_name=plan.name, direction="minimize", load_if_exists=True
    )
    found = study.user_attrs.get("fingerprint")
    if found is None and not study.trials:
        study.set_user_attr("fingerprint", plan.fingerprint)
    elif found != plan.fingerprint:
        raise UserError(
            f"study {plan.name!r} in the journal was made from a different config or [tune] "
            "table (only trials and timeout_s may change); choose another --out"
        )
    return study


def finished_count(study: optuna.Study) -> int:
    """Trials that count towards the budget: complete and pruned ones."""
    return len(study.get_trials(deepcopy=False, states=FINISHED))


def _results(
    runs: Sequence[ExperimentRun], context: _Context
) -> Generator[TrialResult, None, None]:
    # Closing this generator drops the last reference to the runner's iterator, whose clean-up
    # (a process pool's shutdown with its pending runs cancelled, Dask futures released) then
    # runs at once. A run that raised fails its trial, and the search, in one line.
    outcomes = execute_runs(
        runs, context.trial, context.backend, context.jobs, context.client, context.executor
    )
    for outcome in outcomes:
        if isinstance(outcome, RunFailure):
            raise RunsFailedError(outcome.message)
        yield outcome


def evaluate(trial: optuna.Trial, runs: Sequence[ExperimentRun], context: _Context) -> float:
    """The objective of one trial over ``runs`` (seed-major); reports the IQM of each finished
    prefix of seeds and raises ``optuna.TrialPruned`` when the pruner says so."""
    n_seeds = max(spec.seed for spec in runs) + 1
    per_seed = [sum(spec.seed == seed for spec in runs) for seed in range(n_seeds)]
    order = {spec.run_id: position for position, spec in enumerate(runs)}
    done: dict[str, tuple[int, float, float]] = {}
    reported = 0
    with contextlib.closing(_results(runs, context)) as stream:
        for result in stream:
            seed = int(result.coordinates["seed"])
            summary = result.summary
            if math.isnan(summary[OBJECTIVE_KEY]):
                raise UserError(
                    f"{result.run_id}: the convergence episode is NaN (no oracle for "
                    f"{context.config.env_id}?), so there is nothing to minimize"
                )
            done[result.run_id] = (seed, summary[OBJECTIVE_KEY], summary[CONVERGED_KEY])
            while reported < n_seeds and _count(done, reported) == per_seed[reported]:
                reported += 1
                _report(trial, done, order, reported, reported < n_seeds)
    return iqm([value for _, value, _ in done.values()])


def _count(done: dict[str, tuple[int, float, float]], seed: int) -> int:
    return sum(1 for run_seed, _, _ in done.values() if run_seed == seed)


def _report(
    trial: optuna.Trial,
    done: dict[str, tuple[int, float, float]],
    order: dict[str, int],
    seeds: int,
    may_prune: bool,
) -> None:
    """Report the IQM over the first ``seeds`` seeds as step ``seeds`` (and keep the values)."""
    ready = sorted((order[run_id], v) for run_id, v in done.items() if v[0] < seeds)
    values = [value for _, (_, value, _) in ready]
    trial.report(iqm(values), seeds)
    trial.set_user_attr("seeds_done", seeds)
    trial.set_user_attr("convergence_episodes", values)
    trial.set_user_attr("converged_share", float(np.mean([c for _, (_, _, c) in ready])))
    if may_prune and trial.should_prune():
        raise optuna.TrialPruned(f"pruned after {seeds} seeds")


def run_one_trial(study: optuna.Study, plan: _Plan, context: _Context) -> FrozenTrial:
    """Ask ``study`` for a trial, evaluate it, tell the result (a trial interrupted by any
    exception, Ctrl-C included, is told failed before the exception goes on)."""
    finished = finished_count(study)
    study.sampler = make_sampler(context.tune, context.config.root_seed, plan.agent.label, finished)
    waiting = study.get_trials(deepcopy=False, states=(TrialState.WAITING,))
    if finished == 0 and plan.defaults is not None and not waiting:
        study.enqueue_trial(plan.defaults, user_attrs={"point": "the config's own params"})
    trial = study.ask()
    try:
        params = {param.name: param.suggest(trial) for param in plan.space}
        config = trial_config(
            context.config, context.tune, plan.agent, params, f"trial {trial.number}"
        )
        value = evaluate(trial, tuning_runs(config), context)
    except optuna.TrialPruned:
        return study.tell(trial, state=TrialState.PRUNED)
    except BaseException:
        study.tell(trial, state=TrialState.FAIL)
        raise
    return study.tell(trial, value)


def _fail_stale(study: optuna.Study) -> None:
    """Mark failed the trials a killed search left running (one search per journal at a time)."""
    for stale in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        logger.warning(
            "%s: trial %d was left running; marked failed", study.study_name, stale.number
        )
        study.tell(stale.number, state=TrialState.FAIL)


def _optimize(
    plans: Sequence[_Plan],
    studies: dict[str, optuna.Study],
    context: _Context,
    deadline: float | None,
    on_trial: TrialCallback | None,
) -> int:
    """Trials round-robin over the agents until each has ``trials`` finished ones or the
    deadline (``time.monotonic``) passes; returns the trials run."""
    target, executed = context.tune.trials, 0
    while True:
        pending = [plan for plan in plans if finished_count(studies[plan.name]) < target]
        if not pending:
            return executed
        for plan in pending:
            if deadline is not None and time.monotonic() >= deadline:
                logger.info("timeout_s reached; %d trials run", executed)
                return executed
            study = studies[plan.name]
            frozen = run_one_trial(study, plan, context)
            executed += 1
            if on_trial is not None:
                on_trial(plan.agent.label, frozen, finished_count(study), target)


def _needs_work(journal: Path, plans: Sequence[_Plan], target: int) -> bool:
    """Whether any study in ``journal`` (checked against its plan) lacks trials; creates
    nothing."""
    if not journal.exists():
        return True
    storage = open_storage(journal, repair=False)  # the directory is not locked yet
    studies = [_study(storage, plan, create=False) for plan in plans]
    return any(study is None or finished_count(study) < target for study in studies)


def _open_studies(
    out: Path, plans: Sequence[_Plan], tune: TuneConfig, source_text: str
) -> dict[str, optuna.Study]:
    """Create ``out`` and the journal (or reopen them); the studies by name, stale trials
    marked failed."""
    out.mkdir(parents=True, exist_ok=True)
    if source_text and not (out / "config.toml").exists():
        write_atomic(out / "config.toml", source_text.encode())
    storage = open_storage(out / JOURNAL)
    studies = {plan.name: _study(storage, plan, create=True) for plan in plans}
    for study in studies.values():
        study.pruner = make_pruner(tune)
        _fail_stale(study)
    return studies


def tune_experiment(
    config: ExperimentConfig,
    tune: TuneConfig,
    out_dir: Path | str,
    *,
    backend: str = "process",
    jobs: int | None = None,
    scheduler: str | None = None,
    trial: TrialFunction | None = None,
    source_text: str = "",
    config_path: Path | str | None = None,
    on_trial: TrialCallback | None = None,
) -> TuneOutcome:
    """Run (or resume) the search of ``tune`` for every agent with a space; write ``tuned.toml``.

    Arguments as :func:`skidnav.experiments.runner.run_experiment`; ``on_trial`` is called after
    every trial. Everything is checked, and a Dask scheduler reached, before ``out_dir`` is made.
    ``tuned.toml`` is (re)written at the end, also when interrupted.
    """
    started = time.monotonic()
    jobs = default_jobs() if jobs is None else jobs
    _check_backend(backend, jobs, scheduler)
    if trial is None:
        from skidnav.experiments.trial import default_trial

        check_tuning(config, tune, config_path)
        trial = default_trial()
    compared = check_separation(config, tune)
    plans = _plans(config, tune)
    out = Path(out_dir)
    with contextlib.ExitStack() as stack:
        client = None
        if backend == "dask" and _needs_work(out / JOURNAL, plans, tune.trials):
            client = stack.enter_context(dask_client(jobs, scheduler))
        stack.enter_context(directory_lock(out))  # one search per directory
        remove_stale_temporaries(out)
        studies = _open_studies(out, plans, tune, source_text)
        executor = None
        if backend == "process" and jobs > 1:
            executor = stack.enter_context(process_pool(jobs))
        context = _Context(config, tune, trial, backend, jobs, client, executor)
        deadline = None if tune.timeout_s is None else started + tune.timeout_s
        try:
            executed = _optimize(plans, studies, context, deadline, on_trial)
        finally:
            by_label = {plan.agent.label: studies[plan.name] for plan in plans}
            tuned = write_tuned(out, out / JOURNAL, config, tune, by_label, compared)
    finished = {label: finished_count(study) for label, study in by_label.items()}
    return TuneOutcome(out, tuned, executed, finished, time.monotonic() - started)
