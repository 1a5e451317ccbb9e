"""The ``[tune]`` table of an experiment config: budget, sampler, pruner, maps, search spaces.

``skidnav tune CONFIG`` (docs/tuning.md) reads an ordinary experiment config plus one table::

    [tune]
    trials = 30                  # finished trials per agent; a resumed study continues up to it
    seeds = 6                    # tuning seeds per trial
    timeout_s = 3600             # optional: start no new trial after this long [s]
    sampler = "tpe"              # "tpe" (Optuna's TPESampler) or "random"
    startup_trials = 10          # trials sampled at random before TPE models the results
    pruner = "median"            # "median" (Optuna's MedianPruner) or "none"
    pruner_startup_trials = 5    # complete trials before any trial is pruned
    pruner_warmup_seeds = 2      # seeds a trial runs before it may be pruned

    [[tune.maps]]                # the tuning maps, schema of [[maps]] (default: those of [[maps]])
    kind = "obstacles"

    [tune.space.q-learning]      # per agent label: hyperparameter = range or choices
    alpha = { low = 0.05, high = 1.0, log = true }
    planning_steps = { choices = [10, 100, 1000] }

Every problem raises :class:`~skidnav.errors.UserError` naming the file and the key, like the rest
of the config. The search itself is :mod:`skidnav.studies.tuning.search`, the ``tuned.toml`` it
writes :mod:`skidnav.studies.tuning.tuned_file`.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from skidnav.errors import ConfigError, UserError, shown, within
from skidnav.experiments.config import AgentSpec, ExperimentConfig, MapSpec

# The [[maps]] schema lives in configfile; reusing it keeps [[tune.maps]] and [[maps]] one schema,
# with the same messages.
from skidnav.experiments.configfile import config_from_tables, parse_tables, read_map
from skidnav.experiments.limits import check_range
from skidnav.experiments.memory import check_oracle_memory, map_states
from skidnav.files.configtables import check_keys, table, table_array
from skidnav.files.saved import read_config_text

if TYPE_CHECKING:
    import optuna

logger = logging.getLogger(__name__)

Choice = bool | int | float | str
SAMPLERS = ("tpe", "random")
PRUNERS = ("median", "none")
TUNE_KEYS = (
    "trials",
    "seeds",
    "timeout_s",
    "sampler",
    "startup_trials",
    "pruner",
    "pruner_startup_trials",
    "pruner_warmup_seeds",
    "maps",
    "space",
)
RANGE_KEYS = ("low", "high", "log", "step", "choices")
MAX_TRIALS = 10_000
"""Most trials per agent a config may ask for (more is a typo, not a plan)."""
MAX_SEEDS = 1_000
"""Most tuning seeds per trial."""


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


@dataclass(frozen=True)
class ParamRange:
    """The search range of one hyperparameter: a number in [low, high] (an integer when both
    bounds and the step are integers; log-uniform with ``log``), or one of ``choices``.

    >>> ParamRange("alpha", low=0.05, high=1.0, log=True).describe()
    'alpha in [0.05, 1.0] log'
    >>> ParamRange("alpha", low=1.0, high=0.5)
    Traceback (most recent call last):
    ...
    ValueError: alpha: expected low < high, got low = 1.0, high = 0.5
    """

    name: str
    low: float | None = None
    high: float | None = None
    log: bool = False
    step: float | None = None
    choices: tuple[Choice, ...] = ()

    def __post_init__(self) -> None:
        if self.choices or (self.low is None and self.high is None):
            self._check_choices()
        else:
            self._check_bounds()

    def _check_choices(self) -> None:
        if self.low is not None or self.high is not None or self.log or self.step is not None:
            raise ValueError(f"{self.name}: expected either choices or low/high, not both")
        if not isinstance(self.choices, tuple) or not self.choices:
            raise ValueError(f"{self.name}: expected low and high, or non-empty choices")
        if not all(isinstance(choice, Choice) for choice in self.choices):
            raise ValueError(f"{self.name}: expected choices of numbers, strings or booleans")
        if len({(type(c), c) for c in self.choices}) != len(self.choices):
            raise ValueError(
                f"{self.name}: expected distinct choices, got {shown(list(self.choices))}"
            )

    def _check_bounds(self) -> None:
        low, high = self.low, self.high
        if not (_is_number(low) and _is_number(high)):
            raise ValueError(
                f"{self.name}: expected numbers low and high, got {shown(low)}, {shown(high)}"
            )
        assert low is not None and high is not None
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(f"{self.name}: expected low < high, got low = {low}, high = {high}")
        if not isinstance(self.log, bool):
            raise ValueError(f"{self.name}: expected log = true or false, got {shown(self.log)}")
        if self.log and low <= 0:
            raise ValueError(f"{self.name}: expected low > 0 with log = true, got {low}")
        if self.step is not None:
            if not _is_number(self.step) or not 0 < self.step <= high - low:
                raise ValueError(
                    f"{self.name}: expected a step in (0, high - low], got {shown(self.step)}"
                )
            if self.log:
                raise ValueError(f"{self.name}: expected either log or step, not both")

    @property
    def is_integer(self) -> bool:
        """True for an integer range (both bounds, and the step if any, are integers)."""
        numbers = (self.low, self.high, 1 if self.step is None else self.step)
        return not self.choices and all(isinstance(v, int) for v in numbers)

    def suggest(self, trial: optuna.Trial) -> Choice:
        """This hyperparameter's value for ``trial`` (asked from its sampler)."""
        if self.choices:
            choice: Choice = trial.suggest_categorical(self.name, list(self.choices))  # type: ignore[assignment]
            return choice
        assert self.low is not None and self.high is not None
        if self.is_integer:
            step = 1 if self.step is None else int(self.step)
            return trial.suggest_int(
                self.name, int(self.low), int(self.high), step=step, log=self.log
            )
        return trial.suggest_float(
            self.name, float(self.low), float(self.high), step=self.step, log=self.log
        )

    def contains(self, value: Any) -> bool:
        """True when ``value`` is a point of this range (an enqueued trial must be)."""
        if self.choices:
            return any(type(value) is type(c) and value == c for c in self.choices)
        assert self.low is not None and self.high is not None
        if not _is_number(value) or (self.is_integer and not isinstance(value, int)):
            return False
        return bool(self.low <= value <= self.high)

    def corners(self) -> tuple[Choice, ...]:
        """The extreme points (both bounds, or every choice), checked against the agent."""
        if self.choices:
            return self.choices
        assert self.low is not None and self.high is not None
        return (self.low, self.high)

    def describe(self) -> str:
        """One line for the comments of ``tuned.toml``."""
        if self.choices:
            return f"{self.name} in {json.dumps(list(self.choices))}"
        step = f" step {self.step}" if self.step is not None else ""
        return f"{self.name} in [{self.low}, {self.high}]{' log' if self.log else ''}{step}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (part of a study's fingerprint)."""
        if self.choices:
            return {"name": self.name, "choices": list(self.choices)}
        return {
            "name": self.name,
            "low": self.low,
            "high": self.high,
            "log": self.log,
            "step": self.step,
        }


