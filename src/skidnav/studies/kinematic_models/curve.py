"""The learned kinematic model's error against seconds of driving (docs/kinematic-model.md).

For each t of ``driving_seconds`` the model (:class:`~skidnav.models.kinematic.KinematicModel`)
is refitted on the first t seconds of a drive's free sub-steps (0.1 s each) and scored on the
following ``test_seconds``; the prior (the nominal robot, the model held before any refit) is
scored on the same samples. Metrics (Baril et al. 2023, "DRIVE", score their learned skid-steer
model the same way, one-step and over a horizon):

1. one-step error: the RMS over the scored sub-steps of the distance [m] between the predicted
   and the observed body displacement over one 0.1-s sub-step (dt · |Δ(v_x, v_y)|);
2. 1-s error: over each run of 10 consecutive scored sub-steps, the predicted and the observed
   twists integrated (explicit Euler, from the same pose) under the same commands, and the
   distance [m] of the two end positions, RMS over the runs. The log holds free sub-steps only,
   so a run may straddle a collision or a reset the log left out: a bound on what the model
   meets, not a sharper test;
3. coverage: the share of the observed (v_x, v_y, yaw_rate), all three outputs counted, inside
   the model's central 95 % predictive interval (mean ± 1.96 σ); NaN for the prior, which has
   no predictive spread.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

LEVEL_Z = 1.959963984540054
"""Half-width of the central 95 % interval in standard deviations."""
HORIZON = 10
"""Sub-steps of the multi-step error (1 s at 0.1 s)."""


class CurvePoint(NamedTuple):
    """One model's score after t seconds of driving."""

    one_step: float
    """RMS one-sub-step displacement error [m]."""
    one_second: float
    """RMS 1-s position error [m]."""
    coverage: float
    """Share of observed outputs inside the 95 % predictive interval (NaN without spread)."""


def euler_positions(twists: np.ndarray, dt: float) -> np.ndarray:
    """End positions (n_runs, 2) [m] of runs of body twists (n_runs, steps, 3) (v_x [m/s],
    v_y [m/s], yaw_rate [rad/s]) integrated by explicit Euler from the origin, heading 0.

    >>> euler_positions(np.array([[[1.0, 0.0, 0.0]] * 10]), 0.1).round(6).tolist()
    [[1.0, 0.0]]
    """
    n_runs, steps, _ = twists.shape
    position, heading = np.zeros((n_runs, 2)), np.zeros(n_runs)
    for step in range(steps):
        v_x, v_y, yaw_rate = twists[:, step, 0], twists[:, step, 1], twists[:, step, 2]
        position[:, 0] += dt * (v_x * np.cos(heading) - v_y * np.sin(heading))
        position[:, 1] += dt * (v_x * np.sin(heading) + v_y * np.cos(heading))
        heading += dt * yaw_rate
    return position


def score_segment(mean: np.ndarray, std: np.ndarray, observed: np.ndarray, dt: float) -> CurvePoint:
    """The metrics of the module docstring of predictions ``mean``, ``std`` (n, 3) against the
    observed twists ``observed`` (n, 3) of consecutive scored sub-steps."""
    error = mean - observed
    one_step = float(np.sqrt(np.mean(dt**2 * (error[:, 0] ** 2 + error[:, 1] ** 2))))
    n_runs = len(observed) // HORIZON
    shape = (n_runs, HORIZON, 3)
    predicted = euler_positions(mean[: n_runs * HORIZON].reshape(shape), dt)
    actual = euler_positions(observed[: n_runs * HORIZON].reshape(shape), dt)
    one_second = float(np.sqrt(np.mean(np.sum((predicted - actual) ** 2, axis=1))))
    if np.all(np.isfinite(std)):
        coverage = float(np.mean(np.abs(error) <= LEVEL_Z * std))
    else:
        coverage = float("nan")
    return CurvePoint(one_step, one_second, coverage)


def learning_curve(
    log: np.ndarray, driving_seconds: tuple[float, ...], test_seconds: float, dt: float
) -> dict[str, list[CurvePoint]]:
    """The curve of the module docstring on one drive: per model ("learned", "prior") one
    :class:`CurvePoint` per t of ``driving_seconds``.

    Args:
        log: the drive's free sub-steps, rows ``[region, ω_L, ω_R, v_x, v_y, yaw_rate]``
            (n, 6), in time order; at least max(t) + ``test_seconds`` of them.
        driving_seconds: the seconds of driving fitted on, each > 0.
        test_seconds: the seconds scored after each. dt: the sub-step [s].
    """
    from skidnav.models.kinematic import KinematicModel
    from skidnav.robot.params import RobotParams
    from skidnav.world.discretization import Discretization

    prior = KinematicModel(RobotParams(), Discretization())
    n_test = round(test_seconds / dt)
    curves: dict[str, list[CurvePoint]] = {"learned": [], "prior": []}
    for seconds in driving_seconds:
        n_fit = round(seconds / dt)
        test = log[n_fit : n_fit + n_test]
        if len(test) < n_test:
            raise ValueError(f"expected {n_fit + n_test} logged sub-steps, got {len(log)}")
        regions, wheels, observed = test[:, 0].astype(np.int64), test[:, 1:3], test[:, 3:6]
        model = KinematicModel(RobotParams(), Discretization())
        model.feed(log[:n_fit])
        model.refit()
        for name, each in (("learned", model), ("prior", prior)):
            mean, std = each.predict_twist(regions, wheels)
            curves[name].append(score_segment(mean, std, observed, dt))
    return curves


PLATEAU_RATIO = 1.25
"""A curve has reached its plateau at the first t whose 1-s error is within this factor of
the error at the longest t (the least the drive shows)."""


def plateau_seconds(driving_seconds: tuple[float, ...], one_second: np.ndarray) -> float:
    """The first t of ``driving_seconds`` [s] from which the 1-s errors ``one_second`` (one per
    t, same order) stay within :data:`PLATEAU_RATIO` of the last one.

    >>> plateau_seconds((1.0, 2.0, 5.0, 10.0), np.array([20.0, 1.1, 1.2, 1.0]))
    2.0
    >>> plateau_seconds((1.0, 2.0, 5.0, 10.0), np.array([20.0, 1.1, 1.3, 1.0]))
    10.0
    """
    within = np.asarray(one_second) <= PLATEAU_RATIO * one_second[-1]
    outside = np.flatnonzero(~within)
    return float(driving_seconds[0 if len(outside) == 0 else outside[-1] + 1])
