"""Agents by name: :func:`make_agent`, :func:`load_agent`, :func:`available_agents`.

Convention for an agent module (docs/agents/core.md): it defines ``AGENT_NAME`` (the registry
name) and ``AGENT_CLASS`` (a :class:`~skidnav.agents.core.TabularAgent` subclass whose ``name``
equals ``AGENT_NAME`` and whose ``config_class`` is its frozen config dataclass). The registry maps
names to module paths and imports a module only when its agent is asked for.

>>> import numpy as np
>>> agent = make_agent("dyna-q", 10, 4, {"planning_steps": 3}, np.random.default_rng(0))
>>> type(agent).__name__, agent.config.planning_steps
('DynaQAgent', 3)
"""

from __future__ import annotations

import importlib
import json
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.config import QLearningConfig
from skidnav.agents.core import SAVE_FORMAT, SAVE_VERSION, TabularAgent, save_paths
from skidnav.errors import CorruptFileError, UserError

AGENT_MODULES: dict[str, str] = {
    "q-learning": "skidnav.agents.q_learning",
    "dyna-q": "skidnav.agents.dyna_q",
    "dyna-q-plus": "skidnav.agents.dyna_q_plus",
    "prioritized-sweeping": "skidnav.agents.prioritized_sweeping",
    "dyna-kinematic": "skidnav.agents.dyna_kinematic",
    "trajectory-prioritized": "skidnav.agents.trajectory_prioritized",
    "dyna-full": "skidnav.agents.dyna_full",
    "dyna-sweep": "skidnav.agents.dyna_sweep",
}
"""Registry name → module defining ``AGENT_NAME`` and ``AGENT_CLASS``."""


def agent_class(name: str) -> type[TabularAgent]:
    """The agent class registered as ``name``; UserError if unknown or not installed."""
    module_name = AGENT_MODULES.get(name)
    if module_name is None:
        raise UserError(f"unknown agent {name!r}; expected one of {', '.join(AGENT_MODULES)}")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if error.name != module_name:
            raise
        raise UserError(f"agent {name!r} is not available (no module {module_name})") from None
    cls: type[TabularAgent] = module.AGENT_CLASS
    if {module.AGENT_NAME, cls.name} != {name}:
        raise RuntimeError(f"{module_name} registers {module.AGENT_NAME!r}, expected {name!r}")
    return cls


def available_agents() -> list[str]:
    """Names of the registered agents whose modules can be imported."""
    names = []
    for name in AGENT_MODULES:
        try:
            agent_class(name)
        except UserError:
            continue
        names.append(name)
    return names


def make_config(name: str, config: QLearningConfig | Mapping[str, Any] | None) -> QLearningConfig:
    """The config of agent ``name`` from a config object, a mapping (e.g. a TOML table) or None
    (defaults). Bad mappings raise UserError naming the agent."""
    cls = agent_class(name).config_class
    if config is None:
        return cls()
    if isinstance(config, QLearningConfig):
        if not isinstance(config, cls):
            raise UserError(f"agent {name!r} expects a {cls.__name__}, got {type(config).__name__}")
        return config
    try:
        return cls.from_mapping(config)
    except (ValueError, TypeError) as error:
        raise UserError(f"agent {name!r}: {error}") from None


def make_agent(
    name: str,
    n_states: int,
    n_actions: int,
    config: QLearningConfig | Mapping[str, Any] | None = None,
    rng: np.random.Generator | None = None,
    **context: Any,
) -> TabularAgent:
    """A new agent ``name`` for ``n_states`` × ``n_actions``.

    ``config``: the agent's config dataclass, a mapping of its fields, or None for defaults.
    ``rng``: the generator every random draw of the agent comes from (a fresh unseeded one if
    None). ``context``: extra keyword arguments passed to the agent class (e.g. the navigation task
    a kinematic-model agent needs); the classic agents take none.
    """
    cls = agent_class(name)
    return cls(n_states, n_actions, make_config(name, config), rng, **context)


def load_agent(path: str | Path, **context: Any) -> TabularAgent:
    """Read an agent written by ``agent.save(path)``; CorruptFileError naming the file if either
    file is missing, damaged or inconsistent (checked before any kernel touches the arrays)."""
    npz_path, json_path = save_paths(path)
    meta = _read_meta(json_path)
    try:
        name = str(meta["agent"])
        config = agent_class(name).config_class.from_mapping(_mapping(meta, "config"))
        agent = agent_class(name)(
            int(meta["n_states"]), int(meta["n_actions"]), config, None, **context
        )
        with np.load(npz_path, allow_pickle=False) as archive:
            arrays = {key: archive[key] for key in archive.files}
        agent._restore(meta, arrays)
    except KeyError as error:
        raise CorruptFileError(
            f"{npz_path}: cannot load agent: missing {error.args[0]!r}"
        ) from None
    except _LOAD_ERRORS as error:
        raise CorruptFileError(f"{npz_path}: cannot load agent: {_first_line(error)}") from None
    return agent


_LOAD_ERRORS = (
    OSError, ValueError, TypeError, IndexError, EOFError, zipfile.BadZipFile, zlib.error,
    NotImplementedError, UserError,
)  # fmt: skip
"""What reading a damaged file can raise (a CorruptFileError is a UserError; zipfile raises
NotImplementedError for a damaged compression-method field)."""


def _first_line(error: BaseException) -> str:
    return str(error).splitlines()[0] if str(error) else type(error).__name__


def _read_meta(json_path: Path) -> dict[str, Any]:
    """The JSON object of a saved agent; CorruptFileError naming the file otherwise."""
    try:
        meta = json.loads(json_path.read_text())
    except (OSError, ValueError) as error:
        raise CorruptFileError(f"{json_path}: cannot load agent: {_first_line(error)}") from None
    if not isinstance(meta, dict):
        raise CorruptFileError(
            f"{json_path}: cannot load agent: expected a JSON object, got {type(meta).__name__}"
        )
    if meta.get("format") != SAVE_FORMAT or meta.get("version") != SAVE_VERSION:
        raise CorruptFileError(f"{json_path}: not a skidnav agent file of version {SAVE_VERSION}")
    return meta


def _mapping(meta: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    value = meta[key]
    if not isinstance(value, Mapping):
        raise ValueError(f"expected {key!r} to be a JSON object, got {type(value).__name__}")
    return value
