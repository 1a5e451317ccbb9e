"""Writing ``tuned.toml``: the best hyperparameters of a search as an experiment config.

``tuned.toml`` is the config the search was given (its evaluation maps, presets, seeds and
environment, map files by absolute path) with every tuned agent's best hyperparameters merged over
its own params, so ``skidnav run DIR/tuned.toml`` evaluates the tuned agents as they are; comments
give the objective values, trial counts, searched ranges, tuning worlds and the code version.
Agents without a ``[tune.space]`` table keep their params. It is written atomically.
"""

from __future__ import annotations

from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import optuna
from optuna.trial import TrialState

from skidnav.experiments.config import (
    DEFAULT_ENV_ID,
    AgentSpec,
    ExperimentConfig,
    MapSpec,
    config_to_dict,
    freeze_params,
)
from skidnav.experiments.configfile import EXPERIMENT_KEYS
from skidnav.experiments.provenance import code_version
from skidnav.files.atomic import write_atomic
from skidnav.files.configtables import toml_key, toml_value
from skidnav.studies.tuning.config import TuneConfig

TUNED = "tuned.toml"


def _comment(lines: Sequence[str]) -> list[str]:
    return [f"# {line}".rstrip() for line in lines]


def _map_lines(spec: MapSpec) -> list[str]:
    """A ``[[maps]]`` table's body (a map file by its absolute path)."""
    values: dict[str, Any] = {"label": spec.label, "kind": spec.kind, "file": spec.file}
    values["options"] = dict(spec.options)
    return [f"{key} = {toml_value(value)}" for key, value in values.items() if value]


def tuned_toml(
    config: ExperimentConfig,
    agents: Sequence[tuple[AgentSpec, Sequence[str]]],
    header: Sequence[str],
) -> str:
    """The text of ``tuned.toml``: an experiment config equal to ``config`` (its evaluation
    maps, presets, seeds) but with ``agents``, each preceded by its comment lines, and the
    ``header`` comment lines on top. ``skidnav run`` accepts it as it is."""
    experiment = config_to_dict(config)
    experiment["name"] = f"{config.name}-tuned"
    lines = [*_comment(header), "", "[experiment]"]
    lines += [
        f"{key} = {toml_value(value)}"
        for key, value in experiment.items()
        if key in EXPERIMENT_KEYS and value is not None
    ]
    if config.env_options:
        lines += ["", "[env]", *(f"{toml_key(k)} = {toml_value(v)}" for k, v in config.env_options)]
    if config.env_id == DEFAULT_ENV_ID:
        for spec in config.maps:
            lines += ["", "[[maps]]", *_map_lines(spec)]
    for agent, comments in agents:
        lines += ["", *_comment(comments), "[[agents]]"]
        lines += [f"name = {toml_value(agent.name)}", f"label = {toml_value(agent.label)}"]
        lines.append(f"params = {toml_value(agent.params_dict())}")
    return "\n".join(lines) + "\n"


def _tuned_agent(
    agent: AgentSpec, tune: TuneConfig, study: optuna.Study
) -> tuple[AgentSpec, list[str]]:
    """The agent with its best hyperparameters, and the comment lines describing the search."""
    trials = study.get_trials(deepcopy=False)
    count = {state: sum(t.state == state for t in trials) for state in TrialState}
    finished = count[TrialState.COMPLETE] + count[TrialState.PRUNED]
    summary = (
        f"{finished} finished trials ({count[TrialState.COMPLETE]} complete, "
        f"{count[TrialState.PRUNED]} pruned; {count[TrialState.FAIL]} failed)"
    )
    searched = "  searched: " + "; ".join(param.describe() for param in tune.space(agent.label))
    label = agent.label
    if not count[TrialState.COMPLETE]:
        return agent, [f"{label}: no complete trial yet ({summary}): its own params", searched]
    best = study.best_trial
    share = best.user_attrs.get("converged_share", float("nan"))
    lines = [
        f"{label}: best trial {best.number}, objective {best.value:.6g} ({share:.0%} of its runs "
        "converged),",
        f"  of {summary}",
    ]
    own = [t for t in trials if t.state == TrialState.COMPLETE and "point" in t.user_attrs]
    if own:
        lines.append(f"  the config's own params (trial {own[0].number}): {own[0].value:.6g}")
    params = freeze_params({**agent.params_dict(), **best.params})
    return AgentSpec(agent.name, label, params), [*lines, searched]


def _header(
    out: Path, journal: Path, config: ExperimentConfig, tune: TuneConfig, compared: int
) -> list[str]:
    """The header comments: code, journal, objective, tuning worlds, budget, how to evaluate."""
    code = code_version()
    commit = str(code.get("commit") or "unknown")[:12] + (" dirty" if code.get("dirty") else "")
    maps = ", ".join(spec.label for spec in tune.maps)
    separation = (
        f"checked: no tuning map equals any of the {compared} evaluation maps below."
        if compared
        else "the environment brings its own world: tuning and evaluation share it."
    )
    return [
        f"Tuned hyperparameters, written by `skidnav tune` at {datetime.now(UTC):%Y-%m-%d %H:%M}"
        " UTC",
        f"  (skidnav {code.get('version')}, commit {commit}).",
        f"Journal: {journal} (Optuna JournalStorage); `skidnav tune CONFIG --out {out}`",
        "  resumes it.",
        "Objective (minimized): IQM over a trial's tuning runs of the convergence episode; runs",
        "  that never converged count at their censoring time.",
        f"Tuning worlds: maps {maps} x presets {', '.join(config.presets)} x {tune.seeds} seeds,",
        f"  streams of SeedSequence({config.root_seed}).spawn(3)[2] (evaluation: children 0, 1);",
        f"  {separation}",
        f"Budget: {tune.trials} trials per agent, sampler {tune.sampler}, pruner {tune.pruner}.",
        f"Evaluate: skidnav run {out / TUNED} --out runs/{config.name}-tuned",
        "  (the evaluation maps, presets and seeds of the config), or copy the [[agents]] tables.",
    ]


def write_tuned(
    out: Path,
    journal: Path,
    config: ExperimentConfig,
    tune: TuneConfig,
    studies: dict[str, optuna.Study],
    compared: int,
) -> Path:
    """Write ``out/tuned.toml`` atomically from the ``studies`` (by agent label) kept in
    ``journal``; ``compared``: evaluation maps
    :func:`~skidnav.studies.tuning.runs.check_separation`
    compared the tuning maps with. Returns the path."""
    agents: list[tuple[AgentSpec, Sequence[str]]] = []
    for agent in config.agents:
        study = studies.get(agent.label)
        if study is None:
            agents.append((agent, [f"{agent.label}: not tuned (no [tune.space] table)"]))
        else:
            agents.append(_tuned_agent(agent, tune, study))
    header = _header(out, journal, config, tune, compared)
    path = out / TUNED
    write_atomic(path, tuned_toml(config, agents, header).encode())
    return path
