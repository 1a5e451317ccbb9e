"""One run of a data curve (:class:`~skidnav.studies.kinematic_models.curve_grid.KinematicCurve`):
one drive of one floor and dynamics, the learned model and the prior scored on it after every t
of ``driving_seconds`` (:func:`skidnav.studies.kinematic_models.curve.learning_curve`)."""

from __future__ import annotations

import numpy as np

from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import TrialResult
from skidnav.robot.params import RobotParams
from skidnav.studies.kinematic_models.curve import learning_curve, plateau_seconds
from skidnav.studies.kinematic_models.curve_grid import METRICS, KinematicCurve
from skidnav.studies.kinematic_models.trial import drive_log

COVERAGE_AFTER = 10.0
"""[s] The learned model's coverage is summarised over the t of at least this many seconds."""


def curve_trial(spec: RunSpec[KinematicCurve]) -> TrialResult:
    """The runner's trial function of a curve: the drive of world ``spec.seed`` on floor
    ``spec.preset`` with dynamics ``spec.agent.name``, uniformly random actions, no drift.

    The episode arrays are ``{model}_{metric}`` per t (:data:`METRICS`); the summary holds the
    learned model's plateau time [s] (:func:`plateau_seconds`), its mean coverage over the t ≥
    :data:`COVERAGE_AFTER`, and both models' 1-s error [m] at the longest t."""
    curve = spec.config
    dt = RobotParams().dt
    log = drive_log(spec.seed, curve.samples, spec.preset, 0.0, 1e9, spec.agent.name)
    scores = learning_curve(log, curve.driving_seconds, curve.test_seconds, dt)
    episodes = {
        f"{model}_{metric}": np.array([point[k] for point in points], dtype=float)
        for model, points in scores.items()
        for k, metric in enumerate(METRICS)
    }
    late = np.asarray(curve.driving_seconds) >= COVERAGE_AFTER
    summary = {
        "plateau_seconds": plateau_seconds(curve.driving_seconds, episodes["learned_one_second"]),
        "coverage_late": float(np.mean(episodes["learned_coverage"][late]))
        if late.any()
        else np.nan,
        "learned_one_second_last": float(episodes["learned_one_second"][-1]),
        "prior_one_second_last": float(episodes["prior_one_second"][-1]),
    }
    return TrialResult(spec.run_id, spec.coordinates, episodes, summary, {})