@dataclass(frozen=True)
class TuneConfig:
    """The search of ``skidnav tune``, validated on construction (module docs for the TOML).

    Attributes:
        trials: finished (complete or pruned) trials per agent, in [1, MAX_TRIALS].
        seeds: tuning seeds per trial, in [1, MAX_SEEDS]; each seed is one run per tuning map
            and slip preset.
        maps: the tuning maps (drawn from the tuning seed stream, never the evaluation one).
        spaces: (agent label, its hyperparameter ranges) for every agent to tune.
        timeout_s: wall time [s] after which no new trial starts in one invocation, or None.
        sampler: one of :data:`SAMPLERS`.
        startup_trials: trials TPE samples at random before it models the results, ≥ 0.
        pruner: one of :data:`PRUNERS`.
        pruner_startup_trials: complete trials of a study before any of its trials is pruned.
        pruner_warmup_seeds: seeds a trial runs before it may be pruned, in [0, seeds].
    """

    trials: int
    seeds: int
    maps: tuple[MapSpec, ...]
    spaces: tuple[tuple[str, tuple[ParamRange, ...]], ...]
    timeout_s: float | None = None
    sampler: str = "tpe"
    startup_trials: int = 10
    pruner: str = "median"
    pruner_startup_trials: int = 5
    pruner_warmup_seeds: int = 2

    def __post_init__(self) -> None:
        check_range("trials", self.trials, 1, MAX_TRIALS, integer=True)
        check_range("seeds", self.seeds, 1, MAX_SEEDS, integer=True)
        if self.timeout_s is not None:
            check_range("timeout_s", self.timeout_s, 1e-3, math.inf, integer=False)
        for name, value, allowed in (
            ("sampler", self.sampler, SAMPLERS),
            ("pruner", self.pruner, PRUNERS),
        ):
            if value not in allowed:
                raise ValueError(f"expected {name} one of {', '.join(allowed)}, got {shown(value)}")
        check_range("startup_trials", self.startup_trials, 0, MAX_TRIALS, integer=True)
        check_range(
            "pruner_startup_trials", self.pruner_startup_trials, 0, MAX_TRIALS, integer=True
        )
        check_range("pruner_warmup_seeds", self.pruner_warmup_seeds, 0, self.seeds, integer=True)
        if not self.maps:
            raise ValueError("expected at least one tuning map")
        map_labels = [spec.label for spec in self.maps]
        if len(set(map_labels)) != len(map_labels):
            raise ValueError(f"expected unique tuning map labels, got {map_labels}")
        labels = [label for label, _ in self.spaces]
        if not labels:
            raise ValueError("expected a [tune.space.<agent label>] table for at least one agent")
        if len(set(labels)) != len(labels):
            raise ValueError(f"expected unique agent labels in [tune.space], got {labels}")

    def space(self, label: str) -> tuple[ParamRange, ...]:
        """The ranges of agent ``label`` (empty when it is not tuned)."""
        return dict(self.spaces).get(label, ())

    def study_settings(self, label: str) -> dict[str, Any]:
        """Everything of this table that defines agent ``label``'s study (not the budget:
        ``trials`` and ``timeout_s`` may change between invocations of a resumed study)."""
        return {
            "space": [param.to_dict() for param in self.space(label)],
            "sampler": self.sampler,
            "startup_trials": self.startup_trials,
            "pruner": self.pruner,
            "pruner_startup_trials": self.pruner_startup_trials,
            "pruner_warmup_seeds": self.pruner_warmup_seeds,
        }


