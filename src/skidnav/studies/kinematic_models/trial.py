"""One run of a kinematic-model comparison: one model on the logged drive of one seed.

Run (model, seed s) of a :class:`~skidnav.studies.kinematic_models.grid.ModelComparison`: drive
the env ``skidnav/SkidSteerNav-v0`` in the world of seed s with uniformly random actions until
``samples`` free sub-steps are logged (``info["kinematic_log"]``, :func:`drive_log`), fit the
model on the first ``train_fraction`` of them in time order and score its predictions of the
later ones from (region, commanded wheel speeds) (:func:`score`): per output the RMSE, the
coverage of the central 90 % predictive interval and its mean width, and the wall time of the
fit.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from statistics import NormalDist
from typing import NamedTuple

import numpy as np

from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import TrialResult
from skidnav.seeding import ARENA_ROLES, child_sequences, seed_int
from skidnav.studies.kinematic_models.grid import OUTPUTS, ModelComparison

LEVEL = 0.90
"""Level of the central predictive interval whose coverage is measured."""
Z_LEVEL = NormalDist().inv_cdf(0.5 + LEVEL / 2.0)
"""Half-width of the central :data:`LEVEL` interval in standard deviations (1.645)."""

Predictor = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
"""(regions (n,), commanded wheels (n, 2)) → (mean, std), each (n, 3)."""


class Score(NamedTuple):
    """One model's held-out score on one seed: per output (v_x, v_y, yaw_rate), shape (3,)."""

    rmse: np.ndarray
    """Root-mean-square error of the mean [m/s, m/s, rad/s]."""
    coverage: np.ndarray
    """Fraction of held-out samples inside the central 90 % interval."""
    width: np.ndarray
    """Mean width of that interval [m/s, m/s, rad/s]."""
    fit_seconds: float
    """Wall time of the fit [s]."""


def comparison_trial(spec: RunSpec[ModelComparison]) -> TrialResult:
    """The runner's trial function of a comparison: model ``spec.agent.name`` on the drive of
    world ``spec.seed``. The episode arrays are the :class:`Score`'s per-output arrays; the
    summary holds each of them per output (``rmse_v_x`` … ``width_yaw_rate``), the fit time
    [s] and the samples fitted and predicted."""
    comparison = spec.config
    log = drive_log(
        spec.seed, comparison.samples, comparison.slip, comparison.drift, comparison.period
    )
    train, test = log[: comparison.n_train], log[comparison.n_train :]
    predictor, seconds = fit_model(spec.agent.name, train, comparison.window)
    result = score(predictor, test, seconds)
    episodes = {"rmse": result.rmse, "coverage": result.coverage, "width": result.width}
    summary: dict[str, float] = {
        f"{metric}_{output}": float(values[k])
        for metric, values in episodes.items()
        for k, output in enumerate(OUTPUTS)
    }
    summary.update(fit_seconds=seconds, train_samples=len(train), test_samples=len(test))
    return TrialResult(spec.run_id, spec.coordinates, episodes, summary, {})


def drive_log(
    seed: int, samples: int, slip: str, drift: float, period: float, dynamics: str = "kinematic"
) -> np.ndarray:
    """The first ``samples`` free sub-steps (rows of ``LOG_COLUMNS``), shape (samples, 6), of
    uniformly random actions in the world of ``seed`` (map and floor as the env's
    ``world_seed``; the env's reset seed and the actions from the ARENA_ROLES "robot" and
    "agent" children). Episodes ending at the goal or the time limit restart without a seed,
    so the slip clock runs on. ``dynamics``: the env's ("kinematic", or "mujoco": the MuJoCo
    robot on that floor)."""
    import gymnasium

    from skidnav.envs.registration import ENV_ID, register_envs

    register_envs()
    env = gymnasium.make(
        ENV_ID, world_seed=seed, slip=slip, drift_amplitude=drift, drift_period=period,
        dynamics=dynamics,
    )  # fmt: skip
    children = child_sequences(seed, ARENA_ROLES)
    actions = np.random.default_rng(children["agent"])
    env.reset(seed=seed_int(children["robot"]))
    parts, n_rows = [], 0
    while n_rows < samples:
        _, _, terminated, truncated, info = env.step(int(actions.integers(4)))
        parts.append(info["kinematic_log"])
        n_rows += len(info["kinematic_log"])
        if terminated or truncated:
            env.reset()
    env.close()
    return np.concatenate(parts)[:samples]


def fit_model(model: str, train: np.ndarray, window: int) -> tuple[Predictor, float]:
    """(predictor, fit time [s]) of ``model`` ("ridge" or "gp") fitted once on the log rows
    ``train`` (n, 6), keeping ``window`` samples per region."""
    from skidnav.models.gp_kinematic import GaussianProcessConfig, GaussianProcessKinematicModel
    from skidnav.models.kinematic import KinematicModel
    from skidnav.models.kinematic_config import KinematicModelConfig
    from skidnav.robot.params import RobotParams
    from skidnav.world.discretization import Discretization

    grid = Discretization()
    fitted: KinematicModel | GaussianProcessKinematicModel
    if model == "ridge":
        fitted = KinematicModel(RobotParams(), grid, KinematicModelConfig(window=window))
        predictor: Predictor = fitted.predict_twist
    else:
        fitted = GaussianProcessKinematicModel(grid.n_regions, GaussianProcessConfig(window=window))
        predictor = fitted.predict
    start = time.perf_counter()
    fitted.feed(train)
    fitted.refit()
    return predictor, time.perf_counter() - start


def score(predictor: Predictor, test: np.ndarray, fit_seconds: float) -> Score:
    """Held-out RMSE, 90 % coverage and width of ``predictor`` on log rows ``test`` (n, 6);
    samples without a finite prediction are left out."""
    mean, std = predictor(test[:, 0].astype(np.int64), test[:, 1:3])
    truth = test[:, 3:6]
    error = np.where(np.isfinite(mean) & np.isfinite(std), truth - mean, np.nan)
    half = Z_LEVEL * std
    return Score(
        rmse=np.sqrt(np.nanmean(error**2, axis=0)),
        coverage=np.nanmean(np.where(np.isnan(error), np.nan, np.abs(error) <= half), axis=0),
        width=np.nanmean(np.where(np.isnan(error), np.nan, 2.0 * half), axis=0),
        fit_seconds=fit_seconds,
    )
