"""The config of a data curve of the learned kinematic model: floors × dynamics × seeds, one
random drive per run, the model refitted on its first t seconds for every t of a list.

A config is a TOML file (``configs/kinematic-models-curve.toml``)::

    kind = "kinematic-curve"
    name = "kinematic-curve"          # the results directory's default name (runs/NAME)
    floors = ["thesis", "slippery"]   # slip presets of the floor
    dynamics = ["kinematic"]          # the env's dynamics: "kinematic", "mujoco" (physics extra)
    seeds = 3                         # worlds 0 .. 2
    driving_seconds = [1, 2, 5, 10, 20, 40]   # seconds of driving fitted on, increasing
    test_seconds = 60                 # the seconds scored after each

:class:`KinematicCurve` is that config, validated on construction, and the runner's grid
(:class:`~skidnav.experiments.runs.Grid`): its runs are dynamics × floor × seed (agent = the
dynamics, one map, preset = the floor). Run (dynamics, floor, seed s) drives the world of the
integer seed s (:func:`skidnav.studies.kinematic_models.trial.drive_log`) for max(t) +
``test_seconds`` seconds and scores the learned model and the prior on it
(:func:`skidnav.studies.kinematic_models.curve.learning_curve`); the runner's world and run
streams (root seed 0) are not drawn from.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path
from typing import Any

from skidnav.checks import check_integer, check_names, check_number
from skidnav.errors import shown
from skidnav.experiments.config import AgentSpec, MapSpec
from skidnav.experiments.store import RunLayout
from skidnav.extras import require
from skidnav.files.configtables import build_dataclass, check_keys
from skidnav.files.saved import ArraySpec
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SLIP_PRESETS

KIND = "kinematic-curve"
"""The ``kind`` of a curve config."""
DYNAMICS = ("kinematic", "mujoco")
"""The env's dynamics a drive may run on (``mujoco``: the physics extra)."""
MODELS = ("learned", "prior")
"""The models scored on every drive: refitted on the first t seconds, and held at the prior."""
METRICS = ("one_step", "one_second", "coverage")
"""The scores of :class:`~skidnav.studies.kinematic_models.curve.CurvePoint`, in its order."""
MAP_KIND = "obstacles"
"""The map every drive runs on (the env's default)."""
MAX_SEEDS, MAX_SECONDS = 1000, 3600.0
"""At most 1000 seeds and an hour of driving per run (fitted and scored together)."""
EPISODE_COLUMNS = tuple(f"{model}_{metric}" for model in MODELS for metric in METRICS)
"""The per-``t`` arrays of a run, shape (len(driving_seconds),): per model the RMS one-sub-step
error [m], the RMS 1-s error [m] and the 95 % coverage (NaN for the prior, which has no
spread). The results' episode table holds them, one row per t (episode k = the k-th t)."""


