"""``skidnav tune``: a tiny study runs and writes tuned.toml, resumes without redoing trials,
prunes, keeps tuning worlds apart from evaluation worlds, and refuses bad configs in one line."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import optuna
import pytest
from optuna.trial import TrialState

from skidnav.cli import main
from skidnav.errors import RunsFailedError, UserError
from skidnav.experiments.config import config_to_dict
from skidnav.experiments.configfile import load_config, parse_config
from skidnav.experiments.runs import RunSpec, expand_runs
from skidnav.experiments.store import TrialResult
from skidnav.experiments.trial import measure_trial
from skidnav.files.configtables import toml_key, toml_value
from skidnav.statistics.intervals import iqm
from skidnav.studies.tuning.config import ParamRange, TuneConfig, load_tune_config
from skidnav.studies.tuning.optuna_setup import open_storage
from skidnav.studies.tuning.runs import (
    TUNE_STREAM,
    check_separation,
    run_map,
    trial_config,
    tuning_runs,
)
from skidnav.studies.tuning.search import JOURNAL, tune_experiment

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

TINY_TUNE = """
[experiment]
name = "tiny-tune"
episodes = 14
max_steps = 60
seeds = 2
root_seed = 11
presets = ["rough"]

[[maps]]
kind = "free"

[[agents]]
name = "q-learning"
params = { alpha = 0.5, epsilon = 0.1 }

[[agents]]
name = "dyna-q"
params = { planning_steps = 5 }

[tune]
trials = 2
seeds = 2

[[tune.maps]]
kind = "free"
label = "free-tune"