def load_tune_config(path: Path | str) -> tuple[ExperimentConfig, TuneConfig]:
    """Read an experiment config and its ``[tune]`` table (the file read once, with the limits
    of :func:`~skidnav.experiments.configfile.load_config`).

    Raises:
        UserError: anything :func:`~skidnav.experiments.configfile.load_config` refuses, a
            missing ``[tune]`` table, or a bad key or value in it (one line, naming the file).
    """
    config, tune, _ = load_tune_config_and_text(path)
    return config, tune


def load_tune_config_and_text(path: Path | str) -> tuple[ExperimentConfig, TuneConfig, str]:
    """(config, ``[tune]`` table, the file's text) of :func:`load_tune_config`."""
    text = read_config_text(path)
    data = parse_tables(text, path)
    config = config_from_tables(data, path)
    if "tune" not in data:
        raise UserError(f"{path}: no [tune] table (see docs/tuning.md)")
    for agent in config.agents:
        if agent.discretization:  # tuned.toml would lose it
            raise UserError(f"{path}: agent {agent.label!r}: tuning takes no discretization")
    try:
        return config, parse_tune(data["tune"], config, Path(path)), text
    except (UserError, ValueError, TypeError) as error:
        raise within(error, str(path)) from None


def parse_tune(value: Any, config: ExperimentConfig, path: Path) -> TuneConfig:
    """The ``[tune]`` table as a :class:`TuneConfig`; map files relative to ``path``'s folder.

    Raises:
        ValueError, UserError: a bad key or value, naming it.
    """
    tune = table(value, "[tune]")
    check_keys(tune, TUNE_KEYS, "[tune]")
    maps = config.maps
    if "maps" in tune:
        tables = table_array(tune["maps"], "tune.maps")
        where = "[[tune.maps]] #{}"
        maps = tuple(read_map(t, where.format(n + 1), path.parent) for n, t in enumerate(tables))
        for spec in maps:  # as the experiment's [[maps]] are when read
            label = f"[[tune.maps]] {spec.label!r}"
            check_oracle_memory(label, map_states(spec), config.oracle_samples)
    if "space" not in tune:
        raise ConfigError("missing table [tune.space.<agent label>]", ("[tune]",))
    if "seeds" not in tune:
        raise ConfigError("missing key 'seeds'", ("[tune]",), "tuning seeds per trial")
    spaces = tuple(
        (label, _space(label, ranges))
        for label, ranges in table(tune["space"], "[tune.space]").items()
    )
    for label, _ in spaces:
        if label not in config.agent_labels:
            raise ConfigError(
                f"unknown agent label {shown(label)}",
                ("[tune.space]",),
                f"expected one of {', '.join(config.agent_labels)}",
            )
    values = {key: tune[key] for key in TUNE_KEYS if key in tune and key not in {"maps", "space"}}
    try:
        return TuneConfig(maps=maps, spaces=spaces, **values)
    except ValueError as error:
        raise within(error, "[tune]") from None


