"""How every family saves an agent: the two files of a saved agent and its random generator.

An agent of any family saves itself as ``path.npz`` (arrays) and ``path.json`` (config, counters,
generator state): never pickle. :func:`save_paths` names the two files, :func:`generator_state`
and :func:`generator_from_state` carry a ``numpy.random.Generator`` through the JSON.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.errors import shown


def save_paths(path: str | Path) -> tuple[Path, Path]:
    """The ``.npz`` and ``.json`` files of a saved agent; a ``.npz``/``.json`` suffix is dropped."""
    base = Path(path)
    if base.suffix in (".npz", ".json"):
        base = base.with_suffix("")
    return base.with_name(base.name + ".npz"), base.with_name(base.name + ".json")


def new_save_paths(path: str | Path) -> tuple[Path, Path]:
    """:func:`save_paths` of an agent about to be written: its folder is created if missing."""
    npz_path, json_path = save_paths(path)
    npz_path.parent.mkdir(parents=True, exist_ok=True)
    return npz_path, json_path


def generator_state(rng: np.random.Generator) -> dict[str, Any]:
    """The generator's bit-generator state as a JSON-able dict."""
    return dict(rng.bit_generator.state)


def generator_from_state(state: Mapping[str, Any]) -> np.random.Generator:
    """A generator restored from :func:`generator_state`; ValueError if unusable (the message
    quotes at most :data:`~skidnav.errors.EXCERPT_CHARS` characters of the saved state)."""
    name = state.get("bit_generator")
    bit_generator_class = getattr(np.random, str(name), None)
    if not isinstance(bit_generator_class, type) or not issubclass(
        bit_generator_class, np.random.BitGenerator
    ):
        raise ValueError(f"unknown bit generator {shown(name)}")
    bit_generator = bit_generator_class()
    try:
        bit_generator.state = dict(state)
    except (ValueError, TypeError, OverflowError, IndexError) as error:
        # NumPy's messages may quote the saved values whole: name only the kind of problem.
        raise ValueError(
            f"unusable {bit_generator_class.__name__} state ({type(error).__name__})"
        ) from None
    return np.random.Generator(bit_generator)
