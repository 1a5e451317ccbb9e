"""Linear agents by name: :func:`make_linear_agent`, :func:`load_linear_agent`.

The same convention as :mod:`skidnav.agents.tabular.registry` (each module defines ``AGENT_NAME``
and ``AGENT_CLASS``, imported only when asked for), for agents on ``Box`` observations.

>>> import numpy as np
>>> from gymnasium.spaces import Box
>>> space = Box(low=np.zeros(2), high=np.ones(2), dtype=np.float64)
>>> agent = make_linear_agent("linear-q", space, 3, {"tiles": [2]}, np.random.default_rng(0))
>>> agent.n_features  # 8 tilings × 3 × 3
72
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from skidnav.agents.linear.agent import SAVE_FORMAT, SAVE_VERSION, LinearAgent
from skidnav.agents.linear.config import LinearConfig
from skidnav.agents.saving import save_paths
from skidnav.errors import CorruptFileError, UserError, first_line, shown
from skidnav.files.saved import ArraySpec, SavedArchive, loading, read_json

CONTINUOUS_AGENT_MODULES: dict[str, str] = {
    "linear-q": "skidnav.agents.linear.q_learning",
    "linear-sarsa": "skidnav.agents.linear.sarsa",
    "linear-dyna": "skidnav.agents.linear.dyna",
    "linear-dyna-kinematic": "skidnav.agents.linear.dyna_kinematic",
}
"""Registry name → module defining ``AGENT_NAME`` and ``AGENT_CLASS``."""
MAX_AGENT_JSON_BYTES = 2**20
"""Largest ``.json`` of a saved linear agent [bytes]."""
MAX_DIMENSIONS = 1024
"""Most observation dimensions a saved agent may declare."""


def linear_agent_class(name: str) -> type[LinearAgent]:
    """The linear agent class registered as ``name``; UserError if unknown."""
    module_name = CONTINUOUS_AGENT_MODULES.get(name)
    if module_name is None:
        raise UserError(
            f"unknown agent {shown(name)}; expected one of {', '.join(CONTINUOUS_AGENT_MODULES)}"
        )
    module = importlib.import_module(module_name)
    cls: type[LinearAgent] = module.AGENT_CLASS
    if {module.AGENT_NAME, cls.name} != {name}:
        raise RuntimeError(f"{module_name} registers {module.AGENT_NAME!r}, expected {name!r}")
    return cls


def make_linear_agent(
    name: str,
    observation_space: spaces.Box,
    n_actions: int,
    config: LinearConfig | Mapping[str, Any] | None = None,
    rng: np.random.Generator | None = None,
    **context: Any,
) -> LinearAgent:
    """A new agent ``name`` for observations in ``observation_space`` (its bounds set the tile
    coder) and ``n_actions`` actions; ``config`` a config, a mapping of its fields or None;
    ``context`` the keyword arguments its constructor asks for (``task=`` for
    ``linear-dyna-kinematic``). UserError naming the agent for a bad config or space."""
    cls = linear_agent_class(name)
    if not isinstance(observation_space, spaces.Box):
        raise UserError(f"agent {name!r} expects a Box observation space, got {observation_space}")
    try:
        if not isinstance(config, LinearConfig):
            config = cls.config_class.from_mapping(config or {})
        return cls(observation_space.low, observation_space.high, n_actions, config, rng, **context)
    except (ValueError, TypeError) as error:
        raise UserError(f"agent {name!r}: {first_line(error)}") from None


def load_linear_agent(path: str | Path) -> LinearAgent:
    """Read an agent written by ``agent.save(path)``; CorruptFileError naming the file if either
    file is missing, damaged or inconsistent. The JSON is checked and a new agent of it built
    (its constructor bounds every array) before the archive's names, dtypes and shapes are
    checked against that agent's arrays and any data is read."""
    npz_path, json_path = save_paths(path)
    meta = read_json(json_path, max_bytes=MAX_AGENT_JSON_BYTES, what="agent file")
    if meta.get("format") != SAVE_FORMAT or meta.get("version") != SAVE_VERSION:
        raise CorruptFileError(
            f"{json_path}: not a skidnav linear agent file of version {SAVE_VERSION}"
        )
    with loading(json_path, "agent", (ValueError, TypeError, UserError)):
        agent = _fresh_agent(meta)
        counters, rng_state = meta["counters"], meta["rng"]
        if not isinstance(counters, Mapping) or not isinstance(rng_state, Mapping):
            raise ValueError("expected counters and rng to be JSON objects")
    specs = {
        name: ArraySpec(tuple(array.shape), array.dtype.str)
        for name, array in agent.state_arrays().items()
    }
    with loading(npz_path, "agent"):
        with SavedArchive(npz_path) as archive:
            arrays = archive.read_all(specs)
        agent.restore(counters, rng_state, arrays)
    return agent


def _fresh_agent(meta: Mapping[str, Any]) -> LinearAgent:
    """A new agent of the saved name, bounds, actions and config (not yet restored)."""
    cls = linear_agent_class(str(meta["agent"]))
    low, high = _bounds(meta["low"]), _bounds(meta["high"])
    n_actions = meta["n_actions"]
    if not isinstance(n_actions, int) or isinstance(n_actions, bool):
        raise ValueError(f"expected an integer n_actions, got {shown(n_actions)}")
    config = meta["config"]
    if not isinstance(config, Mapping):
        raise ValueError("expected config to be a JSON object")
    context = cls.context_from_json(meta)
    return cls(low, high, n_actions, cls.config_class.from_mapping(config), None, **context)


def _bounds(value: Any) -> np.ndarray:
    """A saved bound: a list of at most :data:`MAX_DIMENSIONS` numbers (finiteness is the
    constructor's check)."""
    if not (isinstance(value, list) and 0 < len(value) <= MAX_DIMENSIONS) or not all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in value
    ):
        raise ValueError(
            f"expected bounds as a list of up to {MAX_DIMENSIONS} numbers, got {shown(value)}"
        )
    return np.array(value, dtype=np.float64)