def _space(label: str, value: Any) -> tuple[ParamRange, ...]:
    where = f"[tune.space.{label}]"
    space = table(value, where)
    if not space:
        raise ConfigError("expected at least one hyperparameter", (where,))
    ranges = []
    for name, spec in space.items():
        spec = table(spec, f"{where} {name}")
        check_keys(spec, RANGE_KEYS, f"{where} {name}")
        values = dict(spec)
        if "choices" in values:
            if not isinstance(values["choices"], list):
                problem = f"expected {name} choices to be a list, got {shown(values['choices'])}"
                raise ConfigError(problem, (where,))
            values["choices"] = tuple(values["choices"])
        try:
            ranges.append(ParamRange(name, **values))
        except ValueError as error:
            raise within(error, where) from None
    return tuple(ranges)


def check_tuning(config: ExperimentConfig, tune: TuneConfig, path: Path | str | None) -> None:
    """Check with the agents package, before anything runs: the tuning maps and environment,
    and every agent's config at each corner of its space (bounds, choices)."""
    from skidnav.agents.tabular.registry import make_config
    from skidnav.experiments.config_checks import check_config

    check_config(dataclasses.replace(config, maps=tune.maps, seeds=tune.seeds), path)
    for agent in config.agents:
        for param in tune.space(agent.label):
            for corner in param.corners():
                try:
                    make_config(agent.name, {**agent.params_dict(), param.name: corner})
                except UserError as error:
                    where = f"[tune.space.{agent.label}] {param.name} = {shown(corner)}"
                    wrapped = within(error, where)
                    raise (wrapped if path is None else within(wrapped, str(path))) from None


def default_point(agent: AgentSpec, space: Sequence[ParamRange]) -> dict[str, Any] | None:
    """The agent's own values of the tuned hyperparameters (its params, else its config's
    defaults), or None when one of them lies outside the space."""
    from skidnav.agents.tabular.registry import make_config

    values = make_config(agent.name, agent.params_dict()).to_dict()
    point = {param.name: values[param.name] for param in space}
    if all(param.contains(point[param.name]) for param in space):
        return point
    logger.info("%s: its own hyperparameters %s lie outside the space", agent.label, point)
    return None