[tune.space.q-learning]
alpha = { low = 0.05, high = 1.0, log = true }
epsilon = { low = 0.01, high = 0.5 }
"""
"""1 tuned agent (dyna-q is not tuned) × 1 map × 1 preset × 2 seeds per trial."""


def _write(tmp_path: Path, text: str, name: str = "tune.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _load(tmp_path: Path, text: str = TINY_TUNE, **tune: Any) -> tuple[Any, TuneConfig]:
    config, parsed = load_tune_config(_write(tmp_path, text))
    return config, dataclasses.replace(parsed, **tune)


class StubTrial:
    """A run function whose convergence episode is 100 α + 10 · seed (no training), recording
    the (trial description, seed) of every call; raises KeyboardInterrupt at call ``stop``."""

    def __init__(self, stop: int | None = None) -> None:
        self.calls: list[tuple[str, int]] = []
        self.stop = stop

    def __call__(self, spec: RunSpec) -> TrialResult:
        if self.stop is not None and len(self.calls) == self.stop:
            raise KeyboardInterrupt
        self.calls.append((spec.config.description, spec.seed))
        value = 100.0 * float(spec.agent.params_dict()["alpha"]) + 10.0 * spec.seed
        coordinates = {
            "agent": spec.agent.label,
            "algorithm": spec.agent.name,
            "map": spec.map.label,
            "preset": spec.preset,
            "seed": spec.seed,
        }
        summary = {"convergence_episode": value, "converged": 1.0}
        return TrialResult(spec.run_id, coordinates, {}, summary, {})


def _study(out: Path, name: str = "tiny-tune/q-learning") -> optuna.Study:
    return optuna.load_study(study_name=name, storage=open_storage(out / JOURNAL))


def _finished(study: optuna.Study) -> list[optuna.trial.FrozenTrial]:
    return study.get_trials(states=(TrialState.COMPLETE, TrialState.PRUNED))


def test_tune_table_parses() -> None:
    _, tune = load_tune_config_text(TINY_TUNE)
    assert (tune.trials, tune.seeds, tune.sampler, tune.pruner) == (2, 2, "tpe", "median")
    assert [m.label for m in tune.maps] == ["free-tune"]
    alpha, _ = tune.space("q-learning")
    assert (alpha.low, alpha.high, alpha.log, alpha.is_integer) == (0.05, 1.0, True, False)
    assert tune.space("dyna-q") == ()
    assert ParamRange("n", low=1, high=100).is_integer
    assert ParamRange("mode", choices=("sample", "expected")).contains("sample")


def load_tune_config_text(text: str) -> tuple[Any, TuneConfig]:
    from skidnav.studies.tuning.config import parse_tune

    config = parse_config(text, "t.toml")
    return config, parse_tune(tomllib.loads(text)["tune"], config, Path("t.toml"))


def test_tiny_study_runs_and_writes_a_runnable_tuned_toml(tmp_path: Path) -> None:
    path = _write(tmp_path, TINY_TUNE)
    out = tmp_path / "study"
    code = main(["tune", str(path), "--out", str(out), "--backend", "serial"])
    assert code == 0
    study = _study(out)
    trials = _finished(study)
    assert len(trials) == 2 and all(t.state == TrialState.COMPLETE for t in trials)
    assert trials[0].params == {"alpha": 0.5, "epsilon": 0.1}  # the config's own params first
    for trial in trials:  # the objective is the IQM of the runs' convergence episodes
        assert trial.value == pytest.approx(iqm(trial.user_attrs["convergence_episodes"]))
        assert len(trial.user_attrs["convergence_episodes"]) == 2
    tuned = parse_config((out / "tuned.toml").read_text(), out / "tuned.toml")
    config = load_config(path)
    q, dyna = tuned.agents
    assert q.params_dict() == {**config.agents[0].params_dict(), **study.best_trial.params}
    assert dyna == config.agents[1]  # not tuned: as it was
    assert tuned.maps == config.maps and tuned.seeds == config.seeds  # evaluation grid kept
    assert (out / "config.toml").read_text() == TINY_TUNE


def test_resume_continues_to_the_trial_count_without_redoing_trials(tmp_path: Path) -> None:
    config, tune = _load(tmp_path, trials=2)
    out = tmp_path / "study"
    first = StubTrial()
    assert tune_experiment(config, tune, out, backend="serial", trial=first).executed == 2
    before = [(t.number, t.params, t.value) for t in _finished(_study(out))]
    second = StubTrial()
    outcome = tune_experiment(
        config, dataclasses.replace(tune, trials=3), out, backend="serial", trial=second
    )
    assert outcome.executed == 1 and outcome.finished == {"q-learning": 3}
    assert len(second.calls) == tune.seeds  # one new trial's runs, nothing redone
    after = [(t.number, t.params, t.value) for t in _finished(_study(out))]
    assert after[:2] == before and [n for n, _, _ in after] == [0, 1, 2]
    third = StubTrial()
    assert tune_experiment(config, tune, out, backend="serial", trial=third).executed == 0
    assert third.calls == []


def _trace(out: Path, name: str = "tiny-tune/q-learning") -> list[tuple[Any, ...]]:
    return [
        (t.number, t.state, t.params, t.value, t.intermediate_values)
        for t in _study(out, name).trials
    ]


SMALL_MAPS = 'label = "free-tune"\noptions = { shape = [8, 8], min_distance = 3 }'
DYNA_SPACE = "[tune.space.dyna-q]\nplanning_steps = { low = 1, high = 50 }\n\n"
BACKEND_TUNE = (
    TINY_TUNE.replace("episodes = 14", "episodes = 30")
    .replace('label = "free-tune"', SMALL_MAPS)
    .replace("[tune.space.q-learning]", DYNA_SPACE + "[tune.space.q-learning]")
)
"""Dyna-Q converges on small tuning maps within 30 episodes, so trials differ and some prune."""


def test_same_study_on_every_backend(tmp_path: Path) -> None:
    config, tune = _load(
        tmp_path, BACKEND_TUNE, trials=3, pruner_startup_trials=1, pruner_warmup_seeds=1
    )
    for backend in ("serial", "process", "dask"):
        tune_experiment(config, tune, tmp_path / backend, backend=backend, jobs=2)
    serial = _trace(tmp_path / "serial", "tiny-tune/dyna-q")
    assert len({value for _, _, _, value, _ in serial}) > 1
    for backend in ("process", "dask"):
        assert _trace(tmp_path / backend, "tiny-tune/dyna-q") == serial
        assert _trace(tmp_path / backend) == _trace(tmp_path / "serial")


def test_interrupted_study_resumes_to_the_same_trials(tmp_path: Path) -> None:
    config, tune = _load(tmp_path, trials=5, seeds=3, pruner="none", startup_trials=2)
    straight = tmp_path / "straight"
    tune_experiment(config, tune, straight, backend="serial", trial=StubTrial())
    cut = tmp_path / "cut"
    with pytest.raises(KeyboardInterrupt):  # Ctrl-C during the second seed of trial 2
        tune_experiment(config, tune, cut, backend="serial", trial=StubTrial(stop=7))
    states = [t.state for t in _study(cut).trials]
    assert states == [TrialState.COMPLETE] * 2 + [TrialState.FAIL]
    assert (cut / "tuned.toml").exists()  # written on the way out, best so far
    tune_experiment(config, tune, cut, backend="serial", trial=StubTrial())
    resumed = [(t.params, t.value) for t in _finished(_study(cut))]
    assert resumed == [(t.params, t.value) for t in _finished(_study(straight))]


def test_a_run_that_raises_fails_its_trial_and_the_search_in_one_line(tmp_path: Path) -> None:
    def divide_by_zero(spec: RunSpec) -> TrialResult:
        raise ZeroDivisionError("float division by zero")

    config, tune = _load(tmp_path)
    with pytest.raises(RunsFailedError, match=r"^run-000000 \(agent q-learning, preset rough, "):
        tune_experiment(config, tune, tmp_path / "study", backend="serial", trial=divide_by_zero)
    assert [t.state for t in _study(tmp_path / "study").get_trials()] == [TrialState.FAIL]


def test_a_trial_left_running_by_a_kill_is_marked_failed(tmp_path: Path) -> None:
    config, tune = _load(tmp_path, trials=1)
    out = tmp_path / "study"
    tune_experiment(config, tune, out, backend="serial", trial=StubTrial())
    _study(out).ask()  # as if SIGKILLed mid-trial
    with open(out / JOURNAL, "ab") as handle:
        handle.write(b'{"op_code": 5, "worker_id"')  # and mid-write
    tune_experiment(
        config, dataclasses.replace(tune, trials=2), out, backend="serial", trial=StubTrial()
    )
    states = [t.state for t in _study(out).trials]
    assert states == [TrialState.COMPLETE, TrialState.FAIL, TrialState.COMPLETE]


def test_median_pruner_stops_bad_trials_after_the_warmup_seeds(tmp_path: Path) -> None:
    config, tune = _load(
        tmp_path,
        trials=8,
        seeds=4,
        sampler="random",
        pruner_startup_trials=1,
        pruner_warmup_seeds=2,
    )
    stub = StubTrial()
    tune_experiment(config, tune, tmp_path / "study", backend="serial", trial=stub)
    trials = _finished(_study(tmp_path / "study"))
    pruned = [t for t in trials if t.state == TrialState.PRUNED]
    assert pruned, [t.value for t in trials]
    runs = {t.number: sum(d.endswith(f"trial {t.number}") for d, _ in stub.calls) for t in trials}
    for trial in trials:
        steps = sorted(trial.intermediate_values)
        assert runs[trial.number] == steps[-1]  # one run per seed, nothing after the prune
        for step in steps:  # each step: the IQM over the first `step` seeds
            alpha = trial.params["alpha"]
            expected = iqm([100 * alpha + 10 * seed for seed in range(step)])
            assert trial.intermediate_values[step] == pytest.approx(expected)
    for trial in pruned:
        assert 2 <= max(trial.intermediate_values) < 4
        complete = [t for t in trials if t.state == TrialState.COMPLETE and t.number < trial.number]
        step = max(trial.intermediate_values)
        median = np.median([t.intermediate_values[step] for t in complete])
        assert min(trial.intermediate_values.values()) > median


def _experiment(config: Any) -> dict[str, Any]:
    """The [experiment] and [[maps]] of a config, without its name, description and agents."""
    values = config_to_dict(config)
    return {k: v for k, v in values.items() if k not in {"name", "description", "agents"}}


def test_tuning_worlds_are_never_evaluation_worlds(tmp_path: Path) -> None:
    config, tune = load_tune_config(CONFIGS / "tune-thesis.toml")
    evaluation = load_config(CONFIGS / "thesis.toml")
    assert _experiment(config) == _experiment(evaluation)  # tuned.toml: thesis.toml, tuned
    assert set(config.agents) <= set(evaluation.agents)
    assert check_separation(config, tune) == evaluation.seeds
    evaluation_runs = expand_runs(evaluation)
    agent = config.agents[0]
    runs = tuning_runs(trial_config(config, tune, agent, {}, ""))
    assert len(runs) == tune.seeds
    for spec in runs:  # the evaluation keys under one more level: disjoint streams
        assert spec.world_seed.spawn_key[0] == spec.run_seed.spawn_key[0] == TUNE_STREAM
    keys = {s.world_seed for s in evaluation_runs} | {s.run_seed for s in evaluation_runs}
    assert not keys & ({s.world_seed for s in runs} | {s.run_seed for s in runs})
    maps = [run_map(spec) for spec in evaluation_runs if spec.agent == evaluation.agents[0]]
    for spec in runs:
        tuning_map = run_map(spec)
        assert not any(
            np.array_equal(tuning_map.occupancy, m.occupancy)
            and (tuning_map.start, tuning_map.goal) == (m.start, m.goal)
            for m in maps
        )


def test_run_map_is_the_map_a_run_trains_on(tmp_path: Path) -> None:
    config, tune = _load(tmp_path)
    spec = tuning_runs(trial_config(config, tune, config.agents[0], {}, ""))[1]
    spec = dataclasses.replace(spec, config=dataclasses.replace(spec.config, episodes=2))
    result = measure_trial(spec)
    grid_map = run_map(spec)
    assert np.array_equal(result.arrays["occupancy"], grid_map.occupancy)
    assert tuple(result.arrays["start"]) == grid_map.start
    assert tuple(result.arrays["goal"]) == grid_map.goal


def test_a_tuning_map_file_equal_to_an_evaluation_map_is_refused(tmp_path: Path) -> None:
    (tmp_path / "arena.txt").write_text(main_map_text(tmp_path))
    text = TINY_TUNE.replace('kind = "free"\n', 'file = "arena.txt"\n')
    config, tune = _load(tmp_path, text)
    with pytest.raises(UserError, match="equals evaluation map"):
        check_separation(config, tune)


def main_map_text(tmp_path: Path) -> str:
    """A map file's text, written by ``skidnav world map generate``."""
    path = tmp_path / "generated.txt"
    assert (
        main(["world", "map", "generate", "--kind", "free", "--seed", "3", "--out", str(path)]) == 0
    )
    return path.read_text()