@dataclass(frozen=True)
class KinematicCurve:
    """A curve config (module doc); validated on construction, seconds stored as floats.

    Attributes:
        name: the results directory's default name.
        floors: distinct slip presets (:data:`skidnav.robot.slip.SLIP_PRESETS`).
        dynamics: distinct names of :data:`DYNAMICS`.
        seeds: worlds 0 .. seeds − 1, at most :data:`MAX_SEEDS`.
        driving_seconds: increasing seconds of driving fitted on [s], each > 0.
        test_seconds: seconds scored after each [s], at least 1 (ten 1-s runs).
    """

    name: str = KIND
    floors: tuple[str, ...] = ("thesis", "slippery", "rough-physics", "slippery-physics")
    dynamics: tuple[str, ...] = ("kinematic",)
    seeds: int = 3
    driving_seconds: tuple[float, ...] = (1.0, 2.0, 5.0, 10.0, 20.0, 40.0)
    test_seconds: float = 60.0

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"expected name to be a non-empty string, got {shown(self.name)}")
        check_names("floors", self.floors, tuple(SLIP_PRESETS))
        check_names("dynamics", self.dynamics, DYNAMICS)
        check_integer("seeds", self.seeds, 1, MAX_SEEDS)
        seconds = self.driving_seconds
        if not (isinstance(seconds, tuple) and seconds):
            raise ValueError(
                f"expected driving_seconds to be a non-empty list, got {shown(seconds)}"
            )
        numbers = tuple(
            check_number("driving_seconds", value, 0.0, MAX_SECONDS) for value in seconds
        )
        if any(later <= earlier for earlier, later in pairwise(numbers)):
            raise ValueError(f"expected driving_seconds to increase, got {list(numbers)}")
        test = check_number("test_seconds", self.test_seconds, 1.0, MAX_SECONDS, closed=True)
        if numbers[-1] + test > MAX_SECONDS:
            raise ValueError(
                f"expected at most {MAX_SECONDS:g} s of driving per run, got "
                f"{numbers[-1] + test:g} (the last of driving_seconds + test_seconds)"
            )
        object.__setattr__(self, "driving_seconds", numbers)  # 1 and 1.0 are one config
        object.__setattr__(self, "test_seconds", test)

    @property
    def agents(self) -> tuple[AgentSpec, ...]:
        """One per dynamics (label = name)."""
        return tuple(AgentSpec(dynamics, dynamics) for dynamics in self.dynamics)

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The one map kind of every drive."""
        return (MapSpec(MAP_KIND, kind=MAP_KIND),)

    @property
    def presets(self) -> tuple[str, ...]:
        """The floors."""
        return self.floors

    @property
    def root_seed(self) -> int:
        """0: run (dynamics, floor, s) drives world s (module doc)."""
        return 0

    @property
    def n_runs(self) -> int:
        """Dynamics × floors × seeds."""
        return len(self.dynamics) * len(self.floors) * self.seeds

    @property
    def samples(self) -> int:
        """Sub-steps logged per drive: the last of the driving seconds and the test seconds."""
        return round((self.driving_seconds[-1] + self.test_seconds) / RobotParams().dt)

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of :func:`curve_to_dict`."""
        text = json.dumps(curve_to_dict(self), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def curve_to_dict(curve: KinematicCurve) -> dict[str, Any]:
    """The config as a JSON-ready dict (read back by :func:`curve_from_dict`)."""
    values = dataclasses.asdict(curve)
    for key in ("floors", "dynamics", "driving_seconds"):
        values[key] = list(values[key])
    return values


def curve_from_dict(values: dict[str, Any]) -> KinematicCurve:
    """The config of :func:`curve_to_dict` (KeyError, TypeError or ValueError if invalid)."""
    return KinematicCurve(**_tuples(values))


def _tuples(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` with its lists as tuples (the config's sequences)."""
    return {
        key: tuple(value) if isinstance(value, list) else value for key, value in values.items()
    }


def curve_from_document(document: Mapping[str, Any], path: Path | str) -> KinematicCurve:
    """The config of a parsed TOML ``document`` (its ``kind`` aside) read from ``path``.

    Raises:
        UserError: ``path: unknown key …`` or ``path: expected …`` in one line.
    """
    keys = ("kind", *(field.name for field in dataclasses.fields(KinematicCurve)))
    check_keys(document, keys, str(path))
    values = _tuples({key: value for key, value in document.items() if key != "kind"})
    return build_dataclass(KinematicCurve, values, str(path))


def require_dynamics_extras(curve: KinematicCurve) -> None:
    """Refuse ``curve`` before anything runs when it drives the MuJoCo robot without the
    physics extra.

    Raises:
        MissingExtraError: one line naming the dynamics and the ``pip install`` that brings it.
    """
    if "mujoco" in curve.dynamics:
        require("physics", "dynamics 'mujoco'")


def run_file_specs(curve: KinematicCurve) -> dict[str, ArraySpec]:
    """What a run file holds besides its document: the :data:`EPISODE_COLUMNS`, float64, one
    value per t of ``driving_seconds``."""
    shape = (len(curve.driving_seconds),)
    return {f"episode.{key}": ArraySpec(shape, "<f8") for key in EPISODE_COLUMNS}


LAYOUT = RunLayout(KIND, EPISODE_COLUMNS, curve_to_dict, curve_from_dict, run_file_specs)
"""The results directory of a curve (:class:`~skidnav.experiments.store.RunLayout`)."""
