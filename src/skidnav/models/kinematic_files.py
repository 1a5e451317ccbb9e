"""Saved files of a :class:`~skidnav.models.kinematic.KinematicModel`: ``<path>.npz`` (its
learned arrays, :meth:`~skidnav.models.kinematic.KinematicModel.state_arrays`) and
``<path>.json`` (config, robot, discretization), each written atomically; never pickle. A model
inside an agent's file is saved by its agent, with the same arrays and the same size check."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

from skidnav.errors import CorruptFileError, first_line
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.files.saved import MAX_ARCHIVE_BYTES, READ_ERRORS, ArraySpec, SavedArchive, read_json
from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_config import KinematicModelConfig
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization

FORMAT_VERSION = 1
"""The version of a model's JSON."""


def model_metadata(model: KinematicModel) -> dict[str, object]:
    """JSON-ready description of ``model``: format version, config, robot and discretization."""
    return {
        "format_version": FORMAT_VERSION,
        "config": asdict(model.config),
        "robot": asdict(model.robot),
        "grid": asdict(model.grid),
    }


def check_model_size(grid: Discretization, config: KinematicModelConfig) -> None:
    """ValueError unless a model of ``grid`` and ``config`` is one a saved file may describe:
    no more slip regions than cells, and its arrays (per region the ``window × 5`` samples, 2
    counts, 8 coefficients, 12 velocities and a count per speed ring, float64 or int64) within
    :data:`~skidnav.files.saved.MAX_ARCHIVE_BYTES`. Checked before a loader allocates one."""
    n_bytes = grid.n_regions * (config.window * 5 + 22 + config.speed_strata) * 8
    if grid.n_regions > grid.n_x * grid.n_y or n_bytes > MAX_ARCHIVE_BYTES:
        raise ValueError(
            f"a kinematic model of {grid.n_regions:,} slip regions on {grid.n_x} × "
            f"{grid.n_y} cells with a window of {config.window:,} samples is too large"
        )


def save_model(model: KinematicModel, path: str | Path) -> tuple[Path, Path]:
    """Write ``<path>.npz`` and ``<path>.json``, each atomically; (their paths)."""
    base = Path(path).with_suffix("")
    npz_path, json_path = base.with_suffix(".npz"), base.with_suffix(".json")
    write_npz_atomic(npz_path, model.state_arrays())
    write_atomic(json_path, json.dumps(model_metadata(model), indent=2).encode())
    return npz_path, json_path


def load_model(path: str | Path) -> KinematicModel:
    """Read a model written by :func:`save_model`; CorruptFileError (one line naming the file)
    when a file is missing, damaged or inconsistent. The JSON is checked (size, nesting, every
    field validated, :func:`check_model_size`) before the model is allocated, the archive's
    member names, dtypes and shapes against that model before any array is read."""
    base = Path(path).with_suffix("")
    meta = read_json(base.with_suffix(".json"), max_bytes=2**20, what="kinematic model file")
    try:
        if meta.get("format_version") != FORMAT_VERSION:
            raise ValueError("unsupported format version")
        grid = Discretization(**_table(meta, "grid"))
        config = KinematicModelConfig(**_table(meta, "config"))
        check_model_size(grid, config)
        model = KinematicModel(RobotParams(**_table(meta, "robot")), grid, config)
        specs = {
            name: ArraySpec(array.shape, array.dtype.str)
            for name, array in model.state_arrays().items()
        }
        with SavedArchive(base.with_suffix(".npz")) as archive:
            model.load_arrays(archive.read_all(specs))
    except (*READ_ERRORS, KeyError, CorruptFileError) as error:
        if isinstance(error, CorruptFileError) and str(error).startswith(f"{base}."):
            raise
        raise CorruptFileError(
            f"{base}: cannot load kinematic model ({first_line(error)})"
        ) from None
    return model


def _table(meta: dict[str, Any], key: str) -> dict[str, Any]:
    """``meta[key]`` if it is a JSON object (TypeError otherwise)."""
    value = meta[key]
    if not isinstance(value, dict):
        raise TypeError(f"expected {key!r} to be a JSON object, got {type(value).__name__}")
    return value
