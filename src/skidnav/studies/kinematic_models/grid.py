"""The config of a kinematic-model comparison: models × seeds, one logged drive per seed.

A config is a TOML file (``configs/kinematic-models.toml``)::

    kind = "kinematic-models"
    name = "kinematic-models"   # the results directory's default name (runs/NAME)
    models = ["ridge", "gp"]
    seeds = 5                   # worlds 0 .. 4
    samples = 20000             # free sub-steps logged per seed
    slip = "slippery"           # slip preset of the floor
    drift = 0.0                 # drift amplitude A (0: stationary)
    # drift_period = 2000.0     # [s]; default: the logged time, samples × 0.1 s
    train_fraction = 0.5        # the first part of the log in time order, fitted on
    window = 500                # samples kept per region, by both models

:class:`ModelComparison` is that config, validated on construction, and the runner's grid
(:class:`~skidnav.experiments.runs.Grid`): its runs are model × seed (agent = model, one map,
preset = the slip preset). Run (model, seed s) drives the world of the integer seed s
(:func:`skidnav.studies.kinematic_models.trial.drive_log`), so both models of a seed fit and
predict the same log, and a seed gives the numbers ``skidnav study kinematic compare`` always
gave for it; the runner's world and run streams (derived from :attr:`ModelComparison.root_seed`,
0) are not drawn from.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from skidnav.checks import check_integer, check_names, check_number
from skidnav.errors import shown
from skidnav.experiments.config import AgentSpec, MapSpec
from skidnav.experiments.store import RunLayout
from skidnav.extras import require
from skidnav.files.configtables import build_dataclass, check_keys, toml_value
from skidnav.files.saved import ArraySpec
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SLIP_PRESETS

KIND = "kinematic-models"
"""The ``kind`` of a comparison config."""
MODELS = ("ridge", "gp")
"""The models compared: Bayesian ridge (:mod:`skidnav.models.kinematic`), Gaussian process
(:mod:`skidnav.models.gp_kinematic`)."""
MODEL_EXTRAS = {"gp": "gp"}
"""The models that need an extra (:mod:`skidnav.extras`; the GP is scikit-learn's) → that
extra."""
OUTPUTS = ("v_x", "v_y", "yaw_rate")
"""The predicted outputs, in the order of the log and of every per-output array."""
MAP_KIND = "obstacles"
"""The map every drive runs on (the env's default)."""
MIN_SAMPLES, MAX_SAMPLES = 100, 1_000_000
MAX_SEEDS = 1000
MIN_WINDOW, MAX_WINDOW = 20, 2000
"""Samples kept per region: at most the GP's ``MAX_WINDOW`` (a 2000 × 2000 kernel matrix)."""
EPISODE_COLUMNS = ("rmse", "coverage", "width")
"""The per-output arrays of a run, shape (3,) in :data:`OUTPUTS` order: held-out RMSE of the
mean [m/s, m/s, rad/s], share of held-out samples inside the central 90 % predictive interval,
mean width of that interval [m/s, m/s, rad/s]. The results' episode table holds them, one row
per output (episode 1, 2, 3 = v_x, v_y, yaw_rate)."""


@dataclass(frozen=True)
class ModelComparison:
    """A comparison (module doc); validated on construction, numbers stored as floats.

    Attributes:
        name: the results directory's default name. models: distinct names of :data:`MODELS`.
        seeds: worlds 0 .. seeds − 1, at most :data:`MAX_SEEDS`.
        samples: free sub-steps logged per seed, in [100, 10⁶].
        slip: slip preset (:data:`skidnav.robot.slip.SLIP_PRESETS`).
        drift: drift amplitude A ≥ 0 of the slip (0: stationary).
        drift_period: drift period [s] > 0; None: the logged time (:attr:`period`).
        train_fraction: the first part of the log (time order) fitted on, in [0.1, 0.9]; the
            rest is predicted.
        window: samples kept per region by both models, in [20, 2000].
    """

    name: str = KIND
    models: tuple[str, ...] = MODELS
    seeds: int = 5
    samples: int = 20_000
    slip: str = "slippery"
    drift: float = 0.0
    drift_period: float | None = None
    train_fraction: float = 0.5
    window: int = 500

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"expected name to be a non-empty string, got {shown(self.name)}")
        check_names("models", self.models, MODELS)
        check_integer("seeds", self.seeds, 1, MAX_SEEDS)
        check_integer("samples", self.samples, MIN_SAMPLES, MAX_SAMPLES)
        if self.slip not in SLIP_PRESETS:
            raise ValueError(
                f"expected slip to be one of {', '.join(SLIP_PRESETS)}, got {shown(self.slip)}"
            )
        numbers = {
            "drift": check_number("drift", self.drift, 0.0, closed=True),
            "train_fraction": check_number(
                "train_fraction", self.train_fraction, 0.1, 0.9, closed=True
            ),
        }
        if self.drift_period is not None:
            numbers["drift_period"] = check_number("drift_period", self.drift_period, 0.0)
        check_integer("window", self.window, MIN_WINDOW, MAX_WINDOW)
        for key, value in numbers.items():
            object.__setattr__(self, key, value)  # 1 and 1.0 are one config

    @property
    def agents(self) -> tuple[AgentSpec, ...]:
        """One per model (label = name)."""
        return tuple(AgentSpec(model, model) for model in self.models)

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The one map kind of every drive."""
        return (MapSpec(MAP_KIND, kind=MAP_KIND),)

    @property
    def presets(self) -> tuple[str, ...]:
        """The slip preset."""
        return (self.slip,)

    @property
    def root_seed(self) -> int:
        """0: run (model, s) drives world s (module doc)."""
        return 0

    @property
    def n_runs(self) -> int:
        """Models × seeds."""
        return len(self.models) * self.seeds

    @property
    def period(self) -> float:
        """The drift period [s]: :attr:`drift_period`, or the logged time."""
        if self.drift_period is not None:
            return self.drift_period
        return self.samples * RobotParams().dt

    @property
    def n_train(self) -> int:
        """Samples of a log fitted on (the first ones)."""
        return int(self.train_fraction * self.samples)

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of :func:`comparison_to_dict`."""
        text = json.dumps(comparison_to_dict(self), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def comparison_to_dict(comparison: ModelComparison) -> dict[str, Any]:
    """The config as a JSON-ready dict (read back by :func:`comparison_from_dict`)."""
    values = dataclasses.asdict(comparison)
    values["models"] = list(comparison.models)
    return values


def comparison_from_dict(values: dict[str, Any]) -> ModelComparison:
    """The config of :func:`comparison_to_dict` (KeyError, TypeError or ValueError if invalid)."""
    return ModelComparison(**{**values, "models": tuple(values["models"])})


def comparison_from_document(document: Mapping[str, Any], path: Path | str) -> ModelComparison:
    """The config of a parsed TOML ``document`` (its ``kind`` aside) read from ``path``.

    Raises:
        UserError: ``path: unknown key …`` or ``path: expected …`` in one line.
    """
    keys = ("kind", *(field.name for field in dataclasses.fields(ModelComparison)))
    check_keys(document, keys, str(path))
    values = {key: value for key, value in document.items() if key != "kind"}
    if isinstance(values.get("models"), list):
        values["models"] = tuple(values["models"])
    return build_dataclass(ModelComparison, values, str(path))


def require_model_extras(comparison: ModelComparison) -> None:
    """Refuse ``comparison`` before anything runs when a model's extra is missing.

    Raises:
        MissingExtraError: one line naming the model and the ``pip install`` that brings it.
    """
    for model in comparison.models:
        if model in MODEL_EXTRAS:
            require(MODEL_EXTRAS[model], f"model {model!r}")


def comparison_toml(comparison: ModelComparison) -> str:
    """The config as the TOML text of a config file (:func:`comparison_from_document` reads it
    back equal); ``drift_period`` left out when it is the logged time."""

    lines = [f"kind = {toml_value(KIND)}"]
    for key, value in comparison_to_dict(comparison).items():
        if value is not None:
            lines.append(f"{key} = {toml_value(value)}")
    return "\n".join(lines) + "\n"


def run_file_specs(comparison: ModelComparison) -> dict[str, ArraySpec]:
    """What a run file holds besides its document: the :data:`EPISODE_COLUMNS`, float64 (3,)."""
    return {f"episode.{key}": ArraySpec((len(OUTPUTS),), "<f8") for key in EPISODE_COLUMNS}


LAYOUT = RunLayout(KIND, EPISODE_COLUMNS, comparison_to_dict, comparison_from_dict, run_file_specs)
"""The results directory of a comparison (:class:`~skidnav.experiments.store.RunLayout`)."""
