"""The CMA-ES state between generations, saved so that a long search can resume exactly.

A checkpoint is ``NAME.npz`` + ``NAME.json`` (never pickle), written after a generation's
``tell``. The archive holds the optimizer's moving parts, float64: the mean m (n,), the
covariance matrix C (n, n), and the evolution paths
p_σ and p_c (n,). The JSON holds the step size σ, the generation counter, the search's config
and its learning curve so far. Everything else of the optimizer (weights, learning rates, the
termination history) is rebuilt from the config, so a file can change nothing but the state.
The optimizer's own random generator is not saved: the search reseeds it at every generation
from the root seed (:func:`skidnav.policysearch.search.sampler_seed`), so a resumed search draws
what an uninterrupted one would. The termination history (``should_stop``) is not restored;
the search stops after its generations, never on it.

The optimizer is ``cmaes.CMA`` (Nomura & Shibata 2024, arXiv:2402.01373); its state entries are read
and written by name (the attributes its pickle support copies; C itself rather than the
triangle pickle keeps, whose copy back makes C symmetric and so changes its last bits), and a
version of ``cmaes`` that names them otherwise is refused in one line.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from cmaes import CMA

from skidnav.agents.core import save_paths
from skidnav.atomicfile import write_atomic, write_npz_atomic
from skidnav.errors import CorruptFileError, first_line, shown
from skidnav.policysearch.config import SearchConfig
from skidnav.savedfile import ArraySpec, SavedArchive, read_json

CHECKPOINT_FORMAT = "skidnav-cmaes-checkpoint"
CHECKPOINT_VERSION = 1
STATE_ARRAYS = {"mean": "_mean", "covariance": "_C", "path_sigma": "_p_sigma", "path_c": "_pc"}
"""Archive name → the optimizer's state entry."""
MAX_CHECKPOINT_JSON_BYTES = 64 * 2**20


def new_optimizer(config: SearchConfig, n_parameters: int) -> CMA:
    """CMA-ES over ``n_parameters`` parameters from the zero vector (the policy that stands
    still) with step size ``config.sigma0`` and ``config.population`` candidates."""
    return CMA(
        mean=np.zeros(n_parameters), sigma=float(config.sigma0), population_size=config.population
    )


def _state(optimizer: CMA) -> dict[str, Any]:
    """The optimizer's attributes (its own ``__dict__``, not a copy)."""
    state: dict[str, Any] = vars(optimizer)
    missing = [name for name in (*STATE_ARRAYS.values(), "_sigma", "_g") if name not in state]
    if missing:
        raise CorruptFileError(f"this version of cmaes has no state entry {missing[0]!r}")
    return state


def save_checkpoint(
    path: str | Path,
    optimizer: CMA,
    config: SearchConfig,
    records: list[dict[str, Any]],
) -> tuple[Path, Path]:
    """Write the optimizer's state after a ``tell``, ``config`` and the learning curve
    ``records`` (JSON-able dicts, :func:`~skidnav.policysearch.search.record_rows`) to
    ``path.npz`` / ``path.json``, atomically. Returns both paths; raises OSError."""
    state = _state(optimizer)
    assert state["_B"] is None and state["_D"] is None, "checkpoint only after a tell"
    npz_path, json_path = save_paths(path)
    write_npz_atomic(
        npz_path,
        {name: np.asarray(state[key], dtype=np.float64) for name, key in STATE_ARRAYS.items()},
    )
    meta = {
        "format": CHECKPOINT_FORMAT,
        "version": CHECKPOINT_VERSION,
        "sigma": float(state["_sigma"]),
        "generation": int(state["_g"]),
        "config": config.to_dict(),
        "records": records,
    }
    write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
    return npz_path, json_path


def load_checkpoint(
    path: str | Path, n_parameters: int
) -> tuple[CMA, SearchConfig, list[dict[str, Any]]]:
    """(optimizer, saved config, learning curve) of :func:`save_checkpoint` for a policy of
    ``n_parameters`` parameters; CorruptFileError naming the file otherwise."""
    npz_path, json_path = save_paths(path)
    meta = read_json(json_path, max_bytes=MAX_CHECKPOINT_JSON_BYTES, what="checkpoint")
    if meta.get("format") != CHECKPOINT_FORMAT or meta.get("version") != CHECKPOINT_VERSION:
        raise CorruptFileError(f"{json_path}: not a skidnav CMA-ES checkpoint of version 1")
    try:
        config = SearchConfig.from_dict(dict(meta["config"]))
        sigma, generation = meta["sigma"], meta["generation"]
        if isinstance(sigma, bool) or not isinstance(sigma, int | float) or not sigma > 0:
            raise ValueError(f"expected sigma > 0, got {shown(sigma)}")
        if isinstance(generation, bool) or not isinstance(generation, int) or generation < 1:
            raise ValueError(f"expected generation to be an integer >= 1, got {shown(generation)}")
        records = _records(meta["records"], generation)
    except (KeyError, TypeError, ValueError) as error:
        raise CorruptFileError(f"{json_path}: cannot resume: {first_line(error)}") from None
    optimizer = new_optimizer(config, n_parameters)
    state = _state(optimizer)
    specs = {name: ArraySpec((n_parameters,), "<f8") for name in STATE_ARRAYS}
    specs["covariance"] = ArraySpec((n_parameters, n_parameters), "<f8")
    with SavedArchive(npz_path) as archive:
        arrays = archive.read_all(specs)
    if not all(np.isfinite(array).all() for array in arrays.values()):
        raise CorruptFileError(f"{npz_path}: cannot resume: a state value is NaN or infinite")
    state.update({STATE_ARRAYS[name]: np.array(array) for name, array in arrays.items()})
    state.update(_sigma=float(sigma), _g=generation, _B=None, _D=None)
    return optimizer, config, records


def _records(values: Any, generation: int) -> list[dict[str, Any]]:
    """The saved learning curve: one object of numbers (or nulls) per generation
    0 .. ``generation``, null → NaN."""
    if not isinstance(values, list) or len(values) != generation + 1:
        raise ValueError(f"expected {generation + 1} records")
    records = []
    for value in values:
        if not isinstance(value, dict) or not all(
            item is None or (isinstance(item, int | float) and not isinstance(item, bool))
            for item in value.values()
        ):
            raise ValueError(f"expected a record object of numbers, got {shown(value)}")
        records.append({key: math.nan if item is None else item for key, item in value.items()})
    return records
