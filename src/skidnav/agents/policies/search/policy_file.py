"""Saved tanh policies: ``NAME.npz`` (the arrays) and ``NAME.json`` (what they mean), no pickle.

The archive holds three float64 arrays: ``parameters`` (n,), ``observation_low`` and
``observation_high`` (d,). The JSON holds the format and version, the layout's integers and floats
(``hidden``, ``lidar_rays``, ``lidar_range`` [m], ``wheel_speed`` [rad/s]) and free ``provenance``
(the search's config and counters). Loading reads the JSON first (size and nesting limited), derives
n and d from it, and checks every array's name, dtype and shape against them before any data is read
(:class:`skidnav.files.saved.SavedArchive`), then every parameter below
:data:`~skidnav.agents.policies.search.config.MAX_PARAMETER` in magnitude (as a search keeps them);
a bad file is one :class:`~skidnav.errors.CorruptFileError` line naming it.

>>> import tempfile
>>> import numpy as np
>>> from pathlib import Path
>>> from skidnav.agents.policies.search.tanh_policy import PolicyLayout, TanhPolicy
>>> layout = PolicyLayout(np.zeros(7), np.ones(7), hidden=2, wheel_speed=1.7, lidar_rays=0)
>>> path = Path(tempfile.mkdtemp()) / "policy"
>>> _ = save_policy(TanhPolicy(layout, np.arange(layout.n_parameters) / 10), path)
>>> load_policy(path).parameters[:3]
array([0. , 0.1, 0.2])
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skidnav.agents.policies.search.config import MAX_PARAMETER
from skidnav.agents.policies.search.tanh_policy import (
    MAX_HIDDEN,
    MAX_LIDAR_RAYS,
    PolicyLayout,
    TanhPolicy,
    parameter_count,
)
from skidnav.agents.saving import new_save_paths, save_paths
from skidnav.checks import check_magnitude, check_number
from skidnav.errors import CorruptFileError, first_line, shown
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.files.saved import ArraySpec, SavedArchive, read_json

SAVE_FORMAT = "skidnav-tanh-policy"
SAVE_VERSION = 1
MAX_POLICY_JSON_BYTES = 1 << 20
"""Largest policy JSON read [bytes] (a few kilobytes with the provenance)."""


def save_policy(
    policy: TanhPolicy, path: str | Path, provenance: Mapping[str, Any] | None = None
) -> tuple[Path, Path]:
    """Write ``path.npz`` and ``path.json`` (a ``.npz``/``.json`` suffix of ``path`` is dropped),
    each atomically; ``provenance`` (JSON-able) is stored as it is. Returns both paths; raises
    OSError."""
    npz_path, json_path = new_save_paths(path)
    layout = policy.layout
    arrays = {
        "parameters": policy.parameters,
        "observation_low": layout.observation_low,
        "observation_high": layout.observation_high,
    }
    write_npz_atomic(npz_path, arrays)
    meta = {
        "format": SAVE_FORMAT,
        "version": SAVE_VERSION,
        "hidden": layout.hidden,
        "lidar_rays": layout.lidar_rays,
        "lidar_range": layout.lidar_range,
        "wheel_speed": layout.wheel_speed,
        "n_parameters": layout.n_parameters,
        "provenance": dict(provenance or {}),
    }
    write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
    return npz_path, json_path


def load_policy(path: str | Path) -> TanhPolicy:
    """The policy of :func:`save_policy`; CorruptFileError naming the file when it is missing,
    damaged, of another format, or its arrays do not fit its JSON."""
    json_path = save_paths(path)[1]
    meta = read_json(json_path, max_bytes=MAX_POLICY_JSON_BYTES, what="policy file")
    return policy_from_file(json_path, meta)


def policy_from_file(json_path: Path, meta: Mapping[str, Any]) -> TanhPolicy:
    """The policy of the JSON file ``json_path`` already parsed as ``meta``, its arrays read from
    the ``.npz`` beside it (the ``function(path, content)`` a registry of policy formats such as
    :mod:`skidnav.agents.policies.family` calls); CorruptFileError as :func:`load_policy`."""
    npz_path = save_paths(json_path)[0]
    if meta.get("format") != SAVE_FORMAT or meta.get("version") != SAVE_VERSION:
        raise CorruptFileError(
            f"{json_path}: not a skidnav tanh policy of version {SAVE_VERSION} "
            f"(format {shown(meta.get('format'))}, version {shown(meta.get('version'))})"
        )
    hidden = _integer(meta, "hidden", MAX_HIDDEN, json_path)
    rays = _integer(meta, "lidar_rays", MAX_LIDAR_RAYS, json_path)
    n_inputs = 7 + rays
    n_parameters = parameter_count(n_inputs, hidden)
    if meta.get("n_parameters") != n_parameters:
        raise CorruptFileError(
            f"{json_path}: n_parameters {shown(meta.get('n_parameters'))} does not fit "
            f"hidden {hidden} and lidar_rays {rays} (expected {n_parameters})"
        )
    specs = {
        "parameters": ArraySpec((n_parameters,), "<f8"),
        "observation_low": ArraySpec((n_inputs,), "<f8"),
        "observation_high": ArraySpec((n_inputs,), "<f8"),
    }
    with SavedArchive(npz_path) as archive:
        arrays = archive.read_all(specs)
    try:
        check_magnitude("parameters", arrays["parameters"], MAX_PARAMETER)
    except ValueError as error:
        raise CorruptFileError(f"{npz_path}: {error}") from None
    try:
        layout = PolicyLayout(
            arrays["observation_low"], arrays["observation_high"], hidden=hidden,
            wheel_speed=check_number("wheel_speed", meta.get("wheel_speed"), 0.0),
            lidar_rays=rays, lidar_range=check_number("lidar_range", meta.get("lidar_range"), 0.0),
        )  # fmt: skip
        return TanhPolicy(layout, arrays["parameters"])
    except ValueError as error:
        where = npz_path.with_suffix("")  # the bounds come from one file, the rest from the other
        raise CorruptFileError(f"{where}: cannot load policy: {first_line(error)}") from None


def _integer(meta: Mapping[str, Any], name: str, high: int, where: Path) -> int:
    """``meta[name]`` if it is an integer in [0, high]; CorruptFileError otherwise."""
    value = meta.get(name)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= high:
        raise CorruptFileError(
            f"{where}: expected {name} to be an integer in [0, {high}], got {shown(value)}"
        )
    return value
