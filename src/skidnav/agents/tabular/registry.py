"""Agents by name: :func:`make_agent`, :func:`load_agent`, :func:`available_agents`.

Convention for an agent module (docs/agents/core.md): it defines ``AGENT_NAME`` (the registry name)
and ``AGENT_CLASS`` (a :class:`~skidnav.agents.tabular.agent.TabularAgent` subclass whose ``name``
equals ``AGENT_NAME`` and whose ``config_class`` is its frozen config dataclass). The registry maps
names to module paths and imports a module only when its agent is asked for.

>>> import numpy as np
>>> agent = make_agent("dyna-q", 10, 4, {"planning_steps": 3}, np.random.default_rng(0))
>>> type(agent).__name__, agent.config.planning_steps
('DynaQAgent', 3)
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from skidnav.agents.config import KinematicModelFields, QLearningConfig
from skidnav.agents.saving import save_paths
from skidnav.agents.tabular.agent import SAVE_FORMAT, SAVE_VERSION, TabularAgent
from skidnav.errors import CorruptFileError, UserError, shown, within
from skidnav.files.saved import READ_ERRORS, ArraySpec, SavedArchive, loading, read_json, up_to

AGENT_MODULES: dict[str, str] = {
    "q-learning": "skidnav.agents.tabular.q_learning",
    "dyna-q": "skidnav.agents.tabular.dyna_q",
    "dyna-q-plus": "skidnav.agents.tabular.dyna_q_plus",
    "prioritized-sweeping": "skidnav.agents.tabular.prioritized_sweeping",
    "dyna-kinematic": "skidnav.agents.tabular.dyna_kinematic",
    "trajectory-prioritized": "skidnav.agents.tabular.trajectory_prioritized",
    "dyna-full": "skidnav.agents.tabular.dyna_full",
    "dyna-sweep": "skidnav.agents.tabular.dyna_sweep",
}
"""Registry name → module defining ``AGENT_NAME`` and ``AGENT_CLASS``."""


def agent_class(name: str) -> type[TabularAgent]:
    """The agent class registered as ``name``; UserError if unknown."""
    module_name = AGENT_MODULES.get(name)
    if module_name is None:
        raise UserError(f"unknown agent {shown(name)}; expected one of {', '.join(AGENT_MODULES)}")
    module = importlib.import_module(module_name)
    cls: type[TabularAgent] = module.AGENT_CLASS
    if {module.AGENT_NAME, cls.name} != {name}:
        raise RuntimeError(f"{module_name} registers {module.AGENT_NAME!r}, expected {name!r}")
    return cls


def available_agents() -> list[str]:
    """Names of the registered agents, in registry order."""
    return list(AGENT_MODULES)


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
        raise within(error, f"agent {name!r}") from None


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


MAX_TABLE_ENTRIES = 2**26
"""Largest Q table a saved agent may declare, n_states × n_actions (512 MiB of float64; the
thesis arena has 12,500 × 4)."""
MAX_COUNTER = 2**62
"""Largest step, episode or planning-update count a saved agent may declare."""
MAX_AGENT_JSON_BYTES = 2**20
"""Largest ``.json`` of a saved agent [bytes] (they are a few kilobytes)."""
_LOAD_ERRORS = (*READ_ERRORS, IndexError, UserError)
"""What restoring from damaged arrays can raise (a CorruptFileError is a UserError)."""
_GEOMETRY_CONTEXT = ("task", "robot", "discretization", "true_kinematics")


def load_agent(path: str | Path, **context: Any) -> TabularAgent:
    """Read an agent written by ``agent.save(path)``; CorruptFileError naming the file if either
    file is missing, damaged, inconsistent or larger than its metadata allow.

    Nothing in the files is trusted before it is checked (docs/agents/core.md, "Saved files"):
    the JSON (size, nesting, integer sizes and counters within bounds, the config validated as
    a new one) before any array is allocated; the archive's member names against the arrays a
    new agent of that metadata saves, and each array's header (dtype, shape) and stored size
    against them, before any data is read; the Q table finite; then the agent's own checks.
    """
    npz_path, json_path = save_paths(path)
    saved = _read_meta(json_path)
    with loading(npz_path, "agent", _LOAD_ERRORS):
        with SavedArchive(npz_path) as archive:
            agent = _fresh_agent(saved, archive, context)
            arrays = archive.read_all(_expected_arrays(agent, saved.steps))
        if not np.isfinite(arrays["q"]).all():
            raise CorruptFileError("the Q table holds NaN or infinite values")
        agent._restore(saved.meta, arrays)
    return agent


class _SavedMeta(NamedTuple):
    """The checked JSON of a saved agent."""

    meta: dict[str, Any]
    cls: type[TabularAgent]
    n_states: int
    n_actions: int
    config: QLearningConfig
    steps: int
    geometry: dict[str, Any]
    """The saved geometry of a model-based agent as constructor arguments (else empty)."""


def _read_meta(json_path: Path) -> _SavedMeta:
    """The JSON of a saved agent, checked (no array allocated yet); CorruptFileError naming the
    file otherwise."""
    meta = read_json(json_path, max_bytes=MAX_AGENT_JSON_BYTES, what="agent file")
    if meta.get("format") != SAVE_FORMAT or meta.get("version") != SAVE_VERSION:
        raise CorruptFileError(f"{json_path}: not a skidnav agent file of version {SAVE_VERSION}")
    with loading(json_path, "agent", (ValueError, TypeError, UserError)):
        cls = agent_class(_string(meta, "agent"))
        n_states = _integer(meta, "n_states", 1, MAX_TABLE_ENTRIES)
        n_actions = _integer(meta, "n_actions", 1, MAX_TABLE_ENTRIES // n_states)
        config = cls.config_class.from_mapping(_mapping(meta, "config"))
        counters = _mapping(meta, "counters")
        steps = _integer(counters, "steps", 0, MAX_COUNTER, "counter ")
        for name in ("episodes", "planning_updates"):
            _integer(counters, name, 0, MAX_COUNTER, "counter ")
        _mapping(meta, "rng")
        geometry = _saved_geometry(cls, n_states, config, meta)
    return _SavedMeta(meta, cls, n_states, n_actions, config, steps, geometry)


def _integer(values: Mapping[str, Any], key: str, low: int, high: int, what: str = "") -> int:
    """``values[key]`` if it is an integer (not a bool, not 12500.7) in [low, high]."""
    value = values[key]
    if not (isinstance(value, int) and not isinstance(value, bool) and low <= value <= high):
        raise ValueError(
            f"expected {what}{key} to be an integer in [{low}, {high:,}], got {shown(value)}"
        )
    return value


def _string(values: Mapping[str, Any], key: str) -> str:
    value = values[key]
    if not isinstance(value, str):
        raise ValueError(f"expected {key!r} to be a string, got {type(value).__name__}")
    return value


def _fresh_agent(
    saved: _SavedMeta, archive: SavedArchive, context: Mapping[str, Any]
) -> TabularAgent:
    """A new agent of the saved metadata (a model-based one with the saved geometry, which
    replaces any geometry in ``context``), built only once the archive's Q table is known to
    have the declared shape."""
    archive.header("q", ArraySpec((saved.n_states, saved.n_actions), "<f8"))
    if saved.geometry:
        kept = {key: value for key, value in context.items() if key not in _GEOMETRY_CONTEXT}
        context = {**kept, **saved.geometry}
    return saved.cls(saved.n_states, saved.n_actions, saved.config, None, **context)


def _saved_geometry(
    cls: type[TabularAgent], n_states: int, config: QLearningConfig, meta: Mapping[str, Any]
) -> dict[str, Any]:
    """The robot and discretization a model-based agent saved in its JSON (empty for the other
    agents), and the true kinematics of one whose ``kinematic_model`` is "true", checked so that
    the agent built from them allocates no more than its metadata declare: its states those of
    the Q table, no more slip regions than cells along each axis, a kinematic model within
    bounds, a true-kinematics table of its regions."""
    from skidnav.agents.geometry import geometry_from_json
    from skidnav.agents.planner_state import true_kinematics_from_json
    from skidnav.agents.tabular.model_based import ModelBasedAgent
    from skidnav.models.kinematic_files import check_model_size

    if not issubclass(cls, ModelBasedAgent):
        return {}
    robot, grid = geometry_from_json(meta["geometry"])
    if grid is None:
        return {"robot": robot}
    if grid.n_states != n_states:
        raise ValueError(f"saved geometry has {grid.n_states} states, expected {n_states}")
    if grid.regions_x > grid.n_x or grid.regions_y > grid.n_y:
        raise ValueError(
            f"saved geometry has {grid.regions_x} × {grid.regions_y} slip regions for "
            f"{grid.n_x} × {grid.n_y} cells"
        )
    geometry: dict[str, Any] = {"robot": robot, "discretization": grid}
    if isinstance(config, KinematicModelFields):
        check_model_size(grid, config.kinematic_config())
        if config.kinematic_model == "true":
            geometry["true_kinematics"] = true_kinematics_from_json(
                meta["true_kinematics"], grid.n_regions
            )
    return geometry


def _expected_arrays(agent: TabularAgent, steps: int) -> dict[str, ArraySpec]:
    """What the archive of ``agent`` may hold: the arrays a new agent saves, with their dtypes
    and shapes; the lists that are empty in a new agent (model entries, queues, trajectories,
    visited states) hold at most one item per state-action pair or per real step."""
    rows = up_to(max(agent.q.size, steps, 3))
    specs = {}
    for name, array in {"q": agent.q, **agent._state_arrays()}.items():
        shape: tuple[int | range, ...] = tuple(array.shape)
        if array.ndim >= 1 and array.shape[0] == 0:
            shape = (rows, *array.shape[1:])
        specs[name] = ArraySpec(shape, array.dtype.str)
    return specs


def _mapping(meta: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    value = meta[key]
    if not isinstance(value, Mapping):
        raise ValueError(f"expected {key!r} to be a JSON object, got {type(value).__name__}")
    return value