def test_a_changed_search_is_refused_on_the_same_directory(tmp_path: Path) -> None:
    config, tune = _load(tmp_path, trials=1)
    out = tmp_path / "study"
    tune_experiment(config, tune, out, backend="serial", trial=StubTrial())
    text = TINY_TUNE.replace("high = 0.5", "high = 0.6")
    config, changed = _load(tmp_path, text)
    with pytest.raises(UserError, match="different config"):
        tune_experiment(config, changed, out, backend="serial", trial=StubTrial())


BAD = {
    "no-tune-table": (TINY_TUNE.split("[tune]")[0], "no [tune] table"),
    "unknown-label": (TINY_TUNE.replace("space.q-learning", "space.sarsa"), "'sarsa'"),
    "empty-space": (TINY_TUNE.split("alpha = { low")[0], "at least one hyperparameter"),
    "no-space": (TINY_TUNE.split("[tune.space")[0], "[tune.space.<agent label>]"),
    "bounds": (TINY_TUNE.replace("low = 0.01, high", "low = 0.9, high"), "low < high"),
    "log-at-zero": (TINY_TUNE.replace("low = 0.05", "low = 0.0"), "low > 0"),
    "zero-trials": (TINY_TUNE.replace("trials = 2", "trials = 0"), "trials"),
    "absurd-trials": (TINY_TUNE.replace("trials = 2", "trials = 1000000000"), "trials"),
    "absurd-seeds": (TINY_TUNE.replace("seeds = 2\n\n[[tune", "seeds = 5000\n\n[[tune"), "seeds"),
    "unknown-key": (TINY_TUNE.replace("trials = 2", "trails = 2"), "'trails'"),
    "bad-sampler": (
        TINY_TUNE.replace("seeds = 2\n\n[[", 'seeds = 2\nsampler = "grid"\n\n[['),
        "sampler",
    ),
    "range-key": (TINY_TUNE.replace("log = true", "logg = true"), "'logg'"),
    "unknown-param": (TINY_TUNE.replace("epsilon = { low", "epsilom = { low"), "epsilom"),
    "out-of-agent-range": (TINY_TUNE.replace("high = 1.0", "high = 1.5"), "alpha = 1.5"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_tune_configs_end_in_one_line_and_exit_2(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text, needle = BAD[name]
    out = tmp_path / "study"
    code = main(["tune", str(_write(tmp_path, text)), "--out", str(out), "--backend", "serial"])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1, lines
    assert lines[0].startswith("skidnav: error: ") and needle in lines[0], lines
    assert not out.exists()


def test_bad_trials_argument_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, TINY_TUNE)
    assert main(["tune", str(path), "--out", str(tmp_path / "s"), "--trials", "0"]) == 2
    assert "--trials" in capsys.readouterr().err


def test_toml_values_round_trip() -> None:
    values = {
        "a": 0.1,
        "b": 1e-05,
        "c": -3,
        "d": True,
        "e": 'x "y"\n',
        "f": [1, 2.5, "z"],
        "g": math.inf,
        "key with space": "ü",
    }
    text = "\n".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in values.items())
    assert tomllib.loads(text) == values
