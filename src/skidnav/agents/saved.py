"""A saved agent of any family, loaded by what its ``.json`` says it is.

Every agent saves itself as ``path.npz`` + ``path.json`` (:meth:`~skidnav.agents.interface.
Agent.save`, never pickle), and each family reads its own files back with every check of its
loader: tabular (:func:`skidnav.agents.tabular.registry.load_agent`), linear
(:func:`skidnav.agents.linear.registry.load_linear_agent`) and deep
(:func:`skidnav.agents.deep.common.load_agent`, onto the env it acts in). :func:`load_saved_agent`
reads the ``format`` of the ``.json`` and hands the files to the loader of that family.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium

from skidnav.agents.catalog import DEEP_AGENTS, entry
from skidnav.agents.interface import Agent
from skidnav.agents.linear.agent import SAVE_FORMAT as LINEAR_FORMAT
from skidnav.agents.linear.registry import load_linear_agent
from skidnav.agents.saving import save_paths
from skidnav.agents.tabular.agent import SAVE_FORMAT as TABULAR_FORMAT
from skidnav.agents.tabular.registry import AGENT_MODULES, load_agent
from skidnav.errors import CorruptFileError, UserError, shown
from skidnav.files.saved import read_json

MAX_JSON_BYTES = 2**20
"""Largest ``.json`` of a saved agent read to tell its family [bytes] (they are kilobytes)."""
DEEP_FORMATS = {f"skidnav-{name}": name for name in DEEP_AGENTS}
"""The ``format`` of a saved deep agent's ``.json`` → its registry name."""


def load_saved_agent(path: str | Path, env: gymnasium.Env[Any, Any] | None = None) -> Agent:
    """The agent saved at ``path`` (``path.npz`` and ``path.json``; a ``.npz``/``.json`` suffix
    is dropped) by ``agent.save(path)``, of whichever family.

    ``env`` is the environment the agent will act in: a deep agent needs it (its networks are
    built on the env's spaces), a tabular agent that plans on the navigation task takes the
    env's task from it; the others ignore it.

    Raises:
        CorruptFileError: a file is missing, damaged, or not a skidnav agent (one line naming
            it).
        UserError: a deep agent without ``env``, or its extra missing.
    """
    json_path = save_paths(path)[1]
    meta = read_json(json_path, max_bytes=MAX_JSON_BYTES, what="agent file")
    kind = meta.get("format")
    if kind == TABULAR_FORMAT:
        name = meta.get("agent")
        context: dict[str, Any] = {}
        if env is not None and isinstance(name, str) and name in AGENT_MODULES:
            context = entry(name).context(env.unwrapped)
        return load_agent(path, **context)
    if kind == LINEAR_FORMAT:
        return load_linear_agent(path)
    if isinstance(kind, str) and kind in DEEP_FORMATS:
        name = DEEP_FORMATS[kind]
        if env is None:
            raise UserError(f"{json_path}: a saved {name} agent loads onto its env (pass env)")
        from skidnav.agents.deep.common import load_agent as load_deep_agent

        return load_deep_agent(entry(name).agent_class, path, env)  # type: ignore[type-var]
    raise CorruptFileError(f"{json_path}: not a saved skidnav agent (format {shown(kind)})")
