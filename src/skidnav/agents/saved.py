"""Saved agents and policies of any family, loaded by what their ``.json`` says they are.

Every agent saves itself as ``path.npz`` + ``path.json`` (:meth:`~skidnav.agents.interface.
Agent.save`, never pickle), and the ``"format"`` of the ``.json`` names its family
(:attr:`~skidnav.agents.family.Family.save_formats`). :func:`load_saved_agent` hands the files
to that family's loader, with every check of the loader; :func:`load_policy` to its policy
loader, for the robot (``skidnav robot run --policy-file``).

>>> import json, tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> _ = (folder / "policy.json").write_text(json.dumps({"format": "some-learner"}))
>>> try:
...     load_policy(folder / "policy")  # the stem works too
... except UserError as error:
...     print(str(error).split(": ", 1)[1])
not a saved skidnav agent or policy (format 'some-learner')
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import gymnasium

from skidnav.agents.catalog import families, family_of_format
from skidnav.agents.family import Family
from skidnav.agents.interface import Agent
from skidnav.agents.saving import save_paths
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import CorruptFileError, UserError, shown
from skidnav.files.saved import read_json

MAX_JSON_BYTES = 16 * 2**20
"""Largest ``.json`` of a saved agent or policy read to tell its family [bytes] (they are
kilobytes; the arrays are in the ``.npz``)."""

SavedPath = str | Path | Sequence[str | Path]
"""Where an agent was saved: ``path`` as given to ``save``, either of its two files, or the pair
of paths ``save`` returned."""


def saved_json(path: SavedPath, what: str = "agent file") -> Path:
    """The ``.json`` file of a saved agent or policy at ``path`` (:data:`SavedPath`: a pair's
    ``.json`` member, else ``path`` with a ``.npz``/``.json`` suffix replaced); UserError for a
    path that names no file (empty, ``.``, ``/``) or a pair without a ``.json`` (``what``:
    the kind of file the message names)."""
    if not isinstance(path, (str, Path)):
        found = [Path(p) for p in path if isinstance(p, (str, Path)) and str(p).endswith(".json")]
        if len(found) != 1:
            raise UserError(f"expected the path of a {what} or its two files, got {path!r}")
        return found[0]
    if not Path(path).name:
        raise UserError(f"{str(path)!r}: not the path of a {what}")
    return save_paths(path)[1]


def saved_family(
    path: SavedPath, what: str = "agent file"
) -> tuple[Path, dict[str, Any], Family[Any]]:
    """(the ``.json`` path, its content, the family of its format) of the agent or policy saved
    at ``path``: which door it goes through (``skidnav robot run --agent-file``);
    CorruptFileError in one line naming the file when it is unreadable or of no family's
    format."""
    return _saved(path, what)


def _saved(path: SavedPath, what: str) -> tuple[Path, dict[str, Any], Family[Any]]:
    """(the ``.json`` path, its content, the family of its format); CorruptFileError in one line
    naming the ``what`` (``"agent file"``, ``"policy file"``) when it is unreadable or of no
    family's format."""
    json_path = saved_json(path, what)
    meta = read_json(json_path, max_bytes=MAX_JSON_BYTES, what=what)
    kind = meta.get("format")
    described = family_of_format(kind)
    if described is None:
        raise CorruptFileError(
            f"{json_path}: not a saved skidnav agent or policy (format {shown(kind)})"
        )
    return json_path, meta, described


def load_saved_agent(path: SavedPath, env: gymnasium.Env[Any, Any] | None = None) -> Agent:
    """The agent saved at ``path`` (:data:`SavedPath`) by ``agent.save(path)``, of whichever
    family.

    ``env`` is the environment the agent will act in: a deep agent needs it (its networks are
    built on the env's spaces), a tabular agent that plans on the navigation task takes the
    env's task from it; the others ignore it.

    Raises:
        CorruptFileError: a file is missing, damaged, or not a skidnav agent (one line naming
            it).
        UserError: a deep agent without ``env``, or its extra missing.
    """
    json_path, meta, described = _saved(path, "agent file")
    return described.load(json_path, meta, env)


def load_policy(path: SavedPath) -> WheelSpeedPolicy:
    """The frozen wheel-speed policy saved at ``path`` (:data:`SavedPath`), by its family's
    policy loader (:attr:`~skidnav.agents.family.Family.policy`).

    Raises:
        UserError: one line naming the file: unreadable, of no family's format, of a family
            whose agents do not drive by wheel speeds, or refused by the loader.
    """
    json_path, meta, described = _saved(path, "policy file")
    if described.policy is None:
        drivers = ", ".join(f.name for f in families() if f.policy is not None)
        raise UserError(
            f"{json_path}: a saved {described.name} agent does not drive by wheel speeds (policies "
            f"come from the {drivers} families)"
        )
    policy = described.policy(json_path, meta)
    if not isinstance(policy, WheelSpeedPolicy):
        raise UserError(f"{json_path}: the {described.name} loader returned no wheel-speed policy")
    return policy
