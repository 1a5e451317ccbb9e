"""Reading experiment configs from TOML files, with one-line errors a user can act on.

Every problem raises :class:`skidnav.errors.UserError` naming the file and the key, e.g.
``configs/a.toml: [experiment]: unknown key 'episods' (expected one of …)`` or
``configs/a.toml:4:9: malformed TOML: Invalid value``. Tables, keys and map paths (relative to
the config file) follow :mod:`skidnav.files.configtables`. Agent names and hyperparameters are
checked against the agents package by
:func:`skidnav.experiments.config_checks.check_config`, which the runner calls before any run
starts.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

from skidnav.errors import ConfigError, UserError, shown, within
from skidnav.experiments.config import (
    DEFAULT_ENV_ID,
    AgentSpec,
    ExperimentConfig,
    MapSpec,
    freeze_params,
)
from skidnav.experiments.memory import check_memory
from skidnav.files.configtables import check_keys, resolve_path, table, table_array
from skidnav.files.saved import MAX_CONFIG_BYTES, parse_toml, read_config_text

MAX_CONFIG_CHARS = MAX_CONFIG_BYTES // 4
"""Longest config text accepted [characters] (a config is a few kilobytes)."""
TOP_KEYS = ("kind", "experiment", "env", "maps", "agents", "tune")
"""Top-level keys of an experiment config: ``kind`` (``"experiment"``, or a study's:
:mod:`skidnav.studies.kind`), ``[tune]`` (:mod:`skidnav.studies.tuning.config`)."""
EXPERIMENT_KEYS = (
    "name",
    "description",
    "env_id",
    "episodes",
    "max_steps",
    "seeds",
    "root_seed",
    "presets",
    "drift_amplitude",
    "drift_period",
    "convergence_tolerance",
    "convergence_window",
    "convergence_level",
    "convergence_objective",
    "eval_rollouts",
    "oracle_samples",
    "baseline",
    "headline",
    "bootstrap_samples",
    "confidence",
    "greedy_eval",
    "save_agents",
    "optimum_grids",
    "optimum_samples",
    "optimum_rollouts",
)
AGENT_KEYS = ("name", "label", "params", "sweep", "discretization")
MAP_KEYS = ("kind", "file", "label", "options")


def load_config(path: Path | str) -> ExperimentConfig:
    """Read and validate an experiment config file (at most
    :data:`~skidnav.files.saved.MAX_CONFIG_BYTES`; a device or a pipe ends at that limit).

    Raises:
        UserError: missing, unreadable or too long file, malformed TOML (with line and column),
            unknown key, wrong type or out-of-range value, missing map file.
    """
    return load_config_and_text(path)[0]


def load_config_and_text(path: Path | str) -> tuple[ExperimentConfig, str]:
    """(:func:`load_config`, the file's text): the file is read once, so the text saved beside
    the results is the one the config came from."""
    text = read_config_text(path)
    return parse_config(text, path), text


def parse_config(text: str, path: Path | str = "<string>") -> ExperimentConfig:
    """Validate config text; map files are resolved relative to ``path``'s folder."""
    return config_from_tables(parse_tables(text, path), path)


def parse_tables(text: str, path: Path | str = "<string>") -> dict[str, Any]:
    """The TOML tables of config text of at most :data:`MAX_CONFIG_CHARS` characters; UserError
    naming ``path`` (with line and column) when it is longer, malformed or nested too deeply."""
    if len(text) > MAX_CONFIG_CHARS:
        raise UserError(f"{path}: config of {len(text):,} characters, expected at most "
                        f"{MAX_CONFIG_CHARS:,}")  # fmt: skip
    return parse_toml(text, path)


def config_from_tables(data: dict[str, Any], path: Path | str) -> ExperimentConfig:
    """The experiment config of parsed TOML tables (map files relative to ``path``'s folder);
    UserError naming ``path`` and the key."""
    try:
        return _build(data, Path(path))
    except (UserError, ValueError, TypeError) as error:
        raise within(error, str(path)) from None


def _string(values: dict[str, Any], key: str, where: str, default: str | None = None) -> str:
    value = values.get(key, default)
    if value is None:
        raise ConfigError(f"missing key {key!r}", (where,))
    if not isinstance(value, str):
        raise ConfigError(f"expected {key} to be a string, got {shown(value)}", (where,))
    return value


def _build(data: dict[str, Any], path: Path) -> ExperimentConfig:
    check_keys(data, TOP_KEYS, "top level")
    experiment = table(data.get("experiment"), "[experiment]")
    check_keys(experiment, EXPERIMENT_KEYS, "[experiment]")
    values = dict(experiment)
    for key in ("name", "description", "env_id", "baseline", "headline"):
        if key in values:
            values[key] = _string(values, key, "[experiment]")
    if "name" not in values:
        values["name"] = path.stem
    presets = values.get("presets", ["thesis"])
    if not isinstance(presets, list) or not all(isinstance(p, str) for p in presets):
        problem = f"expected presets to be a list of strings, got {shown(presets)}"
        raise ConfigError(problem, ("[experiment]",))
    values["presets"] = tuple(presets)
    grids = values.get("optimum_grids", [])
    if not isinstance(grids, list) or not all(isinstance(levels, list) for levels in grids):
        problem = (
            f"expected optimum_grids to be a list of [n_x, n_y, n_headings], got {shown(grids)}"
        )
        raise ConfigError(problem, ("[experiment]",))
    values["optimum_grids"] = tuple(tuple(levels) for levels in grids)
    agents = tuple(
        itertools.chain.from_iterable(
            _agents(agent, f"[[agents]] #{n + 1}")
            for n, agent in enumerate(table_array(data.get("agents"), "agents"))
        )
    )
    maps = _maps(data, values.get("env_id", DEFAULT_ENV_ID), path.parent)
    env = freeze_params(table(data.get("env", {}), "[env]"))
    try:
        config = ExperimentConfig(agents=agents, maps=maps, env_options=env, **values)
    except ValueError as error:
        raise within(error, "[experiment]") from None
    if config.env_id == DEFAULT_ENV_ID:
        check_memory(config)
    return config


def _agents(agent: dict[str, Any], where: str) -> list[AgentSpec]:
    """One agent table, expanded over the cartesian product of its ``sweep`` lists."""
    check_keys(agent, AGENT_KEYS, where)
    name = _string(agent, "name", where)
    label = _string(agent, "label", where, default=name)
    params = table(agent.get("params", {}), f"{where} params")
    sweep = table(agent.get("sweep", {}), f"{where} sweep")
    levels = agent.get("discretization", [])
    if not isinstance(levels, list):
        problem = f"expected discretization to be [n_x, n_y, n_headings], got {shown(levels)}"
        raise ConfigError(problem, (where,))
    for key, values in sweep.items():
        if not isinstance(values, list) or not values:
            problem = f"expected sweep.{shown(key)} to be a non-empty list, got {shown(values)}"
            raise ConfigError(problem, (where,))
        if key in params:
            raise ConfigError(f"key {shown(key)} is both in params and in sweep", (where,))
    keys = sorted(sweep)
    agents = []
    for combination in itertools.product(*(sweep[key] for key in keys)):
        chosen = dict(zip(keys, combination, strict=True))
        suffix = ",".join(f"{key}={value}" for key, value in chosen.items())
        full_label = f"{label}[{suffix}]" if suffix else label
        try:
            agents.append(
                AgentSpec(name, full_label, freeze_params({**params, **chosen}), tuple(levels))
            )
        except ValueError as error:
            raise within(error, where) from None
    return agents


def _maps(data: dict[str, Any], env_id: str, folder: Path) -> tuple[MapSpec, ...]:
    """The ``[[maps]]`` tables; an env other than the skid-steer one brings its own world, so
    its maps may be omitted (one placeholder map named after the env)."""
    if "maps" not in data and env_id != DEFAULT_ENV_ID:
        return (MapSpec(label=env_id.rsplit(":", 1)[-1], kind="free"),)
    tables = table_array(data.get("maps"), "maps")
    return tuple(read_map(spec, f"[[maps]] #{n + 1}", folder) for n, spec in enumerate(tables))


def read_map(spec: dict[str, Any], where: str, folder: Path) -> MapSpec:
    """One ``[[maps]]`` table (also a ``[[tune.maps]]`` one) as a map; its file relative to
    ``folder``, the config file's. ValueError or UserError naming ``where``."""
    check_keys(spec, MAP_KEYS, where)
    kind = _string(spec, "kind", where, default="")
    file = _string(spec, "file", where, default="")
    if file:
        resolved = resolve_path(file, folder)
        if not _is_file(resolved):
            problem = f"no such map file {shown(file)}"
            raise ConfigError(problem, (where,), f"looked in {folder.resolve()}")
        file = str(resolved)
    label = _string(spec, "label", where, default=kind or Path(file).stem)
    options = freeze_params(table(spec.get("options", {}), f"{where} options"))
    try:
        return MapSpec(label=label, kind=kind, file=file, options=options)
    except ValueError as error:
        raise within(error, where) from None


def _is_file(path: Path) -> bool:
    """Whether ``path`` is a file; False also for a name the system refuses (too long)."""
    try:
        return path.is_file()
    except OSError:
        return False
