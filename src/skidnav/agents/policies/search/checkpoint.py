"""The CMA-ES state between generations, saved so that a long search can resume exactly.

A checkpoint is one file, ``NAME.npz`` (never pickle), written atomically after a generation's
``tell``, so that a kill at any moment leaves either the old checkpoint or the new one, whole. It
holds float64 arrays — the optimizer's moving parts, the mean m (n,), the covariance matrix C
(n, n), the evolution paths p_σ and p_c (n,), and the learning curve so far ``records`` (G + 1, 9)
(:func:`~skidnav.agents.policies.search.curve.records_table`) — and ``meta``, uint8, the UTF-8 JSON
of the format, the version, the step size σ, the generation G and the search's config.
``NAME.json``, written after it, is a copy for reading (and the mark of a search in a folder): the
same JSON with the curve as rows. On loading it must be that copy or an older generation's (a kill
between the two writes); anything else (an edited copy) is refused.

Everything else of the optimizer (weights, learning rates, the termination history) is rebuilt from
the config, so a file can change nothing but the state, and every value is checked before use: σ in
(0, 10³²] (cmaes caps σ there itself), every component of m below 10³² in magnitude (cmaes asserts
it of its mean and candidates: :data:`~skidnav.agents.policies.search.config.MAX_PARAMETER`), finite
paths and C, and the curve as the config's search writes it. The optimizer's own random generator is
not saved: the search reseeds it at every generation from the root seed
(:func:`skidnav.agents.policies.search.cmaes.sampler_seed`), so a resumed search draws what an
uninterrupted one would. The termination history (``should_stop``) is not restored; the search stops
after its generations, never on it.

The optimizer is ``cmaes.CMA`` (Nomura & Shibata 2024, arXiv:2402.01373); its state entries are read
and written by name (the attributes its pickle support copies; C itself rather than the
triangle pickle keeps, whose copy back makes C symmetric and so changes its last bits), and a
version of ``cmaes`` that names them otherwise is refused in one line.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import numpy as np
from cmaes import CMA

from skidnav.agents.policies.search.config import MAX_GENERATIONS, MAX_PARAMETER, SearchConfig
from skidnav.agents.policies.search.curve import (
    GenerationRecord,
    record_rows,
    records_from_table,
    records_table,
)
from skidnav.agents.saving import save_paths
from skidnav.checks import check_integer, check_magnitude, check_number
from skidnav.errors import CorruptFileError, first_line
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.files.saved import ArraySpec, SavedArchive, parse_json, read_json, up_to

logger = logging.getLogger(__name__)

CHECKPOINT_FORMAT = "skidnav-cmaes-checkpoint"
CHECKPOINT_VERSION = 2
"""2: one ``.npz`` holding everything (1: the state split over ``.npz`` and ``.json``)."""
STATE_ARRAYS = {"mean": "_mean", "covariance": "_C", "path_sigma": "_p_sigma", "path_c": "_pc"}
"""Archive name → the optimizer's state entry."""
META_SPEC = ArraySpec((up_to(1 << 20),), "|u1")
"""The ``meta`` member: UTF-8 bytes, at most a MiB (the config and three numbers: under a
kilobyte)."""
MAX_CHECKPOINT_JSON_BYTES = 512 * 2**20
"""Largest ``NAME.json`` copy read [bytes]: about 300 bytes per generation, so
:data:`~skidnav.agents.policies.search.config.MAX_GENERATIONS` of them fit."""
MAX_SIGMA = 1e32
"""Largest σ of a checkpoint: cmaes caps σ at this after every ``tell`` (its ``_SIGMA_MAX``)."""
MAX_COVARIANCE = MAX_PARAMETER**2
"""Largest magnitude of an entry of C accepted (far beyond a search's; the optimizer's sums of
C and its decomposition stay finite)."""


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


def _readable_copy(meta: dict[str, Any], records: list[GenerationRecord]) -> dict[str, Any]:
    """What ``NAME.json`` holds: ``meta`` and the curve as rows (NaN as null)."""
    return {**meta, "records": record_rows(records)}


def save_checkpoint(
    path: str | Path, optimizer: CMA, config: SearchConfig, records: list[GenerationRecord]
) -> tuple[Path, Path]:
    """Write the optimizer's state after a ``tell``, ``config`` and the learning curve
    ``records`` (generations 0 .. the optimizer's) to ``path.npz`` atomically, then its copy
    ``path.json``. Returns both paths; raises OSError."""
    state = _state(optimizer)
    assert state["_B"] is None and state["_D"] is None, "checkpoint only after a tell"
    assert len(records) == int(state["_g"]) + 1, "one record per generation and generation 0"
    npz_path, json_path = save_paths(path)
    meta = {
        "format": CHECKPOINT_FORMAT,
        "version": CHECKPOINT_VERSION,
        "sigma": float(state["_sigma"]),
        "generation": int(state["_g"]),
        "config": config.to_dict(),
    }
    arrays = {name: np.asarray(state[key], dtype=np.float64) for name, key in STATE_ARRAYS.items()}
    arrays["records"] = records_table(records)
    arrays["meta"] = np.frombuffer(json.dumps(meta).encode("utf-8"), dtype=np.uint8)
    write_npz_atomic(npz_path, arrays)
    copy = _readable_copy(meta, records)
    write_atomic(json_path, json.dumps(copy, indent=1).encode("utf-8"))
    return npz_path, json_path


