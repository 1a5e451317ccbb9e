"""Saved continuous policies by file format: :func:`load_policy` and :data:`POLICY_LOADERS`.

A learner that hands out :class:`~skidnav.agents.policies.wheel_policy.WheelSpeedPolicy` objects
saves them as a JSON file (``NAME.json``, beside whatever arrays it needs, e.g. ``NAME.npz``) whose
``"format"`` field names the learner's format. :func:`load_policy` reads that field and hands the
file to the loader registered for it, so ``skidnav robot run --policy-file NAME.json`` runs any
learner's policy without knowing the learner.

To register a format, add ``"FORMAT": "package.module:function"`` to :data:`POLICY_LOADERS`;
the module is imported only when a file of that format is loaded. The function takes the path
of the JSON file and its parsed content and returns the policy; it raises
:class:`~skidnav.errors.UserError` (or :class:`~skidnav.errors.CorruptFileError`) in one line
naming the file for anything it cannot use.

>>> import json, tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> _ = (folder / "policy.json").write_text(json.dumps({"format": "some-learner"}))
>>> try:
...     load_policy(folder / "policy")  # the stem works too
... except UserError as error:
...     for part in str(error).split(": ", 1)[1].split("; "):
...         print(part)
unknown policy format 'some-learner'
expected one of skidnav-tanh-policy, skidnav-ppo, skidnav-sac, skidnav-mppi-agent
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from skidnav.agents.policies.wheel_policy import WheelSpeedPolicy
from skidnav.agents.saving import save_paths
from skidnav.errors import CorruptFileError, UserError, shown
from skidnav.files.saved import read_json

POLICY_LOADERS: dict[str, str] = {
    "skidnav-tanh-policy": "skidnav.agents.policies.search.policy_file:policy_from_file",
    "skidnav-ppo": "skidnav.agents.deep.ppo:policy_from_file",
    "skidnav-sac": "skidnav.agents.deep.sac:policy_from_file",
    "skidnav-mppi-agent": "skidnav.agents.mpc.loading:policy_from_file",
}
"""A saved policy's ``"format"`` → ``"package.module:function"`` loading it (module doc)."""

MAX_POLICY_JSON_BYTES = 16 * 2**20
"""Largest policy JSON file read [bytes] (the arrays belong in a ``.npz`` beside it)."""


def policy_json(path: str | Path) -> Path:
    """The JSON file of a saved policy: ``path`` itself if it ends in ``.json``, else
    ``path`` + ``.json`` (a ``.npz`` suffix replaced), as for saved agents; UserError for a
    path that names no file (empty, ``.``, ``/``)."""
    if not Path(path).name:
        raise UserError(f"{str(path)!r}: not the path of a policy file")
    return save_paths(path)[1]


def load_policy(path: str | Path) -> WheelSpeedPolicy:
    """The policy saved at ``path`` (see :func:`policy_json`), by the loader of its format.

    Raises:
        UserError: one line naming the file: unreadable, not a JSON object with a string
            ``"format"``, a format nobody registered, or a loader that refused the file or
            returned no :class:`~skidnav.agents.policies.wheel_policy.WheelSpeedPolicy`.
    """
    json_path = policy_json(path)
    data = read_json(json_path, max_bytes=MAX_POLICY_JSON_BYTES, what="policy file")
    kind = data.get("format")
    if not isinstance(kind, str):
        raise CorruptFileError(f"{json_path}: expected a string 'format' field, got {shown(kind)}")
    target = POLICY_LOADERS.get(kind)
    if target is None:
        known = ", ".join(POLICY_LOADERS) or None
        expected = f"expected one of {known}" if known else "no policy formats are registered yet"
        raise UserError(f"{json_path}: unknown policy format {kind!r}; {expected}")
    policy = _loader(target)(json_path, data)
    if not isinstance(policy, WheelSpeedPolicy):
        raise UserError(f"{json_path}: the {kind!r} loader returned no wheel-speed policy")
    return policy


def _loader(target: str) -> Any:
    """The function ``"package.module:function"`` names (imported now)."""
    module_name, _, function = target.partition(":")
    return getattr(importlib.import_module(module_name), function)