def load_checkpoint(
    path: str | Path, n_parameters: int
) -> tuple[CMA, SearchConfig, list[GenerationRecord]]:
    """(optimizer, saved config, learning curve) of :func:`save_checkpoint` for a policy of
    ``n_parameters`` parameters; CorruptFileError naming the file otherwise (module doc)."""
    npz_path, json_path = save_paths(path)
    with SavedArchive(npz_path) as archive:
        if "meta" not in archive.names:
            raise CorruptFileError(
                f"{npz_path}: not a skidnav CMA-ES checkpoint of version {CHECKPOINT_VERSION}"
            )
        meta = _meta(archive.read("meta", META_SPEC), npz_path)
        config, sigma, generation = _settings(meta, npz_path)
        specs = {name: ArraySpec((n_parameters,), "<f8") for name in STATE_ARRAYS}
        specs["covariance"] = ArraySpec((n_parameters, n_parameters), "<f8")
        specs["records"] = ArraySpec((generation + 1, len(GenerationRecord._fields)), "<f8")
        arrays = archive.read_all({**specs, "meta": META_SPEC})
    try:
        _check_state(arrays)
        records = records_from_table(arrays["records"], config)
    except ValueError as error:
        raise CorruptFileError(f"{npz_path}: cannot resume: {first_line(error)}") from None
    _check_copy(json_path, _readable_copy(meta, records), generation)
    optimizer = new_optimizer(config, n_parameters)
    state = _state(optimizer)
    state.update({STATE_ARRAYS[name]: np.array(arrays[name]) for name in STATE_ARRAYS})
    state.update(_sigma=sigma, _g=generation, _B=None, _D=None)
    return optimizer, config, records


def _meta(data: np.ndarray, where: Path) -> dict[str, Any]:
    """The JSON object of the ``meta`` member, of the format and version of this module."""
    try:
        text = data.tobytes().decode("utf-8")
    except UnicodeDecodeError:
        raise CorruptFileError(f"{where}: array 'meta' is not UTF-8 text") from None
    meta = parse_json(text, f"{where}: array 'meta'")
    if meta.get("format") != CHECKPOINT_FORMAT or meta.get("version") != CHECKPOINT_VERSION:
        raise CorruptFileError(
            f"{where}: not a skidnav CMA-ES checkpoint of version {CHECKPOINT_VERSION}"
        )
    return meta


def _settings(meta: dict[str, Any], where: Path) -> tuple[SearchConfig, float, int]:
    """(config, σ, generation) of ``meta``, each checked; CorruptFileError otherwise."""
    try:
        if not isinstance(meta.get("config"), dict):
            raise ValueError("expected the config to be an object")
        config = SearchConfig.from_mapping(meta["config"])
        sigma = check_number("sigma", meta.get("sigma"), 0.0, MAX_SIGMA)
        generation = meta.get("generation")
        check_integer("generation", generation, 1, MAX_GENERATIONS)
    except (TypeError, ValueError) as error:
        raise CorruptFileError(f"{where}: cannot resume: {first_line(error)}") from None
    assert isinstance(generation, int)
    return config, sigma, generation


def _check_state(arrays: dict[str, np.ndarray]) -> None:
    """ValueError naming the first of the optimizer's arrays with a value out of bounds."""
    bounds = {"mean": MAX_PARAMETER, "path_sigma": MAX_PARAMETER, "path_c": MAX_PARAMETER}
    bounds["covariance"] = MAX_COVARIANCE
    for name, bound in bounds.items():
        check_magnitude(name, arrays[name], bound)


def _check_copy(json_path: Path, expected: dict[str, Any], generation: int) -> None:
    """Refuse a ``NAME.json`` that is neither the copy ``expected`` nor one of an older
    generation (the checkpoint's last write cut short: the ``.npz`` is the checkpoint)."""
    if not json_path.exists():
        return  # the kill came before the first copy was written
    copy = read_json(json_path, max_bytes=MAX_CHECKPOINT_JSON_BYTES, what="checkpoint")
    if copy == expected:
        return
    older = copy.get("generation")
    if isinstance(older, int) and not isinstance(older, bool) and 1 <= older < generation:
        logger.info("%s: of generation %d, the checkpoint of %d", json_path, older, generation)
        return
    raise CorruptFileError(
        f"{json_path}: does not match {json_path.with_suffix('.npz').name}, the checkpoint it "
        "is a copy of (edited by hand?)"
    )
